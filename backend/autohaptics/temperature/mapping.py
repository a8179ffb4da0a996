"""Colour -> temperature (ALGORITHM.md section 4, thesis 5.2).

Mean RGB of the frame; DisR = distance to pure red (255, 0, 0), DisG = distance to pure green
(0, 255, 0). The thesis's ratio DisR / DisG is unbounded (a pure green frame divides by zero) and
overshoots 55 C; we use the bounded, order-preserving r = DisR / (DisR + DisG) in [0, 1] (the
denominator is never below the red-green distance, 360.6) and
T = temp_high - (temp_high - temp_low) * r: red -> temp_high, green -> temp_low.

The curve is a TARGET. 55 C on skin burns: the device profile clamps it to its own safe range
(:func:`clamp_to_device`, default at most 40 C) and real thermal elements need a rate limit
(:func:`slew_limit`). Neutral colours (black, white, grey) land mid-range under the formula; the
``neutral_aware`` option pulls desaturated colours to a skin-neutral ``neutral_c``.

neutral_aware (decision): r = 1/2 exactly when green = red (DisR^2 - DisG^2 = 510 (G - R)), which
includes every grey. The option first re-maps r piecewise-linearly so that r = 1/2 lands on
``neutral_c`` (r = 0 -> temp_high, r = 1 -> temp_low), then pulls towards ``neutral_c`` by chroma.
Then adding red never cools: it raises the re-mapped temperature and, when the colour is on the
cold side (R < G), it can only lower the chroma, i.e. pull a cold value up. Pulling the plain
formula (greys at 42.5 C) towards 33 C broke that: light cyan (200, 255, 255) read 37.4 C and
white, one step redder, 33 C.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import ClassVar

import numpy as np

from autohaptics.errors import ParameterError
from autohaptics.records import DERIVE
from autohaptics.layout import TEMP_HIGH_C, TEMP_LOW_C, TEMP_NEUTRAL_C
from autohaptics.temperature.device import slew_limit

_RED = np.array([255.0, 0.0, 0.0])
_GREEN = np.array([0.0, 255.0, 0.0])


@dataclass(frozen=True)
class ThermalParams:
    """Colour-to-temperature mapping.

    temp_low, temp_high : target temperatures (C) of pure green and pure red (thesis: 30 and 55).
    neutral_aware : greys map to ``neutral_c`` and desaturated colours are pulled towards it
        (module docstring).
    neutral_c : skin-neutral temperature, C (default 33).
    chroma_low, chroma_high : chroma (max - min channel, 0..255) below which a colour is fully
        neutral and above which it keeps its full temperature (linear between), neutral_aware only.
    slew_c_per_s : rate limit of the generated curve, C per second (None = no limit; the device
        applies its own limit too).
    """

    STAGE: ClassVar[str] = DERIVE

    temp_low: float = TEMP_LOW_C
    temp_high: float = TEMP_HIGH_C
    neutral_aware: bool = False
    neutral_c: float = TEMP_NEUTRAL_C
    chroma_low: float = 20.0
    chroma_high: float = 90.0
    slew_c_per_s: float | None = None

    def __post_init__(self):
        for name in ("temp_low", "temp_high", "neutral_c", "chroma_low", "chroma_high"):
            if not math.isfinite(float(getattr(self, name))):
                raise ParameterError(f"thermal.{name} must be finite, got {getattr(self, name)!r}")
        if not (-20.0 <= self.temp_low < self.temp_high <= 80.0):
            raise ParameterError(f"thermal needs -20 <= temp_low < temp_high <= 80 C, got {self.temp_low}, {self.temp_high}")
        if not (self.temp_low <= self.neutral_c <= self.temp_high):
            raise ParameterError(f"thermal.neutral_c must lie in [temp_low, temp_high], got {self.neutral_c}")
        if not (0.0 <= self.chroma_low < self.chroma_high <= 255.0):
            raise ParameterError("thermal needs 0 <= chroma_low < chroma_high <= 255")
        if self.slew_c_per_s is not None and not (0.0 < float(self.slew_c_per_s) < 1e6):
            raise ParameterError(f"thermal.slew_c_per_s must be positive (C/s) or None, got {self.slew_c_per_s!r}")




def warmth_ratio(mean_rgb: np.ndarray) -> np.ndarray:
    """r = DisR / (DisR + DisG) in [0, 1] (0 = pure red, 1 = pure green). [shape=(..., 3)] -> [shape=(...,)]."""
    c = np.clip(np.nan_to_num(np.asarray(mean_rgb, dtype=np.float64)), 0.0, 255.0)
    dis_r = np.linalg.norm(c - _RED, axis=-1)
    dis_g = np.linalg.norm(c - _GREEN, axis=-1)
    return dis_r / (dis_r + dis_g)  # dis_r + dis_g >= |RED - GREEN| = 360.6 > 0


def temperature_target(mean_rgb: np.ndarray, *, params: ThermalParams = ThermalParams()) -> np.ndarray:
    """Target temperature per tick, C. mean_rgb float [shape=(n, 3)] (or (3,)) -> [shape=(n,)] (or scalar).

    Always within [temp_low, temp_high]; a brighter red is never colder.
    """
    c = np.clip(np.nan_to_num(np.asarray(mean_rgb, dtype=np.float64)), 0.0, 255.0)
    r = warmth_ratio(c)
    if not params.neutral_aware:
        t = params.temp_high - (params.temp_high - params.temp_low) * r
    else:
        warm = params.temp_high - (params.temp_high - params.neutral_c) * (2.0 * r)
        cold = params.neutral_c - (params.neutral_c - params.temp_low) * (2.0 * r - 1.0)
        t = np.where(r <= 0.5, warm, cold)
        chroma = c.max(axis=-1) - c.min(axis=-1)
        keep = np.clip((chroma - params.chroma_low) / (params.chroma_high - params.chroma_low), 0.0, 1.0)
        t = params.neutral_c + keep * (t - params.neutral_c)
    return np.clip(t, params.temp_low, params.temp_high)


def temperature_track(mean_rgb: np.ndarray, *, params: ThermalParams = ThermalParams(), tick_s: float = 0.1) -> np.ndarray:
    """The generated temperature curve, C [shape=(n,)]: the target of each tick's mean colour
    [shape=(n, 3)], rate-limited when ``params.slew_c_per_s`` is set, within [temp_low, temp_high]."""
    target = temperature_target(np.asarray(mean_rgb, dtype=np.float64), params=params)
    if params.slew_c_per_s:
        target = slew_limit(target, max_rate_c_per_s=params.slew_c_per_s, tick_s=tick_s)
    return np.clip(target, float(params.temp_low), float(params.temp_high))
