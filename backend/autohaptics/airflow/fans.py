"""The fan rule: which ticks and which of the 9 x 17 cells blow (ALGORITHM.md section 5, steps 2-5).

A tick blows when its sustained motion exceeds the threshold: manual, or adaptive from the clip's
own motion (``strong_rel`` x the 95th percentile of the ticks that move, one-tick spikes left out);
the motion judged is averaged over the neighbouring ticks of the shot first, so a low-quality
encode's uneven motion samples neither drop a run nor raise the threshold, and a tick many times
both its neighbours' (a flow pair across a cut the cut rule missed) is taken at theirs before that.
In a blowing tick a cell blows where its motion, smoothed over the shot's neighbouring ticks and
cells, reaches ``cell_rel`` of the tick's strong motion (its few strongest cells,
:func:`strong_motion`) AND it is near; a near cell enclosed by blowing cells blows too (an object
coming at the camera has a still centre). docs/BENCHMARKS.md ("Fans") has the measurements behind
each rule.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace
from typing import ClassVar

import cv2
import numpy as np

from autohaptics.errors import ParameterError
from autohaptics.records import ANALYSIS, DERIVE, stage
from autohaptics.layout import FAN_COLS, FAN_ROWS
from autohaptics.imaging import finite32
from autohaptics.quantiles import median, percentile
from autohaptics.timebase import gaussian_taps, shot_smoothed


THRESHOLD_MOTIONS = ("despiked", "judged")


@dataclass(frozen=True)
class AirflowParams:
    """Which ticks and which cells blow.

    threshold : motion threshold in frame widths per second; None = adaptive (module docstring).
    floor : motion below this never counts (frame widths/s, default 0.005); also the depth skip limit.
    strong_rel : adaptive threshold = strong_rel x the 95th percentile of the moving ticks' motion (0.3).
    cell_rel, peak_cells, peak_floor : a cell is "strong motion" at ``cell_rel`` (0.55) of the tick's strong
        motion or more: the mean of its ``peak_cells`` (5) strongest cells, at least ``peak_floor`` (0.55) of
        its strongest (:func:`strong_motion`; the thesis: 0.5 of the strongest cell, ``peak_cells`` 1).
    near_min, near_share : a cell is "near" at ``near_min`` or more (0..1, 1 = nearest), or among the nearest
        ``near_share`` of its tick's cells (0..1, default 0.4; 0 = ``near_min`` alone, the thesis; :func:`near_cells`).
    static_level, static_fraction, static_noise : a pair is static when under ``static_fraction`` of the proxy's
        pixels changed by over ``static_level`` grey levels or, higher, ``static_noise`` x the pair's noise (grain).
    fill_enclosed : a near cell enclosed by "on" cells blows too (an approaching object's still centre).
    flat_std : a frame whose luma std is below this (grey levels) is flat; two flat frames: no motion (:func:`is_fade`).
    fade_min_step : a pair only brightened/darkened by this or more (grey levels) is a fade (:func:`is_fade`).
    cell_sigma_ticks, cell_sigma_cells : a tick's cells are judged on their motion averaged over the shot's
        ticks and neighbouring cells, Gaussian stds (ticks 2, cells 0.5; 0 = none; :func:`smoothed_cell_motion`).
    near_sigma_ticks : a blowing tick's nearness is the Gaussian-weighted mean (this std, ticks) over the ticks
        of its shot around it where depth ran (default 2; 0 = its own, the thesis; :func:`smoothed_nearness`).
    motion_sigma_ticks : which ticks blow, and the adaptive threshold, judge each tick's motion smoothed as
        the cells' is, with this std (ticks; default 3; 0 = the tick's own, the thesis; :func:`smoothed_motion`).
    threshold_motion : the adaptive threshold's motion: "despiked" (default: one-tick spikes out first,
        :func:`despiked_motion`) | "judged" (the sustained judged motion: the thesis, the rule before issue 31).
    spike_ratio : a tick over this many times both moving shot neighbours is judged at theirs (10; 0: never, thesis).
    """

    STAGE: ClassVar[str] = DERIVE

    threshold: float | None = None
    floor: float = field(default=0.005, metadata=stage(ANALYSIS))
    strong_rel: float = 0.3
    cell_rel: float = 0.55
    peak_cells: int = 5
    peak_floor: float = 0.55
    near_min: float = 0.5
    near_share: float = 0.4
    static_level: float = field(default=12.0, metadata=stage(ANALYSIS))
    static_fraction: float = field(default=0.002, metadata=stage(ANALYSIS))
    static_noise: float = field(default=6.0, metadata=stage(ANALYSIS))
    fill_enclosed: bool = True
    flat_std: float = field(default=2.0, metadata=stage(ANALYSIS))
    fade_min_step: float = field(default=1.0, metadata=stage(ANALYSIS))
    cell_sigma_ticks: float = 2.0
    cell_sigma_cells: float = 0.5
    near_sigma_ticks: float = 2.0
    motion_sigma_ticks: float = 3.0
    threshold_motion: str = "despiked"
    spike_ratio: float = 10.0

    def __post_init__(self):
        if self.threshold_motion not in THRESHOLD_MOTIONS:
            raise ParameterError(f"airflow.threshold_motion must be one of {THRESHOLD_MOTIONS}, "
                                 f"got {self.threshold_motion!r}")
        if not (self.spike_ratio == 0 or (math.isfinite(self.spike_ratio) and 1.0 <= self.spike_ratio <= 1000.0)):
            raise ParameterError(f"airflow.spike_ratio must be 0 (never) or lie in 1..1000, got {self.spike_ratio!r}")
        if self.threshold is not None and not (math.isfinite(self.threshold) and self.threshold >= 0):
            raise ParameterError(f"airflow.threshold must be >= 0 (frame widths/s) or None, got {self.threshold!r}")
        if not (0.0 <= float(self.floor) < 100.0):
            raise ParameterError(f"airflow.floor must lie in 0..100 frame widths/s, got {self.floor!r}")
        if not (math.isfinite(self.static_noise) and 0.0 <= self.static_noise <= 50.0):
            raise ParameterError(f"airflow.static_noise must lie in 0..50, got {self.static_noise!r}")
        for name in ("flat_std", "fade_min_step"):
            v = float(getattr(self, name))
            if not (math.isfinite(v) and 0.0 <= v <= 255.0):
                raise ParameterError(f"airflow.{name} must lie in 0..255 grey levels, got {getattr(self, name)!r}")
        for name, top in (("cell_sigma_ticks", 50.0), ("cell_sigma_cells", float(FAN_COLS)),
                          ("near_sigma_ticks", 50.0), ("motion_sigma_ticks", 50.0)):
            v = float(getattr(self, name))
            if not (math.isfinite(v) and 0.0 <= v <= top):
                raise ParameterError(f"airflow.{name} must lie in 0..{top:g}, got {getattr(self, name)!r}")
        if not (isinstance(self.peak_cells, int) and 1 <= self.peak_cells <= FAN_ROWS * FAN_COLS):
            raise ParameterError(f"airflow.peak_cells must be a whole number in 1..{FAN_ROWS * FAN_COLS}, "
                                 f"got {self.peak_cells!r}")
        for name in ("cell_rel", "peak_floor", "near_min", "near_share", "static_fraction", "strong_rel"):
            if not (0.0 <= float(getattr(self, name)) <= 1.0):
                raise ParameterError(f"airflow.{name} must lie in 0..1, got {getattr(self, name)!r}")


def grid_means(arr: np.ndarray) -> np.ndarray:
    """Mean of a map over the 9 x 17 fan cells (row 0 = top). [shape=(h, w)] -> float32 [shape=(9, 17)]."""
    a = np.asarray(arr, dtype=np.float32)
    if a.ndim != 2 or a.size == 0:
        raise ParameterError(f"grid_means needs a non-empty 2-D map, got shape {a.shape}")
    a = finite32(a)
    h, w = a.shape
    if h >= FAN_ROWS and w >= FAN_COLS:
        return cv2.resize(a, (FAN_COLS, FAN_ROWS), interpolation=cv2.INTER_AREA)
    rows = np.minimum((np.arange(FAN_ROWS) + 0.5) * h / FAN_ROWS, h - 1).astype(int)
    cols = np.minimum((np.arange(FAN_COLS) + 0.5) * w / FAN_COLS, w - 1).astype(int)
    return a[np.ix_(rows, cols)].astype(np.float32)


def cell_motion(mag: np.ndarray) -> np.ndarray:
    """Mean motion per fan cell, frame widths per second, float32 [shape=(9, 17)]."""
    return grid_means(mag)


def smoothed_cell_motion(cell_motion_: np.ndarray, shot: np.ndarray, ticks: np.ndarray, *,
                         params: AirflowParams = AirflowParams()) -> np.ndarray:
    """The cell motion the fan rule judges ``ticks`` on, frame widths/s: float32 [shape=(len(ticks), 9, 17)].

    cell_motion_ : [shape=(n, 9, 17)], every tick's cell motion (frame widths/s).
    shot : int [shape=(n,)], each tick's shot number; a negative number marks a tick without a
        motion sample of its own (a cut: its flow pair would straddle it), which takes no part.
    ticks : int [shape=(m,)], the ticks wanted.

    Each tick's cells are the Gaussian-weighted mean (``cell_sigma_ticks``) of the ticks around it,
    a tick of another shot or beyond the clip counting as still (the fan rule is relative to the
    tick's strongest cell, so this and leaving those ticks out give the same fans; counting them as
    still keeps k still ticks in front of a clip from changing its fans), then blurred over
    neighbouring cells (``cell_sigma_cells``; beyond the grid's edge the edge cell repeats).
    Why: a tick's flow pair samples one frame interval of its motion, and which cells reach half
    of the strongest one flickers from tick to tick (docs/BENCHMARKS.md, "Fans", point 6).
    """
    cm = np.asarray(cell_motion_)
    if cm.ndim != 3 or np.shape(shot) != (cm.shape[0],):
        raise ParameterError(f"smoothed_cell_motion needs (n, rows, cols) cells and (n,) shots, "
                             f"got {cm.shape} and {np.shape(shot)}")
    out = shot_smoothed(cm, shot, ticks, float(params.cell_sigma_ticks))
    sx = float(params.cell_sigma_cells)
    if sx > 0 and out.size:
        out = _blur_axis(_blur_axis(out, 1, sx), 2, sx)
    return np.clip(out, 0.0, None).astype(np.float32)


def smoothed_nearness(nearness: np.ndarray, shot: np.ndarray, depth_mask: np.ndarray, ticks: np.ndarray, *,
                      params: AirflowParams = AirflowParams()) -> np.ndarray:
    """The nearness the fan rule judges ``ticks`` on, 0..1: float32 [shape=(len(ticks), 9, 17)].

    nearness : [shape=(n, 9, 17)] 0..1; shot : int [shape=(n,)] as in :func:`smoothed_cell_motion`;
    depth_mask : bool [shape=(n,)], the ticks where depth ran. Each tick's nearness is the
    Gaussian-weighted mean (``near_sigma_ticks``) over the ticks of its shot where depth ran, the
    weights renormalised over those ticks; the tick's own always counts. Why: nearness is judged
    on one frame per tick, and the embedded cues (detail, expansion) move with the encoding and
    the flow's noise, so a hard ``near_min`` on one frame flips cells between encodes of one film.
    """
    near = np.asarray(nearness)
    n = near.shape[0]
    if near.ndim != 3 or np.shape(shot) != (n,) or np.shape(depth_mask) != (n,):
        raise ParameterError(f"smoothed_nearness needs (n, rows, cols) nearness and (n,) shots and depth mask, "
                             f"got {near.shape}, {np.shape(shot)} and {np.shape(depth_mask)}")
    near = shot_smoothed(near, shot, ticks, float(params.near_sigma_ticks), mask=np.asarray(depth_mask, bool), mean=True)
    return np.clip(near, 0.0, 1.0).astype(np.float32)


def smoothed_motion(motion: np.ndarray, shot: np.ndarray, *, params: AirflowParams = AirflowParams()) -> np.ndarray:
    """The motion the tick rule judges, frame widths/s: float32 [shape=(n,)].

    motion : [shape=(n,)] frame widths/s; shot : int [shape=(n,)] as in :func:`smoothed_cell_motion`
    (negative: a cut tick, which reads 0). Each tick's motion is the Gaussian-weighted mean
    (``motion_sigma_ticks``) of the ticks around it, a tick of another shot, a cut or beyond the
    clip counting as still, as the cells' smoothing does (:func:`smoothed_cell_motion`, with the
    tick's motion for its one cell). Why: one flow pair per tick samples a low-quality encode's
    motion unevenly (slow motion moves in jumps), which drops weak runs and widens the distribution
    the threshold is taken from (docs/BENCHMARKS.md, "Screener encodes").
    """
    m = np.asarray(motion, dtype=np.float64)
    shot = np.asarray(shot)
    if m.ndim != 1 or shot.shape != m.shape:
        raise ParameterError(f"smoothed_motion needs (n,) motion and shots, got {m.shape} and {shot.shape}")
    one_cell = replace(params, cell_sigma_ticks=params.motion_sigma_ticks, cell_sigma_cells=0.0)
    own = np.where(shot >= 0, np.nan_to_num(m), 0.0)[:, None, None]
    return smoothed_cell_motion(own, shot, np.arange(m.size), params=one_cell)[:, 0, 0]


def despiked_motion(motion: np.ndarray, shot: np.ndarray, *, ratio: float = 0.0) -> np.ndarray:
    """Each tick's motion as the median of itself and its two neighbours, frame widths/s: float64 [shape=(n,)].

    motion, shot : [shape=(n,)] as in :func:`smoothed_motion` (a neighbour of another shot, a cut or
    beyond the clip counts as still; a cut tick reads 0). A one-tick spike (an object popping in, a
    flash: flow reads nonsense there, and how much differs between encodes) falls to its
    neighbours' level before it is smoothed over the shot; an alternating run keeps its level.
    ratio : > 0: only a tick over ``ratio`` x both its neighbours changes, to the larger of theirs (the
    median there), every other tick keeps its own: a pair across a cut that the cut rule missed reads
    tens of times its shot's motion, where real motion is rarely ten times both ticks beside it.
    """
    shot = np.asarray(shot)
    m = np.where(shot >= 0, np.nan_to_num(np.asarray(motion, dtype=np.float64)), 0.0)
    if m.size == 0:
        return m
    same_left = np.concatenate([[False], shot[1:] == shot[:-1]])
    same_right = np.concatenate([shot[:-1] == shot[1:], [False]])
    left = np.where(same_left, np.concatenate([[0.0], m[:-1]]), 0.0)
    right = np.where(same_right, np.concatenate([m[1:], [0.0]]), 0.0)
    if ratio > 0:
        beside = np.maximum(left, right)
        return np.where((m > ratio * beside) & (beside > 0), beside, m)
    return median(np.stack([left, m, right]), axis=0)


def _blur_axis(x: np.ndarray, axis: int, sigma: float) -> np.ndarray:
    """Gaussian blur of ``x`` along ``axis`` (standard deviation ``sigma`` samples), the edge value
    repeated beyond the edge. Element-wise sums in a fixed order: a tick's result does not depend
    on which other ticks share the array."""
    offsets, g = gaussian_taps(sigma)
    size = x.shape[axis]
    out = np.zeros_like(x)
    for d, w in zip(offsets, g):
        out += w * np.take(x, np.clip(np.arange(size) + d, 0, size - 1), axis=axis)
    return out


def motion_threshold(motion: np.ndarray, *, params: AirflowParams = AirflowParams()) -> float:
    """The airflow threshold for a clip, frame widths/s: manual, or adaptive (module docstring)."""
    if params.threshold is not None:
        return float(max(params.threshold, 0.0))
    m = np.asarray(motion, dtype=np.float64)
    m = m[np.isfinite(m) & (m > params.floor)]  # the statistics of the ticks that move
    if m.size == 0:
        return float(params.floor)
    return float(max(params.floor, params.strong_rel * float(percentile(m, 95))))


def fan_levels(cell_motion_: np.ndarray, nearness: np.ndarray, *, params: AirflowParams = AirflowParams()) -> np.ndarray:
    """Fan levels of one airflow tick: strong motion AND near. Both [shape=(9, 17)] -> float32 [0, 1]."""
    m = np.nan_to_num(np.asarray(cell_motion_, dtype=np.float64))
    near = np.nan_to_num(np.asarray(nearness, dtype=np.float64))
    if m.shape != (FAN_ROWS, FAN_COLS) or near.shape != (FAN_ROWS, FAN_COLS):
        raise ParameterError(f"fan_levels needs (9, 17) grids, got {m.shape} and {near.shape}")
    peak = float(m.max())
    if not peak > 0:
        return np.zeros((FAN_ROWS, FAN_COLS), np.float32)
    with np.errstate(over="ignore"):  # a subnormal peak: the quotient overflows, then clips to 1
        rel = np.clip(m / peak, 0.0, 1.0).astype(np.float32)  # the output's precision decides "still"
    near_ok = near_cells(near, params=params)
    bar = np.float32(params.cell_rel * (strong_motion(m, params=params) / peak))  # of the strongest cell
    on = (rel >= bar) & (rel > 0) & near_ok  # a still cell is never "strong motion"
    levels = np.where(on, rel, 0.0)
    if params.fill_enclosed and on.any():
        holes = _enclosed(on) & near_ok
        if holes.any():
            levels[holes] = float(levels[on].mean())
    return levels.astype(np.float32)


def strong_motion(cell_motion_: np.ndarray, *, params: AirflowParams = AirflowParams()) -> float:
    """A tick's strong motion, the reference of its cells' bar: the mean of its ``peak_cells``
    strongest cells, at least ``peak_floor`` x its strongest (same units as the motion; >= 0).

    The strongest cell alone is one sample of 153: which cell peaks, and by how much, changes with
    an encode's blur and blocks, and with it which cells pass a share of it."""
    m = np.asarray(cell_motion_, dtype=np.float64).ravel()
    peak = float(m.max())
    if params.peak_cells == 1:
        return peak
    with np.errstate(over="ignore"):  # cells near the float limit: their sum overflows, the peak serves
        top = float(np.partition(m, m.size - params.peak_cells)[m.size - params.peak_cells:].mean())
    return min(peak, max(top, params.peak_floor * peak))


def near_cells(nearness: np.ndarray, *, params: AirflowParams = AirflowParams()) -> np.ndarray:
    """The cells of one tick that count as near: bool [shape=(9, 17)] from nearness 0..1.

    A cell is near at ``near_min`` or more, or when fewer than ``near_share`` of the cells are
    nearer than it (ties share a rank, so a flat map is all near for any share above 0). Why the
    share: nearness ranks rather than measures, and its cues' noise (a share of the flow's, larger
    over a shorter frame pair) lifts every cell and would move an absolute bar with the encoding.
    """
    near = np.nan_to_num(np.asarray(nearness, dtype=np.float64))
    ok = near >= params.near_min
    if params.near_share > 0:
        flat = np.sort(near.ravel())
        nearer = flat.size - np.searchsorted(flat, near, side="right")
        ok |= nearer < params.near_share * flat.size
    return ok


def _enclosed(on: np.ndarray) -> np.ndarray:
    """Cells that are off and cannot reach the grid border through off cells (4-connected)."""
    off = (~on).astype(np.uint8)
    n, labels = cv2.connectedComponents(off, connectivity=4)
    inside = np.ones(n, bool)
    inside[np.concatenate([labels[0], labels[-1], labels[:, 0], labels[:, -1]])] = False  # the border's labels
    inside[0] = False  # label 0 is the "on" cells
    return inside[labels]


def sustained_motion(motion: np.ndarray) -> np.ndarray:
    """The motion a tick shares with a neighbour: min(m[k], max(m[k-1], m[k+1])), frame widths/s.

    A one-tick spike (an object popping in or a flash: optical flow reads nonsense there, and 100 ms
    of wind cannot be felt anyway) falls to its neighbours' level; motion that lasts two ticks or
    more keeps its value. Outside the clip counts as still.
    """
    m = np.asarray(motion, dtype=np.float64)
    if m.size == 0:
        return m.copy()
    left = np.concatenate([[0.0], m[:-1]])
    right = np.concatenate([m[1:], [0.0]])
    return np.minimum(m, np.maximum(left, right))


_FAN_CHUNK = 2048  # ticks smoothed at a time (bounded memory on a 2-hour film)


def fan_track(motion: np.ndarray, cell_motion_: np.ndarray, nearness: np.ndarray, cut: np.ndarray,
              depth_mask: np.ndarray, *, params: AirflowParams = AirflowParams(),
              out: np.ndarray | None = None) -> tuple[np.ndarray, dict]:
    """The fans track and what decided it.

    motion : [shape=(n,)] frame widths/s; cell_motion_, nearness : [shape=(n, 9, 17)];
    cut, depth_mask : bool [shape=(n,)] (a cut tick never blows; depth must have run).
    out : an all-zero float32 (n, 9, 17) array to write into (the timeline's own track).
    Returns (fans float32 [shape=(n, 9, 17)] in 0..1, stats {threshold_fw_per_s, ticks_on, ...}).
    """
    n = motion.size
    valid = ~cut
    shot = np.where(valid, np.cumsum(cut), -1)
    own = despiked_motion(motion, shot, ratio=params.spike_ratio) if params.spike_ratio > 0 else motion
    judged = smoothed_motion(own, shot, params=params) if params.motion_sigma_ticks > 0 \
        else np.where(valid, own, 0.0)
    sustained = sustained_motion(judged)
    basis = sustained if params.threshold_motion == "judged" else \
        smoothed_motion(despiked_motion(motion, shot), shot, params=params)
    threshold = motion_threshold(basis[valid], params=params)
    on = valid & (sustained > threshold) & depth_mask
    fans = np.zeros((n,) + cell_motion_.shape[1:], np.float32) if out is None else out
    ticks = np.flatnonzero(on)
    for start in range(0, ticks.size, _FAN_CHUNK):
        part = ticks[start:start + _FAN_CHUNK]
        cells = smoothed_cell_motion(cell_motion_, shot, part, params=params)
        near = smoothed_nearness(nearness, shot, depth_mask, part, params=params) \
            if params.near_sigma_ticks > 0 else nearness[part].astype(np.float32)
        for k, c, nk in zip(part, cells, near):
            fans[k] = fan_levels(c, nk, params=params)
    stats = {"threshold_fw_per_s": float(threshold), "ticks_on": int(on.sum()), "ticks_at_cuts": int(cut.sum()),
             "spikes_ignored": int(((judged > threshold) & valid & ~(sustained > threshold)).sum()),
             "spikes_out": int((valid & (own < np.nan_to_num(motion))).sum())}
    return fans, stats
