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
import math
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from autohaptics import __version__
from autohaptics import audio_features as af
from autohaptics import intensity as inten
from autohaptics import media
from autohaptics.errors import MediaError, ParameterError
from autohaptics.layout import ACTUATOR_IDS, AUDIO_MODE_ACTUATORS, FAN_COLS, FAN_ROWS, N_ACTUATORS, TEMP_NEUTRAL_C
from autohaptics.presets import DEFAULT_PRESET, apply_overrides, params_to_dict, preset_overrides
from autohaptics.progress import CancelToken, ProgressFn, check_cancel, null_progress
from autohaptics.timebase import FRAMES_PER_TICK, SAMPLES_PER_FRAME, frames_to_ticks, n_ticks as ticks_for
from autohaptics.timeline import Timeline, default_generator

MODES = ("audio",)
TRACKS = ("vibration", "temperature", "fans")
_AUDIO_SHARE = 0.15  # share of the progress bar given to the audio pass when there is video


@dataclass(frozen=True)
class GenerateParams:
    """Every parameter that shapes a timeline (recorded in ``generator.params``).

    mode : vibration rendering, the thesis's study conditions: "audio" (A1, A2, A5 from the audio
        intensity).
    lfe_gain_db : gain of the LFE channel in the downmix, dB (cinema playback: +10).
    allow_truncated : accept a file whose streams decode shorter than declared (the missing part
        is silence); otherwise such a file is an error.
    """

    mode: str = "audio"
    lfe_gain_db: float = 10.0
    allow_truncated: bool = False
    audio: af.AudioFeatureParams = field(default_factory=af.AudioFeatureParams)
    intensity: inten.IntensityParams = field(default_factory=inten.IntensityParams)

    def __post_init__(self):
        if self.mode not in MODES:
            raise ParameterError(f"mode must be one of {MODES}, got {self.mode!r}")
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
    stats: dict = field(default_factory=dict)

    def save(self, path: str | Path) -> None:
        """Write the cache as one .npz file (arrays plus a JSON header)."""
        arrays = {f"audio_{k}": v for k, v in (self.audio or {}).items()}
        header = {"info": self.info, "sha256": self.sha256, "n_ticks": self.n_ticks, "params": self.params,
                  "stats": self.stats, "has_audio": self.audio is not None, "version": __version__}
        buf = io.BytesIO()
        np.savez(buf, header=np.frombuffer(json.dumps(header).encode(), dtype=np.uint8), **arrays)
        Path(path).write_bytes(buf.getvalue())

    @classmethod
    def load(cls, path: str | Path) -> "Analysis":
        with np.load(path, allow_pickle=False) as z:
            header = json.loads(bytes(z["header"]).decode())
            audio = {k[len("audio_"):]: z[k] for k in z.files if k.startswith("audio_")}
        return cls(info=header["info"], sha256=header["sha256"], n_ticks=int(header["n_ticks"]),
                   params=header["params"], audio=audio if header["has_audio"] else None, stats=header["stats"])


# Fields of GenerateParams that change what analyse() computes; everything else is derive-time.
ANALYSIS_FIELDS = ("audio", "lfe_gain_db", "allow_truncated")


def analysis_key(params: GenerateParams) -> dict:
    """The part of ``params`` an :class:`Analysis` depends on (compare to reuse a cache)."""
    d = params_to_dict(params)
    return {k: d[k] for k in ANALYSIS_FIELDS}


def analysis_compatible(analysis: "Analysis", params: GenerateParams) -> bool:
    """True when ``analysis`` was computed with the same analysis parameters as ``params``."""
    stored = {k: analysis.params.get(k) for k in ANALYSIS_FIELDS}
    return stored == analysis_key(params)


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

    audio = None
    if info.audio is None:
        if params.mode == "audio":
            raise MediaError(f"{info.path}: no audio stream (mode 'audio' needs one)")
    else:
        audio = _audio_pass(info, params, n, stats, progress, cancel, share=1.0)
    progress("done", 1.0)
    return Analysis(info=info.to_dict(), sha256=sha, n_ticks=n, params=params_to_dict(params),
                    audio=audio, stats=stats)


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
    if not params.allow_truncated:
        media.check_truncation(info, report.duration_s, "audio")
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

    if params.mode == "audio":
        cols = [ACTUATOR_IDS.index(a) for a in AUDIO_MODE_ACTUATORS]
        tl.vibration[:, cols] = intensity[:, None]

    gen_params = params_to_dict(params)
    gen_params["thresholds"] = dict(params.intensity.thresholds)
    gen_params["temp_low"], gen_params["temp_high"] = 30.0, 55.0
    tl.generator = default_generator(mode=params.mode, preset=preset, params=gen_params)
    stats["derive"] = {"seconds": time.perf_counter() - t0}
    stats["vibration"] = {"active_ticks": int((tl.vibration.max(axis=1) > 0).sum()), "ticks": n}
    tl.stats = stats
    return tl.validate()


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
