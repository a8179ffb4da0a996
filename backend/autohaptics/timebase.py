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


def gaussian_taps(sigma: float) -> tuple[np.ndarray, np.ndarray]:
    """Offsets -r..r (r = ceil(3 sigma), 0 for sigma <= 0) and their Gaussian weights, summing to 1."""
    r = int(math.ceil(3.0 * sigma)) if sigma > 0 else 0
    offsets = np.arange(-r, r + 1)
    if not r:
        return offsets, np.ones(1)
    with np.errstate(over="ignore"):  # a tiny sigma: the neighbours' weights underflow to 0
        g = np.exp(-0.5 * (offsets / sigma) ** 2)
    return offsets, g / g.sum()


def shot_smoothed(values: np.ndarray, shot: np.ndarray, ticks: np.ndarray, sigma_ticks: float, *,
                  mask: np.ndarray | None = None, mean: bool = False) -> np.ndarray:
    """``values`` of ``ticks`` smoothed over the ticks of their shot: float64 [shape=(len(ticks), ...)].

    values : [shape=(n, ...)] per tick (non-finite values count as 0); shot : int [shape=(n,)], each
    tick's shot number (negative: a tick that takes no part, such as a cut); ticks : int [shape=(m,)].
    Each tick's result is the Gaussian-weighted sum (std ``sigma_ticks``) over the ticks around it of
    its own shot where ``mask`` (bool [shape=(n,)], default all) holds, a tick elsewhere or beyond the
    clip counting as 0; with ``mean`` the weights are renormalised over the ticks that count. The
    tick itself always counts. Element-wise sums in a fixed order: a tick's result does not depend on
    which other ticks are asked for.
    """
    x = np.asarray(values)
    shot = np.asarray(shot)
    ticks = np.asarray(ticks, dtype=np.int64)
    n = x.shape[0] if x.ndim else 0
    if x.ndim < 1 or shot.shape != (n,) or (mask is not None and np.shape(mask) != (n,)):
        raise ParameterError(f"shot_smoothed needs (n, ...) values and (n,) shots and mask, got {x.shape}, "
                             f"{shot.shape} and {None if mask is None else np.shape(mask)}")
    if ticks.size and (ticks.min() < 0 or ticks.max() >= n):
        raise ParameterError(f"ticks must lie in 0..{n - 1}")
    mask = None if mask is None else np.asarray(mask, bool)
    offsets, gauss = gaussian_taps(float(sigma_ticks))
    total = np.zeros((ticks.size,) + x.shape[1:], np.float64)
    weight = np.zeros(ticks.size, np.float64)
    own = shot[ticks] if ticks.size else np.zeros(0, shot.dtype)
    spread = (-1,) + (1,) * (x.ndim - 1)
    for d, g in zip(offsets, gauss):
        src = np.clip(ticks + d, 0, n - 1)
        ok = ((ticks + d) >= 0) & ((ticks + d) < n) & (shot[src] == own) & (shot[src] >= 0)
        if mask is not None:
            ok &= mask[src]
        if d == 0:
            ok = np.ones(ticks.size, bool)
        if ok.any():
            total += np.where(ok, g, 0.0).reshape(spread) * np.nan_to_num(x[src].astype(np.float64))
            weight += np.where(ok, g, 0.0)
    return total / np.maximum(weight, 1e-12).reshape(spread) if mean else total
