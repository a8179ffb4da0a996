"""Per-shot summaries: what the composed timeline and the analysis hold over each shot's ticks."""

from __future__ import annotations

import numpy as np

from autohaptics.errors import ParameterError
from autohaptics.timebase import FRAMES_PER_TICK


def summarise(t0: np.ndarray, t1: np.ndarray, *, vibration: np.ndarray, temperature_c: np.ndarray,
              fans: np.ndarray, loudness: np.ndarray | None = None, mean_rgb: np.ndarray | None = None,
              motion: np.ndarray | None = None) -> dict[str, np.ndarray | None]:
    """Each shot ``[t0, t1)``'s summary, one value per shot [shape=(m,)] (None where the input is).

    vibration : (n, 9) 0..1 -> ``vibration_mean`` and ``vibration_peak`` of the strongest
        actuator per tick. temperature_c : (n,) C -> ``temperature_mean_c``.
    fans : (n, 9, 17) 0..1 -> ``fans_share``, the share of ticks with any fan on.
    loudness : (n * 5,) sone on the 20 ms grid -> ``loudness_sone``, the mean of each tick's
        loudest frame. mean_rgb : (n, 3) 0..255 -> ``colour`` (m, 3), the shot's mean colour.
    motion : (n,) frame widths/s -> ``motion``, the mean.
    Shots must tile the film: t0[0] == 0, t1[i] == t0[i + 1], t1[-1] == n.
    """
    n = int(np.asarray(temperature_c).shape[0])
    t0, t1 = np.asarray(t0, np.int64), np.asarray(t1, np.int64)
    if t0.size == 0 or t0[0] != 0 or t1[-1] != n or (t0[1:] != t1[:-1]).any() or (t1 <= t0).any():
        raise ParameterError(f"shots must tile the film's {n} ticks in order")
    length = (t1 - t0).astype(np.float64)

    def mean(per_tick):
        return np.add.reduceat(np.asarray(per_tick, np.float64), t0, axis=0) / length.reshape(
            (-1,) + (1,) * (np.ndim(per_tick) - 1))

    strongest = np.asarray(vibration, np.float32).max(axis=1) if n else np.zeros(0, np.float32)
    fans_on = np.asarray(fans).reshape(n, -1).max(axis=1) > 0
    out: dict[str, np.ndarray | None] = {
        "vibration_mean": mean(strongest),
        "vibration_peak": np.maximum.reduceat(strongest, t0).astype(np.float64),
        "temperature_mean_c": mean(temperature_c),
        "fans_share": mean(fans_on),
        "loudness_sone": None, "colour": None, "motion": None,
    }
    per_tick = tick_loudness(loudness, n)
    if per_tick is not None:
        out["loudness_sone"] = mean(per_tick)
    if mean_rgb is not None:
        out["colour"] = mean(mean_rgb)
    if motion is not None:
        out["motion"] = mean(motion)
    return out


def tick_loudness(loudness: np.ndarray | None, n: int) -> np.ndarray | None:
    """Each tick's loudest 20 ms frame, sone [shape=(n,)]; None without (enough) loudness."""
    if loudness is None or np.asarray(loudness).size < n * FRAMES_PER_TICK:
        return None
    return np.asarray(loudness)[:n * FRAMES_PER_TICK].reshape(n, FRAMES_PER_TICK).max(axis=1)
