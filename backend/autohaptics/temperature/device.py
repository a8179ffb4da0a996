"""What a thermal element can play: its safe range and its rate of change (ALGORITHM.md section 4).

55 C on skin burns: a device profile clamps the target to its own safe range (default 18..40 C),
and a heater takes seconds to change, so the curve is rate-limited.
"""

from __future__ import annotations

import numpy as np

from autohaptics.errors import ParameterError
from autohaptics.layout import DEVICE_TEMP_MAX_C, DEVICE_TEMP_MIN_C, DEVICE_TEMP_RATE_C_PER_S, TEMP_NEUTRAL_C


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


def chair_curve(temps: np.ndarray, *, min_c: float = DEVICE_TEMP_MIN_C, max_c: float = DEVICE_TEMP_MAX_C,
                rate_c_per_s: float = DEVICE_TEMP_RATE_C_PER_S, tick_s: float = 0.1,
                start_c: float = TEMP_NEUTRAL_C) -> np.ndarray:
    """What a chair's element plays for a target curve: clamped to its safe range, then moved at most
    ``rate_c_per_s`` from ``start_c`` (a chair idles at neutral), as the firmware does (PROTOCOL.md).

    temps float [shape=(n,)], C -> float [shape=(n,)], C, inside [min_c, max_c] once it got there.
    """
    return slew_limit(clamp_to_device(temps, min_c=min_c, max_c=max_c), max_rate_c_per_s=rate_c_per_s,
                      tick_s=tick_s, start_c=start_c)

