"""Compose the stages into a timeline, and decide what to skip.

Two steps, so the editor can re-threshold without decoding again:

1. :func:`analyse` (slow, decodes): the audio pass computes the four psychoacoustic features
   per 20 ms frame; the video pass (after it, because skipping needs the audio intensity)
   computes per tick what the modes need. The result, an :class:`Analysis`, is the feature cache.
2. :func:`derive` (fast, pure): thresholds, normaliser, mode and mappings -> :class:`Timeline`.

:func:`generate` does both.
"""

from __future__ import annotations

import dataclasses
import hashlib
import io
import json
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from autohaptics import __version__
from autohaptics import airflow, cuts, depth, fusion, saliency, thermal
from autohaptics.intensity import features as af
from autohaptics import intensity as inten
from autohaptics import media
from autohaptics.heap import release_free_memory, release_library_pages
from autohaptics.errors import MediaError, ParameterError
from autohaptics.layout import ACTUATOR_IDS, AUDIO_MODE_ACTUATORS, CENTRE_ACTUATOR, N_ACTUATORS, TEMP_NEUTRAL_C
from autohaptics.presets import DEFAULT_PRESET, apply_overrides, params_to_dict, preset_overrides
from autohaptics.progress import CancelToken, ProgressFn, check_cancel, null_progress
from autohaptics.timebase import FRAMES_PER_TICK, TICK_S, frames_to_ticks, n_ticks as ticks_for
from autohaptics.timeline import Timeline, default_generator
from autohaptics.vision import VideoAnalysis, VideoParams, video_pass

MODES = ("multimodal", "audio", "visual", "random")
TRACKS = ("vibration", "temperature", "fans")
# A tick that vibrates but had no saliency computed borrows the weights of the nearest analysed
# tick of the same shot within this many ticks; beyond, it falls back to A5.
_BORROW_TICKS = 10
_AUDIO_SHARE = 0.15  # share of the progress bar given to the audio pass when there is video


@dataclass(frozen=True)
class GenerateParams:
    """Every parameter that shapes a timeline (recorded in ``generator.params``).

    mode : vibration rendering, the thesis's study conditions (table 4.1): "multimodal" (audio
        intensity spread by saliency fusion, the full pipeline), "audio" (A1, A2, A5 from the audio
        intensity), "visual" (the salient area's actuators, no audio), "random" (seeded random events).
    tracks : which tracks to compute; a track left out is still present, off (zeros / neutral).
    seed : random generator seed of the "random" mode.
    lfe_gain_db : gain of the LFE channel in the downmix, dB (cinema playback: +10).
    allow_truncated : accept a file whose streams decode shorter than declared (the missing part
        is silence); otherwise such a file is an error.
    """

    mode: str = "multimodal"
    tracks: tuple[str, ...] = TRACKS
    seed: int = 0
    lfe_gain_db: float = 10.0
    allow_truncated: bool = False
    audio: af.AudioFeatureParams = field(default_factory=af.AudioFeatureParams)
    intensity: inten.IntensityParams = field(default_factory=inten.IntensityParams)
    video: VideoParams = field(default_factory=VideoParams)
    saliency: saliency.SaliencyParams = field(default_factory=saliency.SaliencyParams)
    fusion: fusion.FusionParams = field(default_factory=fusion.FusionParams)
    thermal: thermal.ThermalParams = field(default_factory=thermal.ThermalParams)
    flow: airflow.FlowParams = field(default_factory=airflow.FlowParams)
    airflow: airflow.AirflowParams = field(default_factory=airflow.AirflowParams)
    cuts: cuts.CutParams = field(default_factory=cuts.CutParams)
    depth: depth.DepthParams = field(default_factory=depth.DepthParams)

    def __post_init__(self):
        if self.mode not in MODES:
            raise ParameterError(f"mode must be one of {MODES}, got {self.mode!r}")
        bad = [t for t in self.tracks if t not in TRACKS]
        if bad:
            raise ParameterError(f"unknown track(s) {bad}; choose from {list(TRACKS)}")
        if not (-40.0 <= float(self.lfe_gain_db) <= 20.0):
            raise ParameterError(f"lfe_gain_db must lie in -40..20 dB, got {self.lfe_gain_db!r}")


def resolve_params(preset: str = DEFAULT_PRESET, overrides: dict[str, Any] | None = None,
                   thresholds: dict[str, Any] | None = None) -> tuple[GenerateParams, str]:
    """Build :class:`GenerateParams` from a preset, dotted overrides and threshold overrides."""
    params = apply_overrides(GenerateParams(), preset_overrides(preset))
    params = apply_overrides(params, overrides or {})
    if thresholds:
        th = dict(params.intensity.thresholds)
        for name, value in thresholds.items():
            if name not in inten.FEATURES:
                raise ParameterError(f"unknown threshold {name!r}; expected one of {list(inten.FEATURES)}")
            try:
                th[name] = float(value)
            except (TypeError, ValueError):
                raise ParameterError(f"threshold {name} must be a number, got {value!r}") from None
        params = dataclasses.replace(params, intensity=dataclasses.replace(params.intensity, thresholds=th))
    return params, preset


# ---------------------------------------------------------------------- analysis
@dataclass
class Analysis:
    """The feature cache of one file: what :func:`derive` needs, nothing that depends on thresholds.

    audio : {"loudness" sone, "sharpness" acum, "booming" 1, "low_energy" Pa^2}, each float64
        [shape=(n_frames,)] on the 20 ms grid, n_frames = n_ticks * 5; None without an audio stream.
    """

    info: dict
    sha256: str
    n_ticks: int
    params: dict
    audio: dict[str, np.ndarray] | None
    video: VideoAnalysis | None = None
    stats: dict = field(default_factory=dict)

    def save(self, path: str | Path) -> None:
        """Write the cache as one .npz file (arrays plus a JSON header)."""
        arrays = {f"audio_{k}": v for k, v in (self.audio or {}).items()}
        if self.video is not None:
            arrays.update({f"video_{k}": v for k, v in self.video.arrays().items()})
        header = {"info": self.info, "sha256": self.sha256, "n_ticks": self.n_ticks, "params": self.params,
                  "stats": self.stats, "has_audio": self.audio is not None, "has_video": self.video is not None,
                  "version": __version__}
        buf = io.BytesIO()
        np.savez(buf, header=np.frombuffer(json.dumps(header).encode(), dtype=np.uint8), **arrays)
        Path(path).write_bytes(buf.getvalue())

    @classmethod
    def load(cls, path: str | Path) -> "Analysis":
        with np.load(path, allow_pickle=False) as z:
            header = json.loads(bytes(z["header"]).decode())
            audio = {k[len("audio_"):]: z[k] for k in z.files if k.startswith("audio_")}
            video = {k[len("video_"):]: z[k] for k in z.files if k.startswith("video_")}
        return cls(info=header["info"], sha256=header["sha256"], n_ticks=int(header["n_ticks"]),
                   params=header["params"], audio=audio if header["has_audio"] else None,
                   video=VideoAnalysis.from_arrays(video) if header.get("has_video") else None,
                   stats=header["stats"])


# Fields of GenerateParams that change what analyse() computes; everything else is derive-time.
ANALYSIS_FIELDS = ("audio", "lfe_gain_db", "allow_truncated", "tracks", "video", "saliency", "fusion", "flow",
                   "cuts", "depth")


# ... and the fields of derive-time groups that the video pass reads too (its static, fade and
# depth-skip checks); the rest of ``airflow`` (thresholds, the fan rule) is derive-time
ANALYSIS_SUBFIELDS = {"airflow": ("floor", "static_level", "static_fraction", "flat_std", "fade_min_step")}


def _analysis_part(d: dict) -> dict:
    key = {k: d.get(k) for k in ANALYSIS_FIELDS}
    for group, names in ANALYSIS_SUBFIELDS.items():
        sub = d.get(group) or {}
        key.update({f"{group}.{name}": sub.get(name) for name in names})
    return key


def analysis_key(params: GenerateParams) -> dict:
    """The part of ``params`` an :class:`Analysis` depends on (compare to reuse a cache)."""
    return _analysis_part(params_to_dict(params))


def analysis_compatible(analysis: "Analysis", params: GenerateParams) -> bool:
    """True when ``analysis`` was computed with the same analysis parameters as ``params``."""
    return _analysis_part(analysis.params) == analysis_key(params)


def file_sha256(path: str | Path, *, chunk: int = 1 << 20) -> str:
    """SHA-256 of a file, read in 1 MiB chunks."""
    h = hashlib.sha256()
    with open(path, "rb") as fh:
        while True:
            b = fh.read(chunk)
            if not b:
                break
            h.update(b)
    return h.hexdigest()


def analyse(path: str | Path, params: GenerateParams | None = None, *, progress: ProgressFn | None = None,
            cancel: CancelToken | None = None, info: media.MediaInfo | None = None) -> Analysis:
    """Decode ``path`` once per stream and compute the feature cache.

    Raises MediaError for unusable input (missing, not media, truncated, no audio in audio mode).
    """
    params = params or GenerateParams()
    progress = progress or null_progress
    info = info or media.probe(path)
    n = ticks_for(info.duration_s)
    stats: dict[str, Any] = {}
    t0 = time.perf_counter()
    sha = file_sha256(path)
    stats["hash"] = {"seconds": time.perf_counter() - t0}
    check_cancel(cancel)

    need_colour = "temperature" in params.tracks and info.video is not None
    need_flow = "fans" in params.tracks and info.video is not None
    need_vib = "vibration" in params.tracks
    audio = None
    audio_share = _AUDIO_SHARE if info.video is not None else 1.0
    if info.audio is None:
        if params.mode == "audio" and need_vib:
            raise MediaError(f"{info.path}: no audio stream (mode 'audio' needs one)")
        stats["audio"] = {"skipped": "no audio stream"}
    else:
        audio = _audio_pass(info, params, n, stats, progress, cancel, share=audio_share)
        release_free_memory()  # the decoder's and the feature chunks' freed heap, before the video pass
        release_library_pages()  # e.g. LLVM's code, which ran only to load the compiled kernels

    video = None
    need_saliency = _saliency_needed(params, audio, n) if (need_vib and info.video is not None) else np.zeros(n, bool)
    if info.video is None:
        if params.mode == "visual" and need_vib:
            raise MediaError(f"{info.path}: no video stream (mode 'visual' needs one)")
        stats["video"] = {"skipped": "no video stream"}
    elif need_colour or need_flow or need_saliency.any():
        t0 = time.perf_counter()

        def video_progress(stage: str, fraction: float) -> None:
            progress(stage, audio_share + (1.0 - audio_share) * fraction)

        video = video_pass(info, n, video=params.video, saliency_params=params.saliency,
                           fusion_params=params.fusion, flow_params=params.flow, airflow_params=params.airflow,
                           cut_params=params.cuts, depth_params=params.depth, need_saliency=need_saliency,
                           need_flow=need_flow, need_colour=need_colour, progress=video_progress, cancel=cancel)
        stats["video"] = {"seconds": time.perf_counter() - t0, **video.stats}
        release_free_memory()
        release_library_pages()
    else:
        stats["video"] = {"skipped": "no track needs the picture"}
    if not params.allow_truncated:
        _check_truncation(info, audio_end=stats["audio"].get("decoded_s") if audio is not None else None,
                          video_end=(video.stats["frames"]["last_time_s"] + 1.0 / max(info.video.fps, 1.0))
                          if video is not None else None)
    progress("done", 1.0)
    return Analysis(info=info.to_dict(), sha256=sha, n_ticks=n, params=params_to_dict(params),
                    audio=audio, video=video, stats=stats)


def _check_truncation(info: media.MediaInfo, *, audio_end: float | None, video_end: float | None) -> None:
    """MediaError when the decoded streams end clearly before the file says they should.

    A file cut short ends every stream early; a film whose audio simply outlasts its picture (or
    the reverse) is not truncated: the LATEST decoded end is compared with the container's
    duration. A stream decoded alone is compared with its own declared duration when the
    container gives one (else with the container's, when it is the only stream).
    """
    ends = {name: end for name, end in (("audio", audio_end), ("video", video_end)) if end is not None}
    if not ends:
        return
    if len(ends) == 2 or (info.audio is None) != (info.video is None):
        name = max(ends, key=ends.get)
        media.check_truncation(info, ends[name], name if len(ends) == 1 else "audio and video")
        return
    (name, end), = ends.items()
    declared = getattr(info, name).duration_s
    if declared:
        media.check_truncation(dataclasses.replace(info, duration_s=declared), end, name)


def _saliency_needed(params: GenerateParams, audio: dict | None, n: int) -> np.ndarray:
    """Ticks whose saliency the mode needs: every tick for "visual" (and for "multimodal" without
    skipping), the ticks with non-zero audio intensity for "multimodal", none otherwise."""
    if params.mode == "visual" or (params.mode == "multimodal" and not params.video.skip):
        return np.ones(n, bool)
    if params.mode != "multimodal" or audio is None:
        return np.zeros(n, bool)
    norm = inten.normalise_features(audio, params=params.intensity)
    return inten.tick_intensity(norm, n, params=params.intensity) > 0


def _audio_pass(info: media.MediaInfo, params: GenerateParams, n: int, stats: dict,
                progress: ProgressFn, cancel: CancelToken | None, *, share: float) -> dict[str, np.ndarray]:
    t0 = time.perf_counter()
    report = media.AudioReport()
    duration = info.duration_s

    def chunk_progress(seconds_done: float) -> None:
        check_cancel(cancel)
        progress("audio", share * min(1.0, seconds_done / duration))

    chunks = media.iter_audio(info.path, info=info, lfe_gain_db=params.lfe_gain_db, report=report)
    feats = af.compute_audio_features(chunks, params=params.audio, progress=chunk_progress, cancel=cancel)
    n_frames = n * FRAMES_PER_TICK
    out = {}
    for name in inten.FEATURES:
        x = np.asarray(getattr(feats, name), dtype=np.float64)
        x = np.where(np.isfinite(x), np.maximum(x, 0.0), 0.0)
        if x.size < n_frames:
            x = np.concatenate([x, np.zeros(n_frames - x.size)])
        out[name] = x[:n_frames]
    stats["audio"] = {
        "seconds": time.perf_counter() - t0, "frames": int(n_frames), "decoded_s": round(report.duration_s, 4),
        "nonfinite_samples_repaired": report.nonfinite_samples, "decode_errors": report.decode_errors,
        "downmix": {"main_channels": report.main_channels, "lfe_channel": report.lfe_channel,
                    "lfe_gain_db": params.lfe_gain_db},
    }
    return out


# ------------------------------------------------------------------------ derive
def derive(analysis: Analysis, params: GenerateParams | None = None, *, preset: str = DEFAULT_PRESET) -> Timeline:
    """Turn a feature cache into a timeline (no decoding; milliseconds for a feature film)."""
    params = params or GenerateParams()
    t0 = time.perf_counter()
    n = analysis.n_ticks
    info = analysis.info
    tl = Timeline.empty(n, source=_source_block(info, analysis.sha256))
    stats = json.loads(json.dumps(analysis.stats))

    # Audio -> per-tick intensity (0 everywhere without an audio stream).
    if analysis.audio is not None:
        norm = inten.normalise_features(analysis.audio, params=params.intensity)
        intensity = inten.tick_intensity(norm, n, params=params.intensity)
        for name in inten.FEATURES:
            tl.features[name] = frames_to_ticks(norm[name], n)
    else:
        intensity = np.zeros(n)
        for name in inten.FEATURES:
            tl.features[name] = np.zeros(n)
    tl.features["intensity"] = intensity

    video = analysis.video
    if "vibration" in params.tracks:
        tl.vibration[:] = _vibration(params, intensity, video, n, stats)
    temp_low, temp_high = float(params.thermal.temp_low), float(params.thermal.temp_high)
    neutral = float(np.clip(TEMP_NEUTRAL_C, temp_low, temp_high))
    tl.temperature_c[:] = neutral
    if "temperature" in params.tracks and video is not None:
        target = thermal.temperature_target(video.mean_rgb.astype(np.float64), params=params.thermal)
        if params.thermal.slew_c_per_s:
            target = thermal.slew_limit(target, max_rate_c_per_s=params.thermal.slew_c_per_s, tick_s=TICK_S)
        tl.temperature_c[:] = np.clip(target, temp_low, temp_high)
    if video is not None:
        peak = float(video.motion.max()) if video.motion.size else 0.0
        tl.features["motion"] = np.clip(video.motion / peak, 0.0, 1.0) if peak > 0 else np.zeros(n)
        tl.features["motion_fw_per_s"] = video.motion.astype(np.float64)
        if "fans" in params.tracks:
            _fans(params, video, stats, out=tl.fans)

    gen_params = params_to_dict(params)
    gen_params["thresholds"] = dict(params.intensity.thresholds)
    gen_params["temp_low"], gen_params["temp_high"] = temp_low, temp_high
    tl.generator = default_generator(mode=params.mode, preset=preset, params=gen_params)
    stats["derive"] = {"seconds": time.perf_counter() - t0}
    stats["vibration"] = {"active_ticks": int((tl.vibration.max(axis=1) > 0).sum()), "ticks": n}
    tl.stats = stats
    return tl.validate()


def _vibration(params: GenerateParams, intensity: np.ndarray, video: VideoAnalysis | None, n: int,
               stats: dict) -> np.ndarray:
    """(n, 9) vibration for the mode (thesis table 4.1)."""
    vib = np.zeros((n, N_ACTUATORS))
    centre = ACTUATOR_IDS.index(CENTRE_ACTUATOR)
    if params.mode == "audio":
        vib[:, [ACTUATOR_IDS.index(a) for a in AUDIO_MODE_ACTUATORS]] = intensity[:, None]
    elif params.mode == "multimodal":
        if video is None:  # no picture: the no-salient-region rule puts everything on A5
            vib[:, centre] = intensity
            stats["fusion"] = {"fallback": "no video stream: all weight on A5"}
        else:
            beta, estimated = _beta_for(video, intensity > 0)
            vib = intensity[:, None] * beta
            stats["fusion"] = {"ticks_estimated": int(estimated.sum())}
            if estimated.any():
                stats["needs_analysis"] = True
    elif params.mode == "visual":
        if video is not None:
            salient = video.saliency_mask & (video.beta.sum(axis=1) > 0)
            vib[salient] = video.beta[salient]
    elif params.mode == "random":
        vib = _random_vibration(n, params.seed, float((intensity > 0).mean()) if intensity.any() else 0.2)
    return np.clip(vib, 0.0, 1.0)


def _beta_for(video: VideoAnalysis, wanted: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Actuator weights per tick: the computed ones, else those of the nearest analysed tick of the
    same shot (within ``_BORROW_TICKS``), else A5 only. Returns (beta (n, 9), estimated (n,) bool)."""
    n = wanted.size
    beta = np.array(video.beta, dtype=np.float64)
    have = video.saliency_mask.copy()
    missing = wanted & ~have
    estimated = np.zeros(n, bool)
    fallback = np.zeros(N_ACTUATORS)
    fallback[ACTUATOR_IDS.index(CENTRE_ACTUATOR)] = 1.0
    if missing.any():
        shot = np.cumsum(video.cut)
        have_idx = np.flatnonzero(have)
        for k in np.flatnonzero(missing):
            estimated[k] = True
            if have_idx.size:
                j = have_idx[np.argmin(np.abs(have_idx - k))]
                if abs(j - k) <= _BORROW_TICKS and shot[j] == shot[k]:
                    beta[k] = beta[j]
                    continue
            beta[k] = fallback
    beta[~(have | missing)] = 0.0
    return beta, estimated


def _random_vibration(n: int, seed: int, active_fraction: float) -> np.ndarray:
    """The thesis's "random" condition: events at random times on random actuators, covering about
    ``active_fraction`` of the ticks. Events last 0.3..1.5 s with intensity 0.4..1 on 1..3 actuators."""
    rng = np.random.default_rng(seed)
    vib = np.zeros((n, N_ACTUATORS))
    target = int(round(np.clip(active_fraction, 0.0, 1.0) * n))
    active = np.zeros(n, bool)
    guard = 0
    while active.sum() < target and guard < 10 * n + 10:
        guard += 1
        length = int(rng.integers(3, 16))
        start = int(rng.integers(0, n))
        stop = min(n, start + length)
        acts = rng.choice(N_ACTUATORS, size=int(rng.integers(1, 4)), replace=False)
        vib[start:stop, acts] = np.maximum(vib[start:stop, acts], rng.uniform(0.4, 1.0))
        active[start:stop] = True
    return vib


def sustained_motion(motion: np.ndarray) -> np.ndarray:
    """The motion a tick shares with a neighbour: min(m[k], max(m[k-1], m[k+1])), frame widths/s.

    A one-tick spike (an object popping in or a flash between a frame and its successor: optical
    flow reads nonsense there, and 100 ms of wind cannot be felt anyway) falls to its neighbours'
    level; motion that lasts two ticks or more keeps its value. Outside the clip counts as still.
    """
    m = np.asarray(motion, dtype=np.float64)
    if m.size == 0:
        return m.copy()
    left = np.concatenate([[0.0], m[:-1]])
    right = np.concatenate([m[1:], [0.0]])
    return np.minimum(m, np.maximum(left, right))


_FAN_CHUNK = 2048  # ticks smoothed at a time (bounded memory on a 2-hour film)


def _fans(params: GenerateParams, video: VideoAnalysis, stats: dict, *, out: np.ndarray | None = None) -> np.ndarray:
    """(n, 9, 17) fan levels: ticks whose sustained motion exceeds the (manual or adaptive)
    threshold, not at a cut, with depth computed: strong motion AND near (airflow.fan_levels), the
    cell motion smoothed over the shot's neighbouring ticks and cells (airflow.smoothed_cell_motion).
    ``out``: an all-zero float32 array of that shape to write into (the timeline's own track)."""
    n = video.motion.size
    valid = ~video.cut
    motion = sustained_motion(np.where(valid, video.motion, 0.0))
    threshold = airflow.motion_threshold(motion[valid], params=params.airflow)
    on = valid & (motion > threshold) & video.depth_mask
    fans = np.zeros((n,) + video.cell_motion.shape[1:], np.float32) if out is None else out
    ticks = np.flatnonzero(on)
    shot = np.where(valid, np.cumsum(video.cut), -1)
    for start in range(0, ticks.size, _FAN_CHUNK):
        part = ticks[start:start + _FAN_CHUNK]
        cells = airflow.smoothed_cell_motion(video.cell_motion, shot, part, params=params.airflow)
        for k, c in zip(part, cells):
            fans[k] = airflow.fan_levels(c, video.nearness[k].astype(np.float32), params=params.airflow)
    stats["airflow"] = {"threshold_fw_per_s": float(threshold), "ticks_on": int(on.sum()),
                        "ticks_at_cuts": int(video.cut.sum()),
                        "spikes_ignored": int(((video.motion > threshold) & valid & ~(motion > threshold)).sum())}
    return fans


def generate(path: str | Path, params: GenerateParams | None = None, *, preset: str = DEFAULT_PRESET,
             progress: ProgressFn | None = None, cancel: CancelToken | None = None) -> Timeline:
    """Analyse a media file and derive its timeline (the whole pipeline)."""
    params = params or GenerateParams()
    t0 = time.perf_counter()
    analysis = analyse(path, params, progress=progress, cancel=cancel)
    tl = derive(analysis, params, preset=preset)
    tl.stats["total_seconds"] = time.perf_counter() - t0
    return tl


def _source_block(info: dict, sha256: str) -> dict:
    v, a = info.get("video"), info.get("audio")
    return {
        "name": Path(info["path"]).name, "sha256": sha256, "duration_s": round(info["duration_s"], 6),
        "size_bytes": info.get("size_bytes"), "container": info.get("container"),
        "video": None if v is None else {"width": v["width"], "height": v["height"], "fps": round(v["fps"], 6),
                                          "codec": v["codec"], "rotation": v.get("rotation", 0)},
        "audio": None if a is None else {"sample_rate": a["sample_rate"], "channels": a["channels"],
                                          "layout": a["layout"], "codec": a["codec"]},
    }
