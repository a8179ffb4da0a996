"""The derive: a feature cache and the derive-time parameters (thresholds, mode, mappings, the fan
rule) -> a :class:`~autohaptics.timeline.Timeline`, without decoding (milliseconds for a feature
film). Each track comes from its stage: intensity and fusion (vibration), temperature, airflow (fans).
"""

from __future__ import annotations

import dataclasses
import json
import threading
import time
import weakref
from collections.abc import Callable
from typing import Any

import numpy as np

from autohaptics import intensity as inten
from autohaptics.airflow import fan_track
from autohaptics.fusion import smoothed_weights, vibration_track
from autohaptics.media import source_block
from autohaptics.params import DEFAULT_PRESET, GenerateParams
from autohaptics.pipeline.cache import Analysis
from autohaptics.pipeline.refine import lacking_saliency
from autohaptics.records import params_to_dict
from autohaptics.temperature import temperature_track
from autohaptics.timebase import TICK_S
from autohaptics.timeline import Timeline, default_generator


def derive(analysis: Analysis, params: GenerateParams | None = None, *, preset: str = DEFAULT_PRESET,
           style: Any = None) -> Timeline:
    """Turn a feature cache into a timeline (no decoding; milliseconds for a feature film).

    style : an :class:`autohaptics.style.Style` or None: its parameters apply before the derive,
        its tone curves to the tracks after it; recorded as ``generator["style"]``.
    ``stats["needs_analysis"]`` is set when vibrating ticks lack saliency of their own that their
    frames could give (their weights were borrowed or fell back to A5): :func:`refine` computes it.
    """
    params = params or GenerateParams()
    if style is not None:
        params = style.apply_params(params)
    t0 = time.perf_counter()
    n = analysis.n_ticks
    tl = Timeline.empty(n, source=source_block(analysis.info, sha256=analysis.sha256))
    stats = json.loads(json.dumps(analysis.stats))
    intensity = _intensity(analysis, params, tl, stats)
    video = analysis.video
    if "vibration" in params.tracks:
        vib, vstats = vibration_track(params.mode, intensity, seed=params.seed,
                                      beta=None if video is None else _weights(video, params.fusion.sigma_ticks),
                                      have_beta=None if video is None else video.saliency_mask,
                                      cut=None if video is None else video.cut)
        tl.vibration[:] = vib
        if params.mode == "multimodal":
            stats["fusion"] = vstats
            if lacking_saliency(video, intensity > 0).any():
                stats["needs_analysis"] = True
    temp_low, temp_high = params.thermal.range_c
    if video is None:
        tl.temperature_c[:] = float(np.clip(params.thermal.neutral_c, temp_low, temp_high))
    else:
        _picture_tracks(video, params, tl, stats)
    gen_params = params_to_dict(params)
    gen_params["thresholds"] = dict(params.intensity.thresholds)
    gen_params["temp_low"], gen_params["temp_high"] = temp_low, temp_high
    tl.generator = default_generator(mode=params.mode, preset=preset, params=gen_params)
    if style is not None:
        tl.vibration, tl.temperature_c, tl.fans = style.shape(tl.vibration, tl.temperature_c, tl.fans,
                                                              neutral_c=params.thermal.neutral_c,
                                                              range_c=(temp_low, temp_high))
        tl.generator["style"] = style.to_dict()
    stats["derive"] = {"seconds": time.perf_counter() - t0}
    active = int(np.count_nonzero(np.logical_or.reduce(tl.vibration.T > 0)))
    stats["vibration"] = {"active_ticks": active, "ticks": n, "share": active / n if n else 0.0,
                          **stats.pop("intensity_rule", {})}
    tl.stats = stats
    return tl.validate()


# The picture's tracks of recent derives (temperature, motion, fans), per video analysis (held
# weakly) and the parameters they read: no threshold or intensity rule changes them, and
# recomputing them (the fans most of all) would be most of a threshold commit's derive.
_PICTURE: dict[int, tuple] = {}
_PICTURE_KEPT = 2
_PICTURE_LOCK = threading.Lock()
_MAKING: dict[tuple, threading.Event] = {}  # (table, ident) of the entries some thread computes


def _kept(table: dict, lock: threading.Lock, ident: Any, key: Any, alive: Callable[[tuple], bool],
          compute: Callable[[], tuple]) -> tuple[tuple, bool]:
    """``table[ident]`` when ``alive(hit)`` and its key is ``key``, else ``compute()`` (returning the
    entry to keep), computed by one thread at a time: a derive that starts while another computes
    the same entry (a commit during the warm-up after a job) waits for it instead of doing it again.
    Returns (entry, whether this call computed it)."""
    gate = (id(table), ident)  # the keys hold dicts: not hashable
    while True:
        with lock:
            hit = table.get(ident)
            if hit is not None and alive(hit) and hit[1] == key:
                return hit, False
            busy = _MAKING.get(gate)
            if busy is None:
                busy = _MAKING[gate] = threading.Event()
                break
        busy.wait()  # then read what it kept (or compute, when it failed or was evicted)
    try:
        entry = compute()
        with lock:
            table[ident] = entry
            while len(table) > _PICTURE_KEPT:
                table.pop(next(iter(table)))
        return entry, True
    finally:
        with lock:
            _MAKING.pop(gate, None)
        busy.set()


_WEIGHTS: dict[int, tuple] = {}  # the smoothed saliency weights of recent derives, per video analysis
_WEIGHTS_LOCK = threading.Lock()


def _weights(video, sigma_ticks: float) -> np.ndarray:
    """``video``'s saliency weights smoothed over their shots (``fusion.smoothed_weights``), kept
    read-only per video analysis and standard deviation as the picture's tracks are: no threshold
    changes them, so a threshold commit does not compute them again."""
    if sigma_ticks <= 0:
        return video.beta

    def compute() -> tuple:
        beta = smoothed_weights(video.beta, video.saliency_mask, video.cut, sigma_ticks)
        beta.flags.writeable = False
        return (weakref.ref(video), float(sigma_ticks), beta)

    hit, _ = _kept(_WEIGHTS, _WEIGHTS_LOCK, id(video), float(sigma_ticks), lambda h: h[0]() is video, compute)
    return hit[2]


def _picture_tracks(video, params: GenerateParams, tl: Timeline, stats: dict) -> None:
    """Set ``tl``'s temperature, motion features and fans from ``video`` (and their ``stats``).

    A later derive from the same ``video`` with the same thermal and airflow parameters and tracks
    shares read-only copies of them instead of recomputing them; the first one's own stay writable.
    """
    key = (params.thermal, params.airflow, "temperature" in params.tracks, "fans" in params.tracks)

    def compute() -> tuple:
        own = _picture_compute(video, params, tl)
        arrays = {"temperature_c": tl.temperature_c, "fans": tl.fans,
                  **{name: tl.features[name] for name in ("temperature_target_c", "motion", "motion_fw_per_s")
                     if name in tl.features}}
        kept = {}
        for name, values in arrays.items():
            kept[name] = np.array(values, dtype=np.float32)
            kept[name].flags.writeable = False
        return (weakref.ref(video), key, kept, json.loads(json.dumps(own)))

    hit, computed = _kept(_PICTURE, _PICTURE_LOCK, id(video), key, lambda h: h[0]() is video, compute)
    arrays, kept_stats = hit[2], hit[3]
    if not computed:
        tl.temperature_c, tl.fans = arrays["temperature_c"], arrays["fans"]
        tl.features.update((name, arrays[name]) for name in arrays if name not in ("temperature_c", "fans"))
    stats.update(json.loads(json.dumps(kept_stats)))


def _picture_compute(video, params: GenerateParams, tl: Timeline) -> dict:
    """Compute ``tl``'s temperature, motion features and fans from ``video``; returns their stats."""
    stats = {}
    n = tl.n_ticks
    temp_low, temp_high = params.thermal.range_c
    tl.temperature_c[:] = float(np.clip(params.thermal.neutral_c, temp_low, temp_high))
    if "temperature" in params.tracks:
        tl.temperature_c[:], target, stats["temperature"] = temperature_track(video.mean_rgb, params=params.thermal,
                                                                              tick_s=TICK_S)
        if params.thermal.mapping != "thesis":
            tl.features["temperature_target_c"] = target
    peak = float(video.motion.max()) if video.motion.size else 0.0
    tl.features["motion"] = np.clip(video.motion / peak, 0.0, 1.0) if peak > 0 else np.zeros(n)
    tl.features["motion_fw_per_s"] = video.motion.astype(np.float64)
    if "fans" in params.tracks:
        _, stats["airflow"] = fan_track(video.motion, video.cell_motion, video.nearness, video.cut, video.depth_mask,
                                        params=params.airflow, out=tl.fans)
    return stats


def _intensity(analysis: Analysis, params: GenerateParams, tl: Timeline, stats: dict) -> np.ndarray:
    """The per-tick audio intensity (0 everywhere without an audio stream); the curves the
    thresholds apply to go into ``tl.features`` (normalised features for the thesis rule, their
    novelty for the events rule) and the rule's figures into ``stats["intensity_rule"]``."""
    n = analysis.n_ticks
    if analysis.audio is None:
        for name in inten.FEATURES:
            tl.features[name] = np.zeros(n)
        intensity = np.zeros(n)
    else:
        intensity, curves, rule_stats = inten.audio_intensity(analysis.audio, n, params=params.intensity,
                                                              inputs=kept_decision_inputs(analysis.audio, params.intensity))
        for name in inten.FEATURES:
            tl.features[name] = curves[name]
        stats["intensity_rule"] = rule_stats
    tl.features["intensity"] = intensity
    return intensity


# The intensity rule's decision inputs of recent derives, per audio feature set (held weakly) and
# the intensity parameters that shape them: a threshold commit reuses them.
_CURVES: dict[tuple, tuple] = {}
_CURVES_LOCK = threading.Lock()


def kept_decision_inputs(audio, params: inten.IntensityParams) -> tuple[dict, dict]:
    """:func:`intensity.decision_inputs` of ``audio`` (its dict of per-frame features), kept from an
    earlier derive of the same features when no parameter but those applied after them changed."""
    key = dataclasses.replace(params, **{f: getattr(inten.IntensityParams(), f) for f in inten.APPLIED_AFTER_CURVES})
    arrays = tuple(sorted(audio.items()))
    ident = tuple((name, id(values)) for name, values in arrays)

    def compute() -> tuple:
        inputs = inten.decision_inputs(audio, params=params)
        for curves in inputs:
            for values in curves.values():
                values.flags.writeable = False
        return ([weakref.ref(values) for _, values in arrays], key, inputs)

    alive = lambda hit: all(ref() is values for ref, (_, values) in zip(hit[0], arrays))  # noqa: E731
    return _kept(_CURVES, _CURVES_LOCK, ident, key, alive, compute)[0][2]
