"""Audio -> vibration intensity (ALGORITHM.md section 2, thesis 3.1.1).

Recipe: normalise each of the four psychoacoustic parameters to [0, 1] over the clip ->
apply the four thresholds per 20 ms frame -> where ANY normalised parameter exceeds its
threshold the frame's intensity is the LARGEST of the four normalised values, else 0 ->
each 100 ms tick takes the MAX of its five frames (timebase.frames_to_ticks).

Example from the thesis: (sharpness, booming, low_energy, loudness) = (0.6, 0.4, 0.5, 0.9)
with thresholds (0.5, 0.65, 0.8, 0.85) -> 0.9.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import ClassVar

import numpy as np

from autohaptics.errors import ParameterError
from autohaptics.records import DERIVE
from autohaptics.timebase import frames_to_ticks

FEATURES = ("sharpness", "booming", "low_energy", "loudness")
DEFAULT_THRESHOLDS = {"sharpness": 0.50, "booming": 0.65, "low_energy": 0.80, "loudness": 0.85}
NORMALISERS = ("max", "percentile")


@dataclass(frozen=True)
class IntensityParams:
    """How normalised features become a vibration intensity.

    thresholds : per-feature threshold on the normalised value, 0..1 (thesis: sharpness 0.50,
        booming 0.65, low_energy 0.80, loudness 0.85). A threshold of 1 or more disables the feature.
    normaliser : "max" divides by the clip maximum (the thesis); "percentile" divides by the
        ``percentile``-th percentile and clips at 1, so one explosion does not flatten a feature film.
    percentile : percentile used by the "percentile" normaliser, 50..100 (default 99.5).
    loudness_gate : frames whose normalised loudness is below this never vibrate, 0..1
        (default 0.05, about 40 phon below the clip's loudest moment). Not in the thesis: sharpness
        and booming describe a sound's colour, not its level, so without a gate the hiss of a quiet
        scene can drive the chair at full sharpness. 0 reproduces the thesis.
    """

    STAGE: ClassVar[str] = DERIVE

    thresholds: dict = field(default_factory=lambda: dict(DEFAULT_THRESHOLDS))
    normaliser: str = "max"
    percentile: float = 99.5
    loudness_gate: float = 0.05

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

    def threshold(self, name: str) -> float:
        return float(self.thresholds.get(name, DEFAULT_THRESHOLDS[name]))


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
        ref = float(np.percentile(x, percentile))
        if ref <= 0.0:  # a mostly silent clip: fall back to the maximum
            ref = float(x.max())
    else:
        raise ParameterError(f"normaliser must be one of {NORMALISERS}, got {method!r}")
    if ref <= 0.0 or not math.isfinite(ref):
        return np.zeros_like(x)
    return np.minimum(x / ref, 1.0)


def normalise_features(features: dict[str, np.ndarray], *, params: IntensityParams) -> dict[str, np.ndarray]:
    """Normalise each of the four features (physical units in, [0, 1] out), same shapes."""
    missing = [f for f in FEATURES if f not in features]
    if missing:
        raise ParameterError(f"missing audio feature(s) {missing}")
    return {f: normalise(features[f], method=params.normaliser, percentile=params.percentile) for f in FEATURES}


def frame_intensity(normalised: dict[str, np.ndarray], *, params: IntensityParams) -> np.ndarray:
    """The max rule per frame: I = max of the four values where any exceeds its threshold, else 0
    (and 0 where normalised loudness is below ``params.loudness_gate``).

    normalised : {feature: np.ndarray [shape=(n,)] in [0, 1]}.
    Returns float64 [shape=(n,)] in [0, 1].
    """
    stack = np.stack([np.asarray(normalised[f], dtype=np.float64) for f in FEATURES])  # (4, n)
    thr = np.array([params.threshold(f) for f in FEATURES])[:, None]
    triggered = (stack > thr).any(axis=0)
    if params.loudness_gate > 0:
        triggered &= np.asarray(normalised["loudness"], dtype=np.float64) >= params.loudness_gate
    return np.where(triggered, stack.max(axis=0), 0.0)


def tick_intensity(normalised: dict[str, np.ndarray], n_ticks: int, *, params: IntensityParams) -> np.ndarray:
    """Per-tick audio intensity: the max rule per 20 ms frame, then the MAX of each tick's five frames.

    Returns float64 [shape=(n_ticks,)] in [0, 1].
    """
    return frames_to_ticks(frame_intensity(normalised, params=params), n_ticks)
