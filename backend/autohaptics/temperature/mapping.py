"""Colour -> temperature (ALGORITHM.md section 4): the default warm-cool mapping and the thesis's rule.

``mapping="warmcool"`` (default): the warm-cool value of each tick's mean colour mapped around a
skin-neutral ``neutral_c`` into the device's range, scaled to the film (:mod:`.warmcool`), then
slew-limited at the device's rate: the curve IS what the chair plays (:func:`played_curve`).

``mapping="thesis"`` (thesis 5.2, ``params.THESIS_RULES``): mean RGB of the frame; DisR = distance
to pure red (255, 0, 0), DisG = distance to pure green (0, 255, 0). The thesis's ratio DisR / DisG
is unbounded (a pure green frame divides by zero) and overshoots 55 C; we use the bounded,
order-preserving r = DisR / (DisR + DisG) in [0, 1] (the denominator is never below the red-green
distance, 360.6) and T = temp_high - (temp_high - temp_low) * r: red -> temp_high, green ->
temp_low. Neutral colours land mid-range (42.5 C) and films at 41-45 C, above a 40 C device: the
chair plays its limit. The ``neutral_aware`` option pulls desaturated colours to ``neutral_c``.

neutral_aware (decision): r = 1/2 exactly when green = red (DisR^2 - DisG^2 = 510 (G - R)), which
includes every grey. The option first re-maps r piecewise-linearly so that r = 1/2 lands on
``neutral_c`` (r = 0 -> temp_high, r = 1 -> temp_low), then pulls towards ``neutral_c`` by chroma.
Then adding red never cools: it raises the re-mapped temperature and, when the colour is on the
cold side (R < G), it can only lower the chroma, i.e. pull a cold value up.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar

import numpy as np

from autohaptics.errors import ParameterError
from autohaptics.records import DERIVE, Record, param
from autohaptics.layout import (DEVICE_TEMP_MAX_C, DEVICE_TEMP_MIN_C, DEVICE_TEMP_RATE_C_PER_S, TEMP_HIGH_C,
                                TEMP_LOW_C, TEMP_NEUTRAL_C)
from autohaptics.temperature.colour import warmth
from autohaptics.temperature.device import DeviceProfile, played_curve, slew_limit
from autohaptics.temperature.warmcool import warmcool_target

_RED = np.array([255.0, 0.0, 0.0])
_GREEN = np.array([0.0, 255.0, 0.0])


MAPPINGS = ("warmcool", "thesis")


@dataclass(frozen=True)
class ThermalParams(Record):
    """Colour-to-temperature mapping: the default warm-cool mapping around a skin-neutral
    temperature in the device's range, or the thesis's red/green rule (GUIDE section 4, Temperature).

    mapping : "warmcool" (default: warm-cool around ``neutral_c`` in the device's range) or
        "thesis" (the thesis's red/green rule between ``temp_low`` and ``temp_high``).
    neutral_c : skin-neutral temperature, C (default 33): greys, black and white map here.
    device_min_c, device_max_c, device_rate_c_per_s : the device profile the curve is made for
        (safe range, C, and setpoint rate, C/s; defaults 18, 40, 1 as the chair's firmware).
    fill : share of the warm (cool) headroom that the film's strong warm (cool) scenes reach, 0..1.
    quantile : which of a side's ticks set its scale (0.95: the strongest 5 % reach ``fill`` or more).
    min_scale : smallest scale (warm-cool units; sRGB red is 2.1): paler films stay nearer neutral.
    hue_offset : moves the warm/cool hue boundary (0 = Ou et al.'s model; 0.25 makes green cool).
    temp_low, temp_high : thesis mapping, target temperatures (C) of pure green and pure red.
    neutral_aware : thesis mapping, greys map to ``neutral_c`` and desaturated colours are pulled
        towards it.
    chroma_low, chroma_high : thesis mapping with neutral_aware, chroma (max - min channel,
        0..255) below which a colour is fully neutral and above which it keeps its full temperature.
    slew_c_per_s : thesis mapping, rate limit of the generated curve, C per second (None = none;
        the warmcool curve is always limited at ``device_rate_c_per_s``).
    """

    STAGE: ClassVar[str] = DERIVE
    GROUP: ClassVar[str] = "thermal"

    mapping: str = param("warmcool", choices=MAPPINGS)
    neutral_c: float = param(TEMP_NEUTRAL_C, -20.0, 80.0, unit="C")
    # the device profile (temperature.DeviceProfile's fields, named for the generator)
    device_min_c: float = param(DEVICE_TEMP_MIN_C, -20.0, 80.0, unit="C")
    device_max_c: float = param(DEVICE_TEMP_MAX_C, -20.0, 80.0, unit="C")
    device_rate_c_per_s: float = param(DEVICE_TEMP_RATE_C_PER_S, hi=100.0, gt=0.0, unit="C/s")
    # the warm-cool measure and the film's scaling
    fill: float = param(0.85, hi=1.0, gt=0.0)
    quantile: float = param(0.95, 0.5, 1.0)
    min_scale: float = param(0.5, hi=1e6, gt=0.0)
    hue_offset: float = param(0.25, -1.0, 1.0)
    # the thesis mapping
    temp_low: float = param(TEMP_LOW_C, -20.0, 80.0, unit="C")
    temp_high: float = param(TEMP_HIGH_C, -20.0, 80.0, unit="C")
    neutral_aware: bool = False
    chroma_low: float = param(20.0, 0.0, 255.0)
    chroma_high: float = param(90.0, 0.0, 255.0)
    slew_c_per_s: float | None = param(None, hi=1e6, gt=0.0, unit="C/s")

    def check(self) -> None:
        if not self.temp_low < self.temp_high:
            raise ParameterError(f"thermal needs temp_low < temp_high, got {self.temp_low}, {self.temp_high} C")
        if not self.chroma_low < self.chroma_high:
            raise ParameterError(f"thermal needs chroma_low < chroma_high, got {self.chroma_low}, {self.chroma_high}")
        if not self.device_min_c < self.device_max_c:
            raise ParameterError("thermal needs device_min_c < device_max_c, "
                                 f"got {self.device_min_c}, {self.device_max_c} C")
        lo, hi = self.range_c
        if not (lo <= self.neutral_c <= hi):
            raise ParameterError(f"thermal.neutral_c must lie in [{lo:g}, {hi:g}] C (the {self.mapping} mapping's "
                                 f"range), got {self.neutral_c}")
        if self.fill == 1.0 or abs(self.hue_offset) == 1.0:
            raise ParameterError(f"thermal needs fill < 1 and -1 < hue_offset < 1, got {self.fill}, {self.hue_offset}")

    @property
    def range_c(self) -> tuple[float, float]:
        """(low, high) C that the generated curve stays in: the device's range (warmcool) or
        temp_low..temp_high (thesis); the timeline records it as ``temp_low``/``temp_high``."""
        if self.mapping == "thesis":
            return float(self.temp_low), float(self.temp_high)
        return float(self.device_min_c), float(self.device_max_c)

    @property
    def device(self) -> DeviceProfile:
        """The device profile the curve is made for."""
        return DeviceProfile(self.device_min_c, self.device_max_c, self.neutral_c, self.device_rate_c_per_s)


def warmth_ratio(mean_rgb: np.ndarray) -> np.ndarray:
    """r = DisR / (DisR + DisG) in [0, 1] (0 = pure red, 1 = pure green). [shape=(..., 3)] -> [shape=(...,)]."""
    c = np.clip(np.nan_to_num(np.asarray(mean_rgb, dtype=np.float64)), 0.0, 255.0)
    dis_r = np.linalg.norm(c - _RED, axis=-1)
    dis_g = np.linalg.norm(c - _GREEN, axis=-1)
    return dis_r / (dis_r + dis_g)  # dis_r + dis_g >= |RED - GREEN| = 360.6 > 0


def temperature_target(mean_rgb: np.ndarray, *, params: ThermalParams = ThermalParams()) -> np.ndarray:
    """The thesis mapping's target temperature per tick, C (whatever ``params.mapping`` says). mean_rgb float [shape=(n, 3)] (or (3,)) -> [shape=(n,)] (or scalar).

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


def temperature_track(mean_rgb: np.ndarray, *, params: ThermalParams = ThermalParams(),
                      tick_s: float = 0.1) -> tuple[np.ndarray, np.ndarray, dict]:
    """The generated temperature curve of each tick's mean colour [shape=(n, 3)], 0..255.

    Returns (curve, target, stats): curve C [shape=(n,)] within ``params.range_c``; target, the
    mapping before any rate limit; stats {"mapping", and for warmcool "warm_scale", "cool_scale"}.
    warmcool: the curve is what the chair plays (slew-limited from neutral at the device's rate);
    thesis: rate-limited only when ``params.slew_c_per_s`` is set.
    """
    rgb = np.asarray(mean_rgb, dtype=np.float64)
    if params.mapping == "warmcool":
        target, stats = warmcool_target(warmth(rgb, hue_offset=params.hue_offset), neutral_c=params.neutral_c,
                                        min_c=params.device_min_c, max_c=params.device_max_c, fill=params.fill,
                                        quantile=params.quantile, min_scale=params.min_scale)
        return played_curve(target, params.device, tick_s=tick_s), target, {"mapping": "warmcool", **stats}
    target = temperature_target(rgb, params=params)
    curve = target
    if params.slew_c_per_s:
        curve = slew_limit(target, max_rate_c_per_s=params.slew_c_per_s, tick_s=tick_s)
    return np.clip(curve, float(params.temp_low), float(params.temp_high)), target, {"mapping": "thesis"}
