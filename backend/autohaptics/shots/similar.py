"""Similar shots: each shot's features from the analysis's own per-tick arrays, standardised over
the film's shots, and a distance between two shots in 0..1.

Feature groups (each a mean over the shot's ticks): ``colour`` (mean R, G, B), ``motion`` (log(1 +
frame widths/s)), ``sound`` (log(1 + each tick's loudest 20 ms frame, sone)) and ``saliency`` (the
centroid x, y of the saliency weights on the frame over the ticks where saliency ran, drawn towards
the film's mean by the share of ticks where it did not). Each value is standardised over the film's shots (z = (v - mean) / std;
a value the film does not vary gives 0). With g groups present, d^2 = the mean over the groups of
each group's mean squared z difference, and the distance is ``1 - exp(-d^2 / 2)``: 0 for equal
features, 0.63 at d^2 = 2 (two shots drawn at random from the film, on average), towards 1 beyond.
"""

from __future__ import annotations

import numpy as np

from autohaptics.errors import ParameterError
from autohaptics.layout import ACTUATOR_XY
from autohaptics.shots.summary import tick_loudness


def shot_features(t0: np.ndarray, t1: np.ndarray, *, mean_rgb: np.ndarray | None = None,
                  motion: np.ndarray | None = None, loudness: np.ndarray | None = None,
                  beta: np.ndarray | None = None, saliency_mask: np.ndarray | None = None) -> np.ndarray:
    """The shots' weighted standardised features, float64 [shape=(m, k)]: the squared Euclidean
    distance between two rows is d^2 (module docstring). Shots ``[t0, t1)`` tile the n ticks.

    mean_rgb : (n, 3) 0..255; motion : (n,) frame widths/s; loudness : (n * 5,) sone on the 20 ms
    grid; beta : (n, 9) saliency weights per actuator with saliency_mask (n,) bool where they ran.
    Any of them None: that group is left out (k = 0 when all are)."""
    t0, t1 = np.asarray(t0, np.int64), np.asarray(t1, np.int64)
    if t0.size == 0 or t0[0] != 0 or (t0[1:] != t1[:-1]).any() or (t1 <= t0).any():
        raise ParameterError("shots must tile the film in order")
    n = int(t1[-1])
    length = (t1 - t0).astype(np.float64)[:, None]

    def mean(per_tick):
        return np.add.reduceat(np.asarray(per_tick, np.float64).reshape(n, -1), t0, axis=0) / length

    groups = []
    if mean_rgb is not None:
        groups.append(mean(mean_rgb))
    if motion is not None:
        groups.append(mean(np.log1p(np.maximum(np.asarray(motion, np.float64), 0.0))))
    per_tick = tick_loudness(loudness, n)
    if per_tick is not None:
        groups.append(mean(np.log1p(np.maximum(per_tick, 0.0))))
    if beta is not None and saliency_mask is not None:
        groups.append(_saliency_centroid(t0, np.asarray(beta, np.float32), np.asarray(saliency_mask, bool)))
    cols = [_standardised(g) / np.sqrt(len(groups) * g.shape[1]) for g in groups]
    return np.concatenate(cols, axis=1) if cols else np.zeros((t0.size, 0))


def _saliency_centroid(t0: np.ndarray, beta: np.ndarray, mask: np.ndarray) -> np.ndarray:
    """Per shot, the weight-averaged actuator position (x, y 0..1) over its saliency ticks, drawn
    towards the film's mean by the share of its ticks without saliency (a shot where saliency ran
    on 2 ticks of 20 says little about where its subject is)."""
    w = np.where(mask[:, None], beta, 0.0)
    per_shot = np.add.reduceat(w, t0, axis=0)  # (m, 9): the products with positions on the small array
    weight, where = per_shot.sum(axis=1), per_shot @ ACTUATOR_XY
    length = np.diff(np.append(t0, mask.size))
    share = np.add.reduceat(mask & (w.sum(axis=1) > 1e-9), t0) / length
    seen = weight > 1e-9
    xy = np.full((t0.size, 2), 0.5)
    xy[seen] = where[seen] / weight[seen, None]
    film = xy[seen].mean(axis=0) if seen.any() else xy[0]
    return share[:, None] * xy + (1.0 - share[:, None]) * film


def _standardised(values: np.ndarray) -> np.ndarray:
    std = values.std(axis=0)
    z = (values - values.mean(axis=0)) / np.where(std > 1e-9 * (1 + np.abs(values).max(axis=0)), std, np.inf)
    return z


def distances(features: np.ndarray, i: int) -> np.ndarray:
    """The distance (0..1) of every shot to shot ``i`` (row index), float64 [shape=(m,)]."""
    diff = features - features[i]
    return -np.expm1(-0.5 * np.einsum("ij,ij->i", diff, diff))


def nearest(features: np.ndarray, i: int) -> tuple[np.ndarray, np.ndarray]:
    """(row indices of every other shot by ascending distance to shot ``i``, ties by position; their
    distances)."""
    d = distances(features, i)
    order = np.argsort(d, kind="stable")
    order = order[order != i]
    return order, d[order]
