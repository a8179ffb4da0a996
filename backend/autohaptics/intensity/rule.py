"""Audio -> vibration intensity (ALGORITHM.md section 2, thesis 3.1.1), two rules.

"events" (default): each feature's novelty against its own recent baseline (:mod:`.novelty`)
is compared with its threshold; where ANY exceeds it, and the normalised loudness is at least
``loudness_gate`` (a gate relative to the film's level), the frame's intensity is the LARGEST of
the normalised loudness, booming and low-frequency energy (the sound's level against the film),
else 0. A steady bed stays near its baseline and does not vibrate; impacts, hits and a rising
rumble do, as hard as they are loud. Sharpness, which describes a sound's colour, not its level,
can trigger but does not set the intensity. ``smoothing_s`` keeps its decisions where a lossy
codec re-encodes the sound: loudness and sharpness through a running median of that length, and
a pause shorter than twice it between two triggered stretches bridged, so a codec's dip does not
split one event into two onsets.

"thesis": normalise each of the four features to [0, 1] over the clip -> where ANY normalised
feature exceeds its threshold the frame's intensity is the LARGEST of the four, else 0.
Example from the thesis: (sharpness, booming, low_energy, loudness) = (0.6, 0.4, 0.5, 0.9)
with thresholds (0.5, 0.65, 0.8, 0.85) -> 0.9.

Both: each 100 ms tick takes the MAX of its five frames (timebase.frames_to_ticks). With a
``density`` the four thresholds are scaled by one factor so that about that share of the ticks
vibrate (:func:`density_scale`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import ClassVar

import numpy as np

from autohaptics import quantiles
from autohaptics.errors import ParameterError
from autohaptics.intensity.novelty import feature_novelty
from autohaptics.records import DERIVE
from autohaptics.timebase import FRAME_S, frames_to_ticks

FEATURES = ("sharpness", "booming", "low_energy", "loudness")
DEFAULT_THRESHOLDS = {"sharpness": 0.50, "booming": 0.65, "low_energy": 0.80, "loudness": 0.85}
NORMALISERS = ("max", "percentile")
RULES = ("events", "thesis")
SMOOTHING_MAX_S = 0.5
LEVEL_FEATURES = ("booming", "low_energy", "loudness")  # what sets the "events" rule's intensity


@dataclass(frozen=True)
class IntensityParams:
    """How the audio features become a vibration intensity: the rule, its thresholds, gate and density.

    rule : "events" (default: novelty against the recent baseline) or "thesis" (the thesis's
        rule on the normalised features; ``params.THESIS_RULES``).
    thresholds : per-feature threshold, 0..1, on the novelty ("events") or on the normalised
        value ("thesis"); defaults sharpness 0.50, booming 0.65, low_energy 0.80, loudness 0.85
        (the thesis's). A threshold of 1 or more disables the feature.
    normaliser : "percentile" (default) divides by the ``percentile``-th percentile and clips at
        1, so one explosion does not flatten a feature film and the loudness gate's reference is
        not one frame a codec moves; "max" divides by the clip maximum (the thesis's).
    percentile : percentile used by the "percentile" normaliser, 50..100 (default 99.5).
    loudness_gate : frames whose normalised loudness is below this never vibrate, 0..1 (default
        0.2, about 23 phon below the film's loud level, the normaliser's reference; the thesis
        variant 0.05, about 43 phon below its loudest frame).
        Not in the thesis: without a gate the hiss of a quiet scene can drive the chair.
    baseline_s : length of the "events" rule's recent baseline, seconds, 0.5..30 (default 3).
    smoothing_s : the "events" rule's running median of loudness and sharpness, and half the
        longest pause it bridges, seconds, 0..0.5 (default 0.1; 0: neither).
    density : the share of the film's ticks that should vibrate, 0..1, or None (default: the
        thresholds as they are). When set, the thresholds are scaled by one common factor so
        that about this share vibrates; never more than the share above the loudness gate.
    """

    STAGE: ClassVar[str] = DERIVE

    rule: str = "events"
    thresholds: dict = field(default_factory=lambda: dict(DEFAULT_THRESHOLDS))
    normaliser: str = "percentile"
    percentile: float = 99.5
    loudness_gate: float = 0.2
    baseline_s: float = 3.0
    smoothing_s: float = 0.1
    density: float | None = None

    def __post_init__(self):
        unknown = set(self.thresholds) - set(FEATURES)
        if unknown:
            raise ParameterError(f"unknown threshold name(s) {sorted(unknown)}; expected {list(FEATURES)}")
        for name, value in self.thresholds.items():
            if not isinstance(value, (int, float)) or not math.isfinite(value) or value < 0:
                raise ParameterError(f"threshold {name} must be a finite number >= 0, got {value!r}")
        if self.normaliser not in NORMALISERS:
            raise ParameterError(f"normaliser must be one of {NORMALISERS}, got {self.normaliser!r}")
        if not (50.0 <= float(self.percentile) <= 100.0):
            raise ParameterError(f"percentile must lie in 50..100, got {self.percentile!r}")
        if not (0.0 <= float(self.loudness_gate) <= 1.0):
            raise ParameterError(f"loudness_gate must lie in 0..1, got {self.loudness_gate!r}")
        if self.rule not in RULES:
            raise ParameterError(f"intensity.rule must be one of {RULES}, got {self.rule!r}")
        if not (0.5 <= float(self.baseline_s) <= 30.0):
            raise ParameterError(f"intensity.baseline_s must lie in 0.5..30 s, got {self.baseline_s!r}")
        if not (0.0 <= float(self.smoothing_s) <= SMOOTHING_MAX_S):
            raise ParameterError(f"intensity.smoothing_s must lie in 0..{SMOOTHING_MAX_S} s, got {self.smoothing_s!r}")
        if self.density is not None and not (0.0 <= float(self.density) <= 1.0):
            raise ParameterError(f"intensity.density must lie in 0..1 (a share of the film), got {self.density!r}")

    def threshold(self, name: str) -> float:
        return float(self.thresholds.get(name, DEFAULT_THRESHOLDS[name]))

    def smoothing_frames(self) -> int:
        """``smoothing_s`` in 20 ms frames under the "events" rule, 0 under "thesis"."""
        return int(round(float(self.smoothing_s) / FRAME_S)) if self.rule == "events" else 0


def normalise(x: np.ndarray, *, method: str = "max", percentile: float = 99.5) -> np.ndarray:
    """Scale a non-negative feature curve to [0, 1].

    x : np.ndarray [shape=(n,)], any unit, >= 0 and finite.
    Returns float64 [shape=(n,)] in [0, 1]. A curve whose reference value is 0 (silence)
    normalises to all zeros, never NaN.
    """
    x = np.asarray(x, dtype=np.float64)
    if x.size == 0:
        return x.copy()
    if not np.isfinite(x).all():
        raise ParameterError(f"feature curve holds {int((~np.isfinite(x)).sum())} non-finite value(s) (shape {x.shape})")
    x = np.maximum(x, 0.0)
    if method == "max":
        ref = float(x.max())
    elif method == "percentile":
        ref = float(quantiles.percentile(x, percentile))
        if ref <= 0.0:  # a mostly silent clip: fall back to the maximum
            ref = float(x.max())
    else:
        raise ParameterError(f"normaliser must be one of {NORMALISERS}, got {method!r}")
    if ref <= 0.0 or not math.isfinite(ref):
        return np.zeros_like(x)
    with np.errstate(over="ignore"):  # x / a denormal percentile may overflow to inf: it is clipped to 1
        return np.minimum(x / ref, 1.0)


def normalise_features(features: dict[str, np.ndarray], *, params: IntensityParams) -> dict[str, np.ndarray]:
    """Normalise each of the four features (physical units in, [0, 1] out), same shapes."""
    missing = [f for f in FEATURES if f not in features]
    if missing:
        raise ParameterError(f"missing audio feature(s) {missing}")
    return {f: normalise(features[f], method=params.normaliser, percentile=params.percentile) for f in FEATURES}


def frame_intensity(normalised: dict[str, np.ndarray], *, params: IntensityParams) -> np.ndarray:
    """The thesis's max rule per frame: I = max of the four values where any exceeds its threshold,
    else 0 (and 0 where normalised loudness is below ``params.loudness_gate``).

    normalised : {feature: np.ndarray [shape=(n,)] in [0, 1]}.
    Returns float64 [shape=(n,)] in [0, 1].
    """
    return triggered_values(normalised, normalised, params=params, value_features=FEATURES)


def tick_intensity(normalised: dict[str, np.ndarray], n_ticks: int, *, params: IntensityParams) -> np.ndarray:
    """Per-tick intensity of the thesis's rule: the max rule per 20 ms frame, then the MAX of each
    tick's five frames. Returns float64 [shape=(n_ticks,)] in [0, 1]."""
    return frames_to_ticks(frame_intensity(normalised, params=params), n_ticks)


def decision_curves(features: dict[str, np.ndarray], normalised: dict[str, np.ndarray], *,
                    params: IntensityParams) -> dict[str, np.ndarray]:
    """The curves the thresholds apply to, per 20 ms frame, finite and >= 0: each feature's novelty
    against its recent baseline ("events", unclipped: shown clipped at 1) or the normalised feature
    itself ("thesis", 0..1)."""
    if params.rule == "thesis":
        return normalised
    return feature_novelty({f: features[f] for f in FEATURES}, baseline_s=float(params.baseline_s),
                           median_n=params.smoothing_frames())


def triggered_values(normalised: dict[str, np.ndarray], curves: dict[str, np.ndarray], *, params: IntensityParams,
                     value_features: tuple[str, ...], scale: float = 1.0) -> np.ndarray:
    """Per frame: the largest normalised ``value_features`` where any enabled feature's curve
    exceeds its threshold times ``scale`` and the loudness passes the gate, else 0; a pause shorter
    than 2 x ``params.smoothing_frames()`` frames between two such stretches takes its values too.
    Returns float64 [shape=(n,)] in [0, 1]."""
    stack = np.stack([np.asarray(curves[f], dtype=np.float64) for f in FEATURES])  # (4, n)
    thr = np.array([params.threshold(f) for f in FEATURES])
    enabled = thr < 1.0
    triggered = (stack[enabled] > (thr[enabled] * scale)[:, None]).any(axis=0)
    if params.loudness_gate > 0:
        triggered &= np.asarray(normalised["loudness"], dtype=np.float64) >= params.loudness_gate
    triggered = bridge_pauses(triggered, 2 * params.smoothing_frames() - 1)
    values = np.stack([np.asarray(normalised[f], dtype=np.float64) for f in value_features]).max(axis=0)
    return np.where(triggered, values, 0.0)


def trigger_depths(normalised: dict[str, np.ndarray], curves: dict[str, np.ndarray], thresholds: np.ndarray,
                   n_ticks: int, *, params: IntensityParams, value_features: tuple[str, ...]) -> np.ndarray:
    """For threshold sets that only rise (``thresholds`` [shape=(sets, 4)], columns in
    :data:`FEATURES` order, never decreasing down a column; 1 or more: that feature off), per tick
    the count k of leading sets whose :func:`triggered_values` (scale 1, ``params``' gate and
    pauses) vibrate it: the tick vibrates with sets 0..k-1 and none after (a rising threshold only
    takes triggered frames away, and the bridged pauses with them). One pass for all the sets,
    exactly what one evaluation per set gives. Returns int32 [shape=(n_ticks,)] in 0..sets."""
    thresholds = np.asarray(thresholds, np.float64)
    thr = np.where(thresholds < 1.0, thresholds, np.inf)
    depth = np.zeros(len(curves[FEATURES[0]]), np.int32)
    for f, column in zip(FEATURES, thr.T):
        np.maximum(depth, np.searchsorted(column, np.asarray(curves[f], np.float64), side="left"), out=depth)
    if params.loudness_gate > 0:
        depth[np.asarray(normalised["loudness"], dtype=np.float64) < params.loudness_gate] = 0
    n = depth.size
    longest = min(2 * params.smoothing_frames() - 1, n - 2)  # no pause between two frames is longer
    if longest >= 1:  # a frame in a pause of at most ``longest`` frames between two frames deep >= k
        bridged = depth.copy()
        after = np.zeros((longest + 1, n), np.int32)  # after[m][x]: the deepest of frames x+1..x+m
        for m in range(1, longest + 1):
            after[m] = after[m - 1]  # frames past the film's end add nothing
            np.maximum(after[m - 1, :n - m], depth[m:], out=after[m, :n - m])
        for a in range(1, longest + 1):
            np.maximum(bridged[a:], np.minimum(depth[:-a], after[longest + 1 - a, a:]), out=bridged[a:])
        depth = bridged
    values = np.stack([np.asarray(normalised[f], dtype=np.float64) for f in value_features]).max(axis=0)
    return frames_to_ticks(np.where(values > 0, depth, 0), n_ticks)


def bridge_pauses(on: np.ndarray, longest: int) -> np.ndarray:
    """``on`` (bool [shape=(n,)]) with every run of False of at most ``longest`` frames that has True
    on both sides set True; a copy, ``on`` itself for longest < 1."""
    on = np.asarray(on, dtype=bool)
    if longest < 1 or not on.any():
        return on
    edges = np.diff(np.concatenate([[0], on.astype(np.int8), [0]]))
    ends, starts = np.flatnonzero(edges == -1)[:-1], np.flatnonzero(edges == 1)[1:]  # pause = [end, start)
    out = on.copy()
    for a, b in zip(ends[starts - ends <= longest], starts[starts - ends <= longest]):
        out[a:b] = True
    return out


def density_scale(normalised: dict[str, np.ndarray], curves: dict[str, np.ndarray], n_ticks: int, *,
                  params: IntensityParams) -> float:
    """The factor on every threshold that makes about ``params.density`` of the ticks vibrate:
    each tick scores the largest curve / threshold over its frames above the loudness gate, and
    the factor is the score of the first tick left out when the ticks are ranked (ties and the
    gate can leave fewer). Returns a finite factor >= 0 (1.0 without a density)."""
    if params.density is None or n_ticks == 0:
        return 1.0
    thr = np.array([params.threshold(f) for f in FEATURES])
    enabled = thr < 1.0
    if not enabled.any():
        return 1.0
    stack = np.stack([np.asarray(curves[f], dtype=np.float64) for f in FEATURES])[enabled]
    ratio = stack / np.maximum(thr[enabled], 1e-6)[:, None]
    score = ratio.max(axis=0) * (np.asarray(normalised["loudness"]) >= params.loudness_gate)
    ticks = np.sort(frames_to_ticks(score, n_ticks))[::-1]
    keep = int(round(float(params.density) * n_ticks))
    if keep >= n_ticks:
        return 0.0
    return float(ticks[keep])


# The fields applied after the decision curves (:func:`decision_inputs`): a threshold commit changes
# only these, so the curves of one film can be kept across commits (``pipeline.derive``).
APPLIED_AFTER_CURVES = ("thresholds", "density", "loudness_gate")


def decision_inputs(features: dict[str, np.ndarray], *,
                    params: IntensityParams) -> tuple[dict[str, np.ndarray], dict[str, np.ndarray]]:
    """The normalised features and the curves the thresholds apply to, per 20 ms frame: the part of
    :func:`audio_intensity` that none of :data:`APPLIED_AFTER_CURVES` changes (most of its time)."""
    norm = normalise_features(features, params=params)
    return norm, decision_curves(features, norm, params=params)


def audio_intensity(features: dict[str, np.ndarray], n_ticks: int, *, params: IntensityParams,
                    inputs: tuple[dict, dict] | None = None) -> tuple[np.ndarray, dict[str, np.ndarray], dict]:
    """The per-tick vibration intensity of ``params.rule`` (module docstring).

    features : {feature: physical values per 20 ms frame [shape=(n_ticks * 5,)]}.
    inputs : :func:`decision_inputs` of ``features`` with these parameters, when already computed.
    Returns (intensity float64 [shape=(n_ticks,)] in [0, 1], the per-tick curves the thresholds
    apply to {feature: [shape=(n_ticks,)] in [0, 1]}, stats {"rule", "density", "threshold_scale"}).
    """
    norm, curves = inputs if inputs is not None else decision_inputs(features, params=params)
    scale = density_scale(norm, curves, n_ticks, params=params)
    value_features = FEATURES if params.rule == "thesis" else LEVEL_FEATURES
    frames = triggered_values(norm, curves, params=params, value_features=value_features, scale=scale)
    stats = {"rule": params.rule, "density": params.density, "threshold_scale": scale}
    shown = {f: frames_to_ticks(np.minimum(curves[f], 1.0), n_ticks) for f in FEATURES}
    return frames_to_ticks(frames, n_ticks), shown, stats
