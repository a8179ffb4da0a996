"""Simulated designers with known tastes (the style tests and ``autohaptics bench style``).

A designer edits a film's generated timeline in two ways: their taste, the same on every film (a
threshold scale, a power curve and gain per actuator with weak effects cleared, the same for the
fans, the temperature's distance from neutral scaled and shifted), and a few one-off edits of
their own on each film (a scene's vibration cleared or set, its fans scaled, its temperature
pinned), seeded so every run edits the same ticks. The tastes are not the style's own curves
(power laws, hard floors), so a learned style can only approximate them.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from autohaptics.params import GenerateParams
from autohaptics.pipeline import Analysis, derive
from autohaptics.style.apply import scaled_params
from autohaptics.timebase import TICK_S
from autohaptics.timeline import Timeline

ONE_OFF_SECONDS = (1.0, 4.0)  # length of a one-off edit's range, s
ONE_OFF_EVERY_S = 15.0  # film seconds per one-off edit
BACK, SEAT = (0, 1, 3, 4, 5), (7, 8)  # A1, A2, A4-A6 and A8, A9 (layout.ACTUATORS)


@dataclass(frozen=True)
class Designer:
    """A taste. Levels 0..1 become ``clip(gain * actuator_gain * x ** gamma)``, 0 where ``x`` is
    below ``floor``; temperatures ``neutral + temp_scale * (t - neutral) + temp_offset_c``."""

    name: str
    taste: str
    threshold_scale: float = 1.0
    gain: float = 1.0
    gamma: float = 1.0
    floor: float = 0.0
    actuator_gain: tuple[float, ...] = (1.0,) * 9
    fan_gain: float = 1.0
    fan_gamma: float = 1.0
    fan_floor: float = 0.0
    temp_scale: float = 1.0
    temp_offset_c: float = 0.0


_BACK_HEAVY = tuple(1.3 if a in BACK else 0.6 if a in SEAT else 1.0 for a in range(9))
DESIGNERS: tuple[Designer, ...] = (
    Designer("punchy", "stronger vibration, weak effects lifted", gain=1.5, gamma=0.8),
    Designer("subtle", "gentle everything: weaker vibration and fans, temperature near neutral",
             gain=0.6, fan_gain=0.5, temp_scale=0.5),
    Designer("busy", "more events (lower thresholds), a little stronger", threshold_scale=0.7, gain=1.2),
    Designer("sparse", "fewer events (higher thresholds), weak vibration cleared",
             threshold_scale=1.4, floor=0.25),
    Designer("warm", "2 C warmer throughout, only strong wind", temp_offset_c=2.0, fan_gamma=1.6, fan_floor=0.15),
    Designer("breezy", "cooler and more contrasted, fans up", temp_offset_c=-1.5, temp_scale=1.3, fan_gain=1.5),
    Designer("back-heavy", "the back more than the seat", actuator_gain=_BACK_HEAVY, gamma=1.2),
)


def edit(designer: Designer, analysis: Analysis, params: GenerateParams | None = None, *, seed: int = 0,
         one_offs: int | None = None) -> Timeline:
    """The designer's edited timeline of a film: their taste over the derive from ``params``,
    then ``one_offs`` one-off edits at seeded random places (default one per
    :data:`ONE_OFF_EVERY_S` of film, at least one; none when 0)."""
    params = params or GenerateParams()
    if one_offs is None:
        one_offs = max(1, round(analysis.n_ticks * TICK_S / ONE_OFF_EVERY_S))
    tl = derive(analysis, scaled_params(params, threshold_scale=designer.threshold_scale, overrides={}))
    gains = np.asarray(designer.actuator_gain, np.float64) * designer.gain
    tl.vibration = _levels(tl.vibration, gains, designer.gamma, designer.floor)
    tl.fans = _levels(tl.fans, designer.fan_gain, designer.fan_gamma, designer.fan_floor)
    lo, hi = params.thermal.range_c
    neutral = params.thermal.neutral_c
    t = tl.temperature_c.astype(np.float64)
    tl.temperature_c = np.clip(neutral + designer.temp_scale * (t - neutral) + designer.temp_offset_c, lo, hi)
    _one_offs(tl, np.random.default_rng(seed), one_offs, (lo, hi))
    return tl.validate()


def _levels(x: np.ndarray, gain, gamma: float, floor: float) -> np.ndarray:
    x = np.asarray(x, np.float64)
    out = np.clip(gain * x ** gamma, 0.0, 1.0)
    out[x < floor] = 0.0
    return out.astype(np.float32)


def _one_offs(tl: Timeline, rng: np.random.Generator, count: int, range_c: tuple[float, float]) -> None:
    """Edit ``count`` random ranges in place, each one of four kinds (module docstring)."""
    for _ in range(count):
        length = int(rng.uniform(*ONE_OFF_SECONDS) / tl.tick_s)
        a = int(rng.integers(0, max(1, tl.n_ticks - length)))
        b = min(tl.n_ticks, a + length)
        kind = int(rng.integers(0, 4))
        if kind == 0:
            tl.vibration[a:b] = 0.0
        elif kind == 1:
            tl.vibration[a:b, rng.choice(9, size=3, replace=False)] = rng.uniform(0.3, 1.0)
        elif kind == 2:
            tl.fans[a:b] = np.clip(tl.fans[a:b] * rng.uniform(0.0, 2.0), 0.0, 1.0)
        else:
            tl.temperature_c[a:b] = rng.uniform(*range_c)
