"""Saliency -> spatial distribution over the nine actuators (ALGORITHM.md section 3, thesis 3.2).

Recipe per analysed frame:

1. salient shape: binarise the map, remove small noisy specks (the thesis filters "noisy salient edges");
2. for each of the 14 triangles holding salient pixels: the centroid C_i of those pixels;
3. alpha = 1 / distance(C_i, vertex) for each ACTUATOR vertex of the triangle (frame corners carry
   no actuator and get no weight); w = alpha / sum(alpha); a centroid on a vertex gives that vertex 1;
4. W_A = sum of w over the triangles around actuator A; beta = W / max(W) (strongest actuator = 1);
5. nothing salient: all weight on A5 (thesis 4.4.3).

``variant="paper"`` is exactly that. ``variant="mass"`` multiplies each triangle's w by its salient
mass (its share of the frame's salient pixels), so a speck no longer counts as much as a fully
salient triangle.

Binarisation (decision; the thesis used a CNN mask): a pixel is salient when its value is at least
``max(min_level, mean + k_std * std)`` of the map; then a morphological opening (3 x 3) and removal
of connected regions smaller than ``min_speck_area`` of the frame.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar
from functools import lru_cache

import cv2
import numpy as np

from autohaptics.errors import ParameterError
from autohaptics.records import ANALYSIS, DERIVE, Record, param
from autohaptics.layout import ACTUATOR_IDS, CENTRE_ACTUATOR, N_ACTUATORS, TRIANGLES, vertex_xy
from autohaptics.imaging import finite32

VARIANTS = ("paper", "mass")
_N_TRI = len(TRIANGLES)
# (14, 3) actuator index of each triangle vertex, -1 for a corner; (14, 3, 2) vertex coordinates
TRIANGLE_ACTUATORS = np.array([[ACTUATOR_IDS.index(v) if v.startswith("A") else -1 for v in tri] for tri in TRIANGLES])
TRIANGLE_XY = np.array([[vertex_xy(v) for v in tri] for tri in TRIANGLES], dtype=np.float64)
_VERTEX_EPS = 1e-9


@dataclass(frozen=True)
class FusionParams(Record):
    """How a saliency map becomes actuator weights.

    variant : "paper" (the thesis) | "mass" (triangles weighted by their salient mass).
    min_level : lowest map value (0..1) that can count as salient.
    k_std : a pixel is salient at mean + k_std * std of the map or above (and >= min_level).
    min_speck_area : connected salient regions smaller than this fraction of the frame are noise.
    sigma_ticks : an analysed tick's weights are the Gaussian-weighted mean (this std, ticks) of those
        of the analysed ticks of its shot around it, scaled to a strongest actuator of 1 (default 2;
        0 = its own frame's, the thesis; ``fusion.modes.smoothed_weights``).
    """

    STAGE: ClassVar[str] = ANALYSIS
    GROUP: ClassVar[str] = "fusion"

    variant: str = param("paper", choices=VARIANTS)
    min_level: float = param(0.3, 0.0, 1.0)
    k_std: float = param(1.5, -10.0, 10.0)
    min_speck_area: float = param(0.002, 0.0, 0.99)
    sigma_ticks: float = param(2.0, 0.0, 50.0, unit="ticks", stage=DERIVE)


def fallback_weights() -> np.ndarray:
    """All weight on A5: the rule when nothing is salient. float64 [shape=(9,)]."""
    beta = np.zeros(N_ACTUATORS)
    beta[ACTUATOR_IDS.index(CENTRE_ACTUATOR)] = 1.0
    return beta


def salient_shape(saliency: np.ndarray, *, params: FusionParams = FusionParams()) -> np.ndarray:
    """Binarised, de-specked saliency. saliency float [shape=(h, w)] in [0, 1] -> bool [shape=(h, w)]."""
    s = np.asarray(saliency, dtype=np.float32)
    if s.ndim != 2 or s.size == 0:
        raise ParameterError(f"a saliency map must be 2-D and non-empty, got shape {s.shape}")
    s = finite32(s)
    if float(s.max()) <= 0.0:
        return np.zeros(s.shape, bool)
    level = max(float(params.min_level), float(s.mean() + params.k_std * s.std()))
    mask = (s >= min(level, float(s.max()))).astype(np.uint8)
    h, w = mask.shape
    if min(h, w) >= 5:
        mask = cv2.morphologyEx(mask, cv2.MORPH_OPEN, np.ones((3, 3), np.uint8))
    min_px = params.min_speck_area * h * w
    if min_px >= 1 and mask.any():
        n, labels, st, _ = cv2.connectedComponentsWithStats(mask, connectivity=8)
        keep = np.zeros(n, bool)
        keep[1:] = st[1:, cv2.CC_STAT_AREA] >= min_px
        if not keep[1:].all():  # else every region stays: the mask as it is
            mask = keep[labels].astype(np.uint8)
    return mask.astype(bool)


@lru_cache(maxsize=32)
def triangle_index_map(h: int, w: int) -> np.ndarray:
    """Which triangle (0..13, T1 = 0) holds each pixel centre of an h x w frame. int8 [shape=(h, w)].

    A pixel centre on a shared edge belongs to the lower-numbered triangle.
    """
    if h < 1 or w < 1:
        raise ParameterError(f"frame size must be positive, got {h} x {w}")
    px = (np.arange(w) + 0.5) / w  # pixel centres, normalised
    py = (np.arange(h) + 0.5)[:, None] / h
    out = np.full((h, w), -1, np.int8)
    for i in range(_N_TRI):
        (x1, y1), (x2, y2), (x3, y3) = TRIANGLE_XY[i]
        # only the pixels around the triangle's bounding box are tested (the rest are outside it)
        c0, c1 = _span(min(x1, x2, x3), max(x1, x2, x3), w)
        r0, r1 = _span(min(y1, y2, y3), max(y1, y2, y3), h)
        x, y, cell = px[c0:c1], py[r0:r1], out[r0:r1, c0:c1]
        det = (y2 - y3) * (x1 - x3) + (x3 - x2) * (y1 - y3)
        l1 = ((y2 - y3) * (x - x3) + (x3 - x2) * (y - y3)) / det
        l2 = ((y3 - y1) * (x - x3) + (x1 - x3) * (y - y3)) / det
        l3 = 1.0 - l1 - l2
        cell[(l1 >= -1e-12) & (l2 >= -1e-12) & (l3 >= -1e-12) & (cell < 0)] = i
    out.setflags(write=False)
    return out


def _span(lo: float, hi: float, n: int) -> tuple[int, int]:
    """The pixels (first, end) of ``n`` whose centres may lie in lo..hi (normalised), a pixel to spare."""
    return max(0, int(np.floor(lo * n)) - 1), min(n, int(np.ceil(hi * n)) + 1)


def triangle_weights(centroid: tuple[float, float], triangle: int) -> np.ndarray:
    """Inverse-distance weights of one triangle's actuator vertices for a centroid (x, y).

    Returns float64 [shape=(9,)] summing to 1 over the triangle's actuators; a centroid on an
    actuator vertex gives that actuator 1 (no division by zero).
    """
    c = np.asarray(centroid, dtype=np.float64)
    w = np.zeros(N_ACTUATORS)
    acts = TRIANGLE_ACTUATORS[triangle]
    pts = TRIANGLE_XY[triangle]
    d = np.hypot(*(pts - c).T)
    real = acts >= 0
    hit = real & (d < _VERTEX_EPS)
    if hit.any():
        w[acts[np.argmax(hit)]] = 1.0
        return w
    alpha = np.where(real, 1.0 / np.maximum(d, _VERTEX_EPS), 0.0)
    alpha /= alpha.sum()
    for a, v in zip(acts, alpha):
        if a >= 0:
            w[a] += v
    return w


def _weights_of(centroids: np.ndarray, triangles: np.ndarray) -> np.ndarray:
    """:func:`triangle_weights` of many (centroid, triangle) pairs at once, the same values:
    centroids float [shape=(m, 2)], triangles int [shape=(m,)] -> float64 [shape=(m, 9)]."""
    acts = TRIANGLE_ACTUATORS[triangles]
    d = np.hypot(*(TRIANGLE_XY[triangles] - centroids[:, None, :]).transpose(2, 0, 1))
    real = acts >= 0
    alpha = np.where(real, 1.0 / np.maximum(d, _VERTEX_EPS), 0.0)
    alpha /= np.add.reduce(alpha, axis=1, keepdims=True)
    rows = np.zeros((len(triangles), N_ACTUATORS))
    r, v = np.nonzero(real)
    rows[r, acts[r, v]] = alpha[r, v]
    for i in np.flatnonzero((real & (d < _VERTEX_EPS)).any(axis=1)):  # on a vertex: the rule's own case
        rows[i] = triangle_weights(tuple(centroids[i]), int(triangles[i]))
    return rows


def actuator_weights(saliency: np.ndarray | None = None, *, params: FusionParams = FusionParams(),
                     shape: np.ndarray | None = None) -> np.ndarray:
    """beta per actuator A1..A9 for one frame: float64 [shape=(9,)] in [0, 1], max 1.

    saliency : float [shape=(h, w)] in [0, 1]; or give the binary ``shape`` (salient_shape output).
    Nothing salient -> all weight on A5.
    """
    if shape is None:
        if saliency is None:
            raise ParameterError("actuator_weights needs a saliency map or a salient shape")
        shape = salient_shape(saliency, params=params)
    shape = np.asarray(shape, dtype=bool)
    if shape.ndim != 2 or not shape.any():
        return fallback_weights()
    h, w = shape.shape
    tri = triangle_index_map(h, w)
    ys, xs = np.nonzero(shape)
    t = tri[ys, xs].astype(np.int64)
    ok = t >= 0
    ys, xs, t = ys[ok], xs[ok], t[ok]
    if t.size == 0:
        return fallback_weights()
    counts = np.bincount(t, minlength=_N_TRI).astype(np.float64)
    cx = np.bincount(t, weights=(xs + 0.5) / w, minlength=_N_TRI)
    cy = np.bincount(t, weights=(ys + 0.5) / h, minlength=_N_TRI)
    held = np.flatnonzero(counts)
    rows = _weights_of(np.stack([cx[held] / counts[held], cy[held] / counts[held]], axis=1), held)
    if params.variant == "mass":
        rows *= (counts[held] / counts.sum())[:, None]
    W = np.add.reduce(rows, axis=0)
    peak = W.max()
    if not peak > 0:
        return fallback_weights()
    return W / peak
