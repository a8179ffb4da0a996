"""Area averaging of uint8 planes, the same bytes OpenCV's ``INTER_AREA`` gives, faster.

OpenCV's area resize has a fast path for whole ratios only. A fractional ratio (854 -> 160 px:
5.34) walks a table of (source pixel, output pixel, weight) entries one pixel at a time, and on
the proxies of a 480p film that was the video pass's largest cost after optical flow
(docs/BENCHMARKS.md, "Full-frame 1080p", tenth stop). :func:`area_rows` walks the same table,
with the same float32 products and sums in the same order, over whole rows at once (a compiled
kernel, :mod:`.area_kernels`): five times faster on those planes. Where the kernel cannot be
built, OpenCV computes it.
"""

from __future__ import annotations

import functools
import math

import cv2
import numpy as np

from autohaptics.aot import KernelSet

KERNELS = KernelSet("ahimaging", "autohaptics.media.area_kernels",
                    {"area_rows": "void(u1[:,:], i8[:], i8[:], f4[:], u1[:,:])"}, host_cpu=True)


def area_resize(arr: np.ndarray, size: tuple[int, int]) -> np.ndarray:
    """Area-average uint8 ``arr`` to ``size`` (w, h). OpenCV's area resize has a fast path for whole
    ratios only; a downscale with a fractional ratio (960x540 -> 64x64: 15 x 8.44) runs one axis
    at a time instead (measured on 1080p frames: 0.25 instead of 1.2-1.4 ms, within a grey level
    of the one-pass result), each axis as OpenCV's own area pass (:func:`area_rows`). An upscale
    falls back to bilinear."""
    w, h = int(size[0]), int(size[1])
    ah, aw = arr.shape[:2]
    if w > aw or h > ah:
        return cv2.resize(arr, (w, h), interpolation=cv2.INTER_LINEAR if (w > aw and h > ah) else cv2.INTER_AREA)
    if aw % w == 0 and ah % h == 0:
        return cv2.resize(arr, (w, h), interpolation=cv2.INTER_AREA)
    if arr.ndim != 2 or arr.dtype != np.uint8:
        return cv2.resize(cv2.resize(arr, (w, ah), interpolation=cv2.INTER_AREA), (w, h), interpolation=cv2.INTER_AREA)
    across = cv2.resize(arr, (w, ah), interpolation=cv2.INTER_AREA) if aw % w == 0 else \
        cv2.transpose(area_rows(cv2.transpose(arr), w))
    return area_rows(across, h)


def area_rows(arr: np.ndarray, n: int) -> np.ndarray:
    """uint8 ``arr`` [shape=(rows, m)] area-averaged to ``n`` <= rows rows: the bytes of
    ``cv2.resize(arr, (m, n), interpolation=cv2.INTER_AREA)``."""
    rows, m = arr.shape
    run = kernel()
    if rows % n == 0 or run is None:  # a whole ratio is OpenCV's fast path (integer sums)
        return cv2.resize(arr, (m, n), interpolation=cv2.INTER_AREA)
    si, di, weight = area_table(rows, n)
    out = np.empty((n, m), np.uint8)
    run(np.ascontiguousarray(arr), si, di, weight, out)
    return out


@functools.lru_cache(maxsize=64)
def area_table(n_in: int, n_out: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """OpenCV's table of an area pass from ``n_in`` to ``n_out`` < ``n_in`` pixels: (source index,
    output index, weight) of each entry, int64, int64, float32, by output then source; each
    output's weights are its source pixels' shares of it (a cut pixel counts by its share)."""
    scale = 1.0 / (n_out / n_in)  # as OpenCV derives it, from the inverse scale
    si, di, weight = [], [], []
    for d in range(n_out):
        lo = d * scale
        hi = lo + scale
        cell = min(scale, n_in - lo)
        first, last = math.ceil(lo), math.floor(hi)
        last = min(last, n_in - 1)
        first = min(first, last)
        if first - lo > 1e-3:
            si.append(first - 1), di.append(d), weight.append((first - lo) / cell)
        for s in range(first, last):
            si.append(s), di.append(d), weight.append(1.0 / cell)
        if hi - last > 1e-3:
            si.append(last), di.append(d), weight.append(min(min(hi - last, 1.0), cell) / cell)
    tables = np.array(si, np.int64), np.array(di, np.int64), np.array(weight, np.float32)
    for t in tables:
        t.setflags(write=False)
    return tables


@functools.cache
def kernel():
    """The compiled :func:`.area_kernels.area_rows`, or None where it cannot be built."""
    try:
        return KERNELS.built().area_rows
    except Exception:  # no C compiler, no numba: OpenCV computes the same bytes
        return None
