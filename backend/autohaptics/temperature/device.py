"""What a thermal element can play: its safe range, its neutral point and its rate of change
(ALGORITHM.md section 4).

55 C on skin burns: a device profile clamps the target to its own safe range (default 18..40 C),
and a heater takes seconds to change, so the curve is rate-limited (default 1 C/s, the firmware's
``AH_TEMP_RATE_CC_PER_S``). :func:`played_curve` is what the chair plays for a target curve: the
editor draws it, the exporters write it, and the default mapping produces it.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from autohaptics.errors import ParameterError
from autohaptics.layout import DEVICE_TEMP_MAX_C, DEVICE_TEMP_MIN_C, DEVICE_TEMP_RATE_C_PER_S, TEMP_NEUTRAL_C
from autohaptics.timebase import TICK_S

# Curves are stored with 4 decimals (Timeline.write): a step this much over the slew limit is the
# rounding of a curve that was already limited, not a step to limit again.
CURVE_SLACK_C = 2e-4


@dataclass(frozen=True)
class DeviceProfile:
    """A chair's thermal element, degrees C: safe range, neutral point (what it returns to when
    idle or stopped) and the rate its setpoint follows, C per second (from its HELLO)."""

    temp_min_c: float = DEVICE_TEMP_MIN_C
    temp_max_c: float = DEVICE_TEMP_MAX_C
    temp_neutral_c: float = TEMP_NEUTRAL_C
    temp_rate_c_per_s: float = DEVICE_TEMP_RATE_C_PER_S

    def __post_init__(self) -> None:
        lo, hi, neu, rate = self.temp_min_c, self.temp_max_c, self.temp_neutral_c, self.temp_rate_c_per_s
        if not all(math.isfinite(v) for v in (lo, hi, neu)) or not lo <= neu <= hi:
            raise ParameterError(f"device profile needs finite temp_min <= neutral <= temp_max, got {lo}, {neu}, {hi}")
        if not (math.isfinite(rate) and rate > 0):
            raise ParameterError(f"device profile needs a positive temperature rate (C/s), got {rate}")

    @classmethod
    def from_hello(cls, hello) -> "DeviceProfile":
        """The profile a chair reports in its HELLO (:class:`~autohaptics.chair.messages.Hello`)."""
        return cls(hello.temp_min_c, hello.temp_max_c, hello.temp_neutral_c, hello.temp_rate_c_per_s)


def profile_of(generator_params: dict) -> DeviceProfile:
    """The device profile a timeline was made for, from its ``generator.params`` (``thermal``'s
    device_min_c, device_max_c, neutral_c, device_rate_c_per_s); the defaults where absent."""
    thermal = generator_params.get("thermal") if isinstance(generator_params, dict) else None
    thermal = thermal if isinstance(thermal, dict) else {}
    default = DeviceProfile()
    values = [thermal.get(key, fallback) for key, fallback in (
        ("device_min_c", default.temp_min_c), ("device_max_c", default.temp_max_c),
        ("neutral_c", default.temp_neutral_c), ("device_rate_c_per_s", default.temp_rate_c_per_s))]
    try:
        return DeviceProfile(*(float(v) for v in values))
    except (TypeError, ValueError):
        raise ParameterError(f"generator.params.thermal has a device profile that is not numbers: {values}") from None


def slew_limit(temps: np.ndarray, *, max_rate_c_per_s: float, tick_s: float = TICK_S,
               start_c: float | None = None, slack_c: float = 0.0) -> np.ndarray:
    """Limit the change between consecutive ticks to ``max_rate_c_per_s * tick_s``.

    temps float [shape=(n,)], C. start_c : the element's temperature before tick 0 (default temps[0]).
    slack_c : a change at most this much over the limit is kept as it is (idempotence on a limited
    curve that was rounded since).
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
        delta = target - cur
        cur = target if abs(delta) <= step + slack_c else cur + math.copysign(step, delta)
        out[i] = cur
    return out


def clamp_to_device(temps: np.ndarray, *, min_c: float = DEVICE_TEMP_MIN_C, max_c: float = DEVICE_TEMP_MAX_C) -> np.ndarray:
    """Clamp a target curve to a device's safe range (default 18..40 C); NaN reads as neutral."""
    if not min_c <= max_c:
        raise ParameterError(f"device range must have min <= max, got {min_c}, {max_c}")
    return np.clip(np.nan_to_num(np.asarray(temps, dtype=np.float64), nan=TEMP_NEUTRAL_C), min_c, max_c)


def played_curve(temps: np.ndarray, profile: DeviceProfile = DeviceProfile(), *, tick_s: float = TICK_S) -> np.ndarray:
    """What the chair plays for a target curve, C [shape=(n,)]: clamped to the profile's range,
    then slew-limited at its rate from its neutral point (where an idle chair sits at tick 0).

    Idempotent on its own output, also after rounding to 4 decimals (:data:`CURVE_SLACK_C`).
    """
    clamped = clamp_to_device(temps, min_c=profile.temp_min_c, max_c=profile.temp_max_c)
    return slew_limit(clamped, max_rate_c_per_s=profile.temp_rate_c_per_s, tick_s=tick_s,
                      start_c=profile.temp_neutral_c, slack_c=CURVE_SLACK_C)
