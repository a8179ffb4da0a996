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

import cv2
import numpy as np

from autohaptics.errors import ParameterError
from autohaptics.layout import DEVICE_TEMP_MAX_C, DEVICE_TEMP_MIN_C, TEMP_HIGH_C, TEMP_LOW_C, TEMP_NEUTRAL_C

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


def mean_colour(rgb: np.ndarray) -> np.ndarray:
    """Mean RGB of a frame. rgb uint8 [shape=(h, w, 3)] -> float64 [shape=(3,)], 0..255.

    OpenCV's per-channel mean for uint8 frames (~10 us on a 128 px proxy, 50x numpy's float64
    reduction: it runs once per tick, 72 000 times for a 2-hour film).
    """
    rgb = np.asarray(rgb)
    if rgb.ndim != 3 or rgb.shape[2] != 3 or rgb.size == 0:
        raise ParameterError(f"expected an RGB frame of shape (h, w, 3), got {rgb.shape}")
    if rgb.dtype == np.uint8:
        return np.array(cv2.mean(np.ascontiguousarray(rgb))[:3], dtype=np.float64)
    return rgb.reshape(-1, 3).mean(axis=0, dtype=np.float64)


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


def slew_limit(temps: np.ndarray, *, max_rate_c_per_s: float, tick_s: float = 0.1,
               start_c: float | None = None) -> np.ndarray:
    """Limit the change between consecutive ticks to ``max_rate_c_per_s * tick_s``.

    temps float [shape=(n,)], C. start_c : the element's temperature before tick 0 (default temps[0]).
    """
    x = np.asarray(temps, dtype=np.float64)
    if x.size == 0:
        return x.copy()
    if not (max_rate_c_per_s > 0 and tick_s > 0):
        raise ParameterError("slew_limit needs a positive rate and tick")
    step = float(max_rate_c_per_s) * float(tick_s)
    out = np.empty_like(x)
    cur = float(x[0] if start_c is None else start_c)
    for i, target in enumerate(x.tolist()):
        cur += min(step, max(-step, target - cur))
        out[i] = cur
    return out


def clamp_to_device(temps: np.ndarray, *, min_c: float = DEVICE_TEMP_MIN_C, max_c: float = DEVICE_TEMP_MAX_C) -> np.ndarray:
    """Clamp a target curve to a device's safe range (default 18..40 C)."""
    if not min_c <= max_c:
        raise ParameterError(f"device range must have min <= max, got {min_c}, {max_c}")
    return np.clip(np.nan_to_num(np.asarray(temps, dtype=np.float64), nan=TEMP_NEUTRAL_C), min_c, max_c)
