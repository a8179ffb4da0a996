"""The compiled inner loop of :mod:`.area` (numba): callers reach it through that module, which
loads it built ahead of time (:class:`autohaptics.aot.KernelSet`), without importing numba."""

from __future__ import annotations

import numba
import numpy as np


@numba.njit(cache=True, nogil=True)
def area_rows(src, si, di, weight, out):
    """out[d] = round(((w0 * src[s0]) + w1 * src[s1]) + ...) over the table entries (si, di,
    weight) of output row d, in table order, in float32, each row whole: OpenCV's area sums.

    src uint8 [shape=(n_in, m)]; si, di int64 [shape=(k,)] source and output row of each entry
    (di ascending); weight float32 [shape=(k,)]; out uint8 [shape=(n_out, m)], written.
    Rounded half to even and clamped to 0..255, as OpenCV's saturate_cast does.
    """
    m = src.shape[1]
    acc = np.zeros(m, np.float32)
    cur = -1
    for k in range(si.shape[0]):
        d, s, w = di[k], si[k], weight[k]
        if d != cur:
            if cur >= 0:
                _store(acc, out, cur)
            for j in range(m):
                acc[j] = np.float32(src[s, j]) * w
            cur = d
        else:
            for j in range(m):
                acc[j] += np.float32(src[s, j]) * w
    if cur >= 0:
        _store(acc, out, cur)


@numba.njit(cache=True, nogil=True)
def _store(acc, out, row):
    """out[row] = acc rounded half to even, clamped to 0..255."""
    for j in range(acc.shape[0]):
        out[row, j] = np.uint8(min(max(np.rint(acc[j]), np.float32(0.0)), np.float32(255.0)))
