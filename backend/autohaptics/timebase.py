"""Every time <-> frame <-> tick conversion lives here (ALGORITHM.md section 1).

- Output tick: ``TICK_S`` = 0.1 s; tick k covers [0.1 k, 0.1 (k + 1)) s.
- Audio feature frame: ``FRAME_S`` = 0.02 s, ``FRAMES_PER_TICK`` = 5 frames per tick.
- A clip of duration d s has ceil(d / 0.1) ticks; no stage invents its own count.
"""

from __future__ import annotations

import math

import numpy as np

from autohaptics.errors import ParameterError

TICK_S = 0.1
FRAME_S = 0.02
FRAMES_PER_TICK = 5
TICK_HZ = 10.0
FRAME_HZ = 50.0
ANALYSIS_SAMPLE_RATE = 48_000  # Hz; ISO 532-1 is defined at 48 kHz
SAMPLES_PER_FRAME = 960  # 20 ms at 48 kHz

# Durations are read from containers with a few microseconds of rounding noise
# (52.6630000001 s must give 527 ticks, not 528).
_EPS = 1e-6


def n_ticks(duration_s: float) -> int:
    """Number of 100 ms ticks for a clip of ``duration_s`` seconds: ceil(d / 0.1), at least 1.

    Raises ParameterError for a non-finite or non-positive duration (an empty clip is an
    error, never 0 ticks).
    """
    if not math.isfinite(duration_s) or duration_s <= 0:
        raise ParameterError(f"duration must be a positive number of seconds, got {duration_s!r}")
    return max(1, math.ceil(duration_s / TICK_S - _EPS))


def n_frames(duration_s: float) -> int:
    """Number of 20 ms audio feature frames covering ``n_ticks(duration_s)`` ticks exactly."""
    return n_ticks(duration_s) * FRAMES_PER_TICK


def tick_start_s(k: np.ndarray | int) -> np.ndarray | float:
    """Start time in seconds of tick ``k`` (k * 0.1)."""
    return np.asarray(k) * TICK_S if not isinstance(k, int) else k * TICK_S


def tick_of_time(t_s: np.ndarray | float) -> np.ndarray | int:
    """Index of the tick that holds time ``t_s`` (seconds), floor(t / 0.1) with rounding tolerance."""
    if np.ndim(t_s) == 0:
        return int(math.floor(float(t_s) / TICK_S + _EPS))
    return np.floor(np.asarray(t_s, dtype=np.float64) / TICK_S + _EPS).astype(np.int64)


def frame_times_s(n: int) -> np.ndarray:
    """Start times (s) of ``n`` consecutive 20 ms frames, shape (n,)."""
    return np.arange(n, dtype=np.float64) * FRAME_S


def tick_times_s(n: int) -> np.ndarray:
    """Start times (s) of ``n`` consecutive ticks, shape (n,)."""
    return np.arange(n, dtype=np.float64) * TICK_S


def fit_length(x: np.ndarray, n: int, *, fill: float = 0.0) -> np.ndarray:
    """Cut or pad ``x`` along axis 0 to exactly ``n`` rows (padding with ``fill``)."""
    x = np.asarray(x)
    if x.shape[0] == n:
        return x
    if x.shape[0] > n:
        return x[:n]
    pad = np.full((n - x.shape[0],) + x.shape[1:], fill, dtype=x.dtype)
    return np.concatenate([x, pad], axis=0)


def frames_to_ticks(x: np.ndarray, n_ticks_out: int) -> np.ndarray:
    """Aggregate 20 ms frame values to 100 ms ticks by the MAX of each tick's five frames.

    x : np.ndarray [shape=(n_frames, ...)]; missing trailing frames count as 0 (silence).
    Returns [shape=(n_ticks_out, ...)], same dtype. A 20 ms gunshot is not averaged away.
    """
    x = fit_length(np.asarray(x), n_ticks_out * FRAMES_PER_TICK)
    out = x[0::FRAMES_PER_TICK].copy()  # strided maxima: ~5x faster than a max over a length-5 axis
    for k in range(1, FRAMES_PER_TICK):
        np.maximum(out, x[k::FRAMES_PER_TICK], out=out)
    return out
