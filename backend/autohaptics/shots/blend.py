"""Where a found cross-dissolve lies (:func:`autohaptics.shots.detect`'s dissolves): its span
widened to the contrast dip it sits in, and the row where it is half one shot, half the other.

A dissolve is read on the thumbnails as 3 x 4 block means (:func:`coarse`): a blend of two shots
is a blend at any scale, while the shots' own motion moves little at this one. Each row of the
span is fitted as ``a * first + b * last + c`` (the span's outer rows, c a flat picture):

- a plain dissolve (a + b about 1 throughout): the boundary is where the blend weight (each row
  projected on the line between the outer rows) crosses 0.5;
- a dissolve through a third picture (a haze, a glare: a + b below ``haze_weight`` somewhere, so
  neither shot dominates there): placed like a fade through a flat picture, midway between where
  a falls through 0.5 and where b rises through it.
"""

from __future__ import annotations

import numpy as np

from autohaptics.airflow import cuts

GROWTH = 0.01  # the contrast grows by more than this share within two rows: still the dip's ramp


def coarse(sigs: np.ndarray) -> np.ndarray:
    """The thumbnails of colour signatures [shape=(n, 192)] as 3 x 4 block means, float64
    [shape=(n, 12)]."""
    th = cuts.thumbnails(sigs).reshape(-1, 3, 3, 4, 4)
    return th.mean(axis=(2, 4), dtype=np.float64).reshape(-1, 12)


def widened(level: np.ndarray, usable: np.ndarray, s0: int, s1: int, max_ramp: int) -> tuple[int, int]:
    """The span [s0, s1) of a found dissolve widened to the contrast dip it sits in: from the
    lowest contrast (``level``, the thumbnail standard deviation) in the span, or downhill from
    there up to the span's length away, outward while the contrast still grows (:data:`GROWTH`),
    at most ``max_ramp`` rows a side, over ``usable`` rows only. Why: a blend has less contrast
    than its shots (unless one is much flatter), and where only its end reads as linear (the
    shots move through it) the dip still shows where it starts."""
    lv = np.where(usable, level, np.nan)
    if not np.isfinite(lv[s0:s1]).any():
        return s0, s1
    m = s0 + int(np.nanargmin(lv[s0:s1]))
    for step in (-1, 1):
        j = m
        while abs(j + step - m) <= s1 - s0 and 0 <= j + step < lv.size and lv[j + step] < lv[j]:
            j += step
        if j != m:
            m = j
            break
    ends = []
    for step in (-1, 1):
        j = m
        while abs(j - m) < max_ramp and _grows(lv, j, step):
            j += step
        ends.append(j)
    return min(s0, ends[0]), max(s1, ends[1] + 1)


def _grows(lv: np.ndarray, j: int, step: int) -> bool:
    """The contrast one or two rows on from row j (by ``step``) is above row j's by GROWTH."""
    a, b = j + step, j + 2 * step
    if not (0 <= a < lv.size and np.isfinite(lv[a])):
        return False
    far = lv[b] if 0 <= b < lv.size and np.isfinite(lv[b]) else lv[a]
    return bool(max(lv[a], far) > (1.0 + GROWTH) * lv[j])


def half_way(blocks: np.ndarray, pa: int, pb: int, k: int, fallback: float, haze_weight: float) -> float:
    """Where the dissolve over rows ``pa``..``pb`` is half-way (module docstring), in rows, the
    crossing nearest row ``k`` interpolated between rows; ``fallback`` where it never crosses."""
    t = np.arange(pa, pb + 1)
    rows = blocks[t]
    fit = np.linalg.lstsq(np.stack([blocks[pa], blocks[pb], np.ones(blocks.shape[1])], axis=1),
                          rows.T, rcond=None)[0]
    if float((fit[0] + fit[1]).min()) < haze_weight:
        out, into = _crossing(1.0 - fit[0], t, k), _crossing(fit[1], t, k)
        if out is not None and into is not None:
            return 0.5 * (out + into)
    d = blocks[pb] - blocks[pa]
    w = (rows - blocks[pa]) @ d / max(float(d @ d), 1e-9)
    at = _crossing(w, t, k)
    return fallback if at is None else at


def _crossing(w: np.ndarray, t: np.ndarray, k: int) -> float | None:
    """Where ``w`` (over rows ``t``) rises through 0.5, the crossing nearest row k, or None."""
    up = np.flatnonzero((w[:-1] < 0.5) & (w[1:] >= 0.5))
    if not up.size:
        return None
    j = int(up[np.argmin(np.abs(t[up] - k))])
    return float(t[j] + (0.5 - w[j]) / (w[j + 1] - w[j]))


def between(best_r: np.ndarray, k: int) -> float:
    """Where the picture is half one shot and half the other, in rows, near row ``k`` (the row
    with the lowest residual ``best_r`` against its window's ends): the residual is V-shaped
    around the dissolve's middle, so its vertex between the neighbours places the middle."""
    r0 = best_r[k]
    rl = best_r[k - 1] if k > 0 else np.inf
    rr = best_r[k + 1] if k + 1 < best_r.size else np.inf
    offset = 0.0
    if np.isfinite(rl) and np.isfinite(rr) and max(rl, rr) - r0 > 1e-9:
        offset = 0.5 * (rl - rr) / (max(rl, rr) - r0)
    return k + offset
