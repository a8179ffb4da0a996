"""Medians, percentiles and quantiles exactly as numpy computes them (its default, "linear" method),
without the masked-array module numpy imports on the first ``median`` or ``percentile`` call (a NaN
check and ``np.unique``): 11 ms of every process's first analysis, on the main thread before the
video pass and again in the audio pass (docs/BENCHMARKS.md, "Full-frame 1080p", tenth stop). The
same numbers, bit for bit (tests/test_quantiles.py); finite values only.
"""

from __future__ import annotations

import numpy as np


def percentile(x, q):
    """``np.percentile(x, q)``: ``q`` in 0..100, a number (-> a float64 number) or a sequence (->
    float64 [shape=(len(q),)]), of the finite float64 or integer values of ``x`` (any shape,
    flattened; not empty)."""
    return _quantile(x, np.true_divide(q, 100))


def quantile(x, q):
    """``np.quantile(x, q)``: as :func:`percentile` with ``q`` in 0..1."""
    return _quantile(x, np.asanyarray(q))


def median(x, axis: int | None = None):
    """``np.median(x, axis)`` of finite values: the middle value, or the mean of the middle two."""
    a = np.asanyarray(x)
    if axis is None:
        a, axis = a.ravel(), 0
    n = a.shape[axis]
    half = n // 2
    part = np.partition(a, [half] if n % 2 else [half - 1, half], axis=axis)
    middle = [slice(None)] * a.ndim
    middle[axis] = slice(half, half + 1) if n % 2 else slice(half - 1, half + 1)
    return np.mean(part[tuple(middle)], axis=axis)


def _quantile(x, q: np.ndarray):
    a = np.array(x).ravel()  # a copy, partitioned in place
    n = a.size
    virtual = np.asanyarray((n - 1) * q)
    lower = np.floor(virtual)
    upper = lower + 1
    top, bottom = virtual >= n - 1, virtual < 0
    lower, upper = np.where(top, -1, np.where(bottom, 0, lower)), np.where(top, -1, np.where(bottom, 0, upper))
    lower, upper = lower.astype(np.intp), upper.astype(np.intp)
    a.partition(sorted({0, n - 1, *(lower % n).ravel().tolist(), *(upper % n).ravel().tolist()}))
    below, above = a[lower], a[upper]
    gamma = np.asanyarray(virtual - lower, dtype=virtual.dtype)
    step = above - below
    out = np.asanyarray(below + step * gamma)
    out = np.where(gamma >= 0.5, above - step * (1 - gamma), out)
    return out[()] if out.ndim == 0 else out
