"""Motion + depth -> the 9 x 17 fan grid (ALGORITHM.md section 5, thesis 5.3).

1. Dense optical flow between consecutive frames on a gray proxy (OpenCV DIS by default, Farneback
   as the reference variant).
2. Motion in frame widths per second (flow px / proxy width / frame interval): the same scene gives
   the same number at 160 px / 24 fps and at 4K / 60 fps, so one threshold transfers.
3. Ticks whose mean motion exceeds the threshold are airflow ticks; the threshold is manual
   (``AirflowParams.threshold``) or adaptive from the clip's own motion distribution (default):
   ``max(floor, strong_rel * P95)``, P95 being the 95th percentile of the ticks that move (motion
   above the floor): a tick blows when it reaches ``strong_rel`` (0.3) of the clip's strong motion.
   A static clip (all motion below the floor) gets no airflow at all; a calm clip's few moving
   moments all blow; in an action film only its stronger half does. Static ticks are left out
   of the statistics (more than half of a film can be static: titles, dialogue). Measured: the
   Sintel trailer blows on 47 of its 517 cut-free ticks (both encodes: 47 and 48), BBB's opening
   on 70 of 296; the first rule, ``median + 3 * 1.4826 * MAD`` over all ticks, had median = MAD = 0
   there and blew on every moving tick (260); the same rule over the moving ticks only (an
   outlier detector) blew on none of the 10 ticks of :func:`autohaptics.synth.sample_scene`'s only
   motion, a disc rushing at the camera (P95 rule: all 10).
4. Per tick the frame is split into 17 columns x 9 rows; a fan is on where its cell has strong
   motion (at least ``cell_rel`` of the tick's strongest cell) AND is near (nearness at least
   ``near_min``); its level is the cell's motion relative to the strongest cell, 0..1.
5. The cell motion judged in point 4 is smoothed first (:func:`smoothed_cell_motion`): a Gaussian
   over the shot's neighbouring ticks (standard deviation 2 ticks) and a light one over
   neighbouring cells (0.5 cells). A tick's flow pair spans one frame interval (17-42 ms of the
   tick's 100 ms at 60-24 fps), and which cells reach half of the strongest one changes from pair
   to pair. Measured against the reference preset (every frame, 640 px flow) on the shared 2 s
   1080p60 BBB clip: the reference given only half its frames agreed with itself at a fan-cell IoU
   of 0.66 with each tick's own cells, 0.76 with the smoothed ones; balanced (one 160 px pair per
   tick) agreed with the reference at 0.30 -> 0.44 (0.31 -> 0.49 on the 30 s loop made of that
   clip in ``bench accuracy``; 0.72 with the proxy of "Decisions" below), on the Sintel trailer
   at 0.50 -> 0.63; Sintel's two encodes with each other 0.91 -> 0.94. Fans stay on longer (the
   reference's mean run of an "on" cell: 2.3 -> 6.4 ticks on the BBB clip, 2.6 -> 5.7 on Sintel)
   and blow over a wider area (cells on per blowing tick: BBB 8 -> 14, Sintel 64 -> 101 of 153).
   With about as many cells on (old rule at ``cell_rel`` 0.4: 11 cells; smoothed at 0.6: 10)
   balanced's agreement on BBB is 0.35 vs 0.47: the gain is not the wider area. A blur of 1 cell
   gained a little more on the clips (BBB 0.53) but spread a moving object onto a moving
   background (tests/test_airflow.py). A longer smoothing (3 ticks) agreed a little better with
   the reference on the shared clips (BBB 1080p 0.73 -> 0.77, Sintel 0.65 -> 0.67, BBB opening
   0.42 -> 0.44) but smears an object crossing the grid along its path (at a quarter of a cell
   per tick, IoU with the truth 0.80 at 2 ticks, 0.73 at 3; tests/test_airflow.py).
   ``cell_sigma_ticks = cell_sigma_cells = 0`` restores each tick's own cells.

A static pair (nothing changed beyond noise) is detected by a cheap frame difference so flow is
not computed at all, and flow is never computed across a shot cut (see :mod:`autohaptics.cuts`).
A fade (a global change of brightness and contrast and nothing else) and a pair of flat frames
(black, noise under a title) have no motion in every preset, the reference included
(:func:`is_fade`): DIS reads a brightness ramp as motion, and on the BBB opening's fade in from
black the reference blew the fans through the fade (0.3-0.9 frame widths/s on ticks 2-15, more
than the clip's action), which also raised its adaptive threshold.

Decisions (measured; synthetic scenes from :mod:`autohaptics.synth` have exact answers):

- The flow proxy grows with the picture (``FlowParams.proxy_fraction``, default 1/8 of the width
  as shown, at least ``proxy_width``): 160 px up to 1280 px wide pictures, 240 px at 1920, 480 at
  3840. At 1080p a fan cell of a 160 px proxy is 9 x 10 px, about one DIS patch, and the balanced
  preset waited about 2 s of its 6-7 s for the decoder on the 30 s 1080p60 BBB loop; decoding
  costs in proportion to the picture's pixels, the flow to the proxy's, so a proxy in proportion
  to the picture keeps the flow inside the decoder's time. Measured against the reference in one
  ``bench accuracy`` run (``out/bench/s19``, 3 alternating runs each): fan IoU 0.49 -> 0.72 at
  0.98 x the bare decode's wall time (160 px: 1.01 x; CPU 1.02 x against 0.97 x); on a synthetic
  1920x1080 scene 0.55 -> 0.68 (320 px: 0.80). Up to 1280 px the proxy stays at 160 px: on the
  Sintel trailer (640 px) 240 px gained nothing (0.63 -> 0.62) and cost 66 % more wall time, on
  the 1280 px BBB opening it gained 0.42 -> 0.50 for 46 % more. The reference's third of the
  width is its 640 px at 1080p; the fast preset's sixteenth is its 128 px up to 2048 px.
- DIS preset "medium" by default. On the 160 px proxy the "fast" preset estimates flow at a
  quarter of the proxy's resolution (finest scale 2) and smears it over static surroundings: a
  textured disc translating over a static textured background gave a relative end-point error of
  0.31 inside the disc and 5 % of its motion far from it (13 % for a disc growing toward the
  camera; a static strip above it read a third of the peak cell's motion), which turned on fans
  over static background. "medium" (finest scale 1): errors 0.01 (translation) and 0.16
  (expansion), no measurable smear; the 320x180@24 vs 1280x720@30 renders of
  :func:`autohaptics.synth.sample_scene` went from fan-cell IoU 0.76 to 0.93. Cost: 2.1 ms
  instead of 0.45 ms per 160x68 pair on one core.
- Farneback (kept as a variant) needs second-order image structure within its polynomial
  neighbourhood (5-7 px): on smooth content it under-reads motion badly (a smooth texture panned
  2 px/frame read 0.02-0.06 px at any window size; on the Sintel trailer at 640 px its mean
  motion is a median 0.22 of DIS "medium"'s, whereas DIS at 160 px and at 640 px agree within
  1 %). It is accurate on finely textured content.
- A near cell enclosed by blowing cells blows as well (``fill_enclosed``): an object coming
  straight at the camera expands, and its centre has no image motion although all of it
  approaches; without this its fans form a ring. Its level is the mean level of the blowing cells.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import lru_cache

import cv2
import numpy as np

from autohaptics.errors import ParameterError
from autohaptics.layout import FAN_COLS, FAN_ROWS

FLOW_METHODS = ("dis", "farneback")
DIS_PRESETS = {"ultrafast": cv2.DISOPTICAL_FLOW_PRESET_ULTRAFAST, "fast": cv2.DISOPTICAL_FLOW_PRESET_FAST,
               "medium": cv2.DISOPTICAL_FLOW_PRESET_MEDIUM}
_MIN_FLOW_SIDE = 16  # px; smaller proxies have no room for a flow patch: motion reads 0


@dataclass(frozen=True)
class FlowParams:
    """Optical flow.

    method : "dis" (OpenCV DIS, default) | "farneback" (the reference).
    proxy_width : width of the gray proxy the flow runs on, px (default 160); the least width
        when ``proxy_fraction`` asks for more (:meth:`width_for`).
    dis_preset : "ultrafast" | "fast" | "medium" (default; see the module docstring).
    proxy_fraction : the proxy is at least this fraction of the picture's width as shown, in
        multiples of 16 px, 0..1 (default 1/8: 240 px at 1920, 480 at 3840, ``proxy_width`` up to
        1280; 0 = always ``proxy_width``). Module docstring, "Decisions".
    """

    method: str = "dis"
    proxy_width: int = 160
    dis_preset: str = "medium"
    proxy_fraction: float = 0.125

    def __post_init__(self):
        if self.method not in FLOW_METHODS:
            raise ParameterError(f"flow.method must be one of {FLOW_METHODS}, got {self.method!r}")
        if self.dis_preset not in DIS_PRESETS:
            raise ParameterError(f"flow.dis_preset must be one of {sorted(DIS_PRESETS)}, got {self.dis_preset!r}")
        if not (8 <= int(self.proxy_width) <= 7680):
            raise ParameterError(f"flow.proxy_width must lie in 8..7680 px, got {self.proxy_width!r}")
        if not (0.0 <= float(self.proxy_fraction) <= 1.0):  # NaN fails too
            raise ParameterError(f"flow.proxy_fraction must lie in 0..1, got {self.proxy_fraction!r}")

    def width_for(self, picture_width: int) -> int:
        """The gray proxy's width for a picture ``picture_width`` px wide as shown, px:
        ``max(proxy_width, proxy_fraction x picture_width rounded to 16 px)``, at most 7680."""
        scaled = 16 * int(round(float(self.proxy_fraction) * max(int(picture_width), 0) / 16.0))
        return int(min(max(int(self.proxy_width), scaled), 7680))


@dataclass(frozen=True)
class AirflowParams:
    """Which ticks and which cells blow.

    threshold : motion threshold in frame widths per second; None = adaptive (module docstring).
    floor : motion below this never counts (frame widths/s, default 0.005); also the depth skip limit.
    strong_rel : adaptive threshold = strong_rel x the 95th percentile of the moving ticks' motion
        (default 0.3; module docstring).
    cell_rel : a cell is "strong motion" at this fraction of the tick's strongest cell or more.
    near_min : a cell is "near" at this nearness or more (0..1, 1 = nearest).
    static_level, static_fraction : a frame pair is static when fewer than ``static_fraction`` of
        the proxy's pixels changed by more than ``static_level`` grey levels (noise tolerant, yet a
        small moving object is seen).
    fill_enclosed : a near cell enclosed by "on" cells blows too (the still centre of an object
        expanding toward the camera; see the module docstring).
    flat_std : a frame whose luma standard deviation is below this (grey levels) is flat; a pair
        of flat frames has no motion (:func:`is_fade`).
    fade_min_step : a pair whose mean brightness moved by at least this (grey levels) and that
        differs in nothing else than a global brightness/contrast change is a fade: no motion
        (:func:`is_fade`).
    cell_sigma_ticks : a blowing tick's cells are judged on their motion averaged over the
        neighbouring ticks of its shot with Gaussian weights of this standard deviation (ticks;
        default 2, 0 = the tick alone; :func:`smoothed_cell_motion`).
    cell_sigma_cells : that motion is also blurred over neighbouring cells with this standard
        deviation (cells; default 0.5, 0 = the cell alone).
    """

    threshold: float | None = None
    floor: float = 0.005
    strong_rel: float = 0.3
    cell_rel: float = 0.5
    near_min: float = 0.5
    static_level: float = 12.0
    static_fraction: float = 0.002
    fill_enclosed: bool = True
    flat_std: float = 2.0
    fade_min_step: float = 1.0
    cell_sigma_ticks: float = 2.0
    cell_sigma_cells: float = 0.5

    def __post_init__(self):
        if self.threshold is not None and not (math.isfinite(self.threshold) and self.threshold >= 0):
            raise ParameterError(f"airflow.threshold must be >= 0 (frame widths/s) or None, got {self.threshold!r}")
        if not (0.0 <= float(self.floor) < 100.0):
            raise ParameterError(f"airflow.floor must lie in 0..100 frame widths/s, got {self.floor!r}")
        for name in ("flat_std", "fade_min_step"):
            v = float(getattr(self, name))
            if not (math.isfinite(v) and 0.0 <= v <= 255.0):
                raise ParameterError(f"airflow.{name} must lie in 0..255 grey levels, got {getattr(self, name)!r}")
        for name, top in (("cell_sigma_ticks", 50.0), ("cell_sigma_cells", float(FAN_COLS))):
            v = float(getattr(self, name))
            if not (math.isfinite(v) and 0.0 <= v <= top):
                raise ParameterError(f"airflow.{name} must lie in 0..{top:g}, got {getattr(self, name)!r}")
        for name in ("cell_rel", "near_min", "static_fraction", "strong_rel"):
            if not (0.0 <= float(getattr(self, name)) <= 1.0):
                raise ParameterError(f"airflow.{name} must lie in 0..1, got {getattr(self, name)!r}")


@lru_cache(maxsize=16)
def _dis(preset: str, h: int, w: int):
    """One DIS object per preset AND frame size: OpenCV's DIS keeps buffers across calls, and a
    call at another size changes later results (up to 0.06 px on a 160x68 pair; on the Sintel
    trailer analysed after other sizes, per-tick motion moved by up to 0.19 frame widths/s).
    Per size, results depend on the inputs only (tests/test_airflow.py)."""
    return cv2.DISOpticalFlow_create(DIS_PRESETS[preset])


def optical_flow(prev_gray: np.ndarray, gray: np.ndarray, *, params: FlowParams = FlowParams()) -> np.ndarray:
    """Dense flow from ``prev_gray`` to ``gray`` (uint8 [shape=(h, w)]), px per frame interval.

    Returns float32 [shape=(h, w, 2)] (dx, dy); zeros when the proxy is too small for flow.
    """
    a, b = _gray(prev_gray), _gray(gray)
    if a.shape != b.shape:
        raise ParameterError(f"flow needs two frames of one size, got {a.shape} and {b.shape}")
    h, w = a.shape
    if min(h, w) < _MIN_FLOW_SIDE:
        return np.zeros((h, w, 2), np.float32)
    if params.method == "dis":
        flow = _dis(params.dis_preset, h, w).calc(a, b, None)
    else:
        win = max(5, int(round(w / 40)) | 1)
        levels = max(1, min(5, int(math.log2(min(h, w) / 8))))
        flow = cv2.calcOpticalFlowFarneback(a, b, None, 0.5, levels, win, 3, 5, 1.1, 0)
    flow = np.asarray(flow, dtype=np.float32)
    return np.where(np.isfinite(flow), flow, 0.0).astype(np.float32)


def motion_magnitude(flow: np.ndarray, *, dt_s: float, width_px: int) -> np.ndarray:
    """Flow magnitude in frame widths per second. flow [shape=(h, w, 2)] px -> float32 [shape=(h, w)]."""
    if not (dt_s > 0 and width_px > 0):
        raise ParameterError(f"motion_magnitude needs dt_s > 0 and width_px > 0, got {dt_s}, {width_px}")
    flow = np.asarray(flow, dtype=np.float32)
    mag = np.sqrt(flow[..., 0] ** 2 + flow[..., 1] ** 2) / (float(width_px) * float(dt_s))
    return np.where(np.isfinite(mag), mag, 0.0).astype(np.float32)


def motion_score(mag: np.ndarray) -> float:
    """A frame's motion: the mean magnitude, frame widths per second (0 for an empty map)."""
    mag = np.asarray(mag, dtype=np.float64)
    return float(mag.mean()) if mag.size else 0.0


def grid_means(arr: np.ndarray) -> np.ndarray:
    """Mean of a map over the 9 x 17 fan cells (row 0 = top). [shape=(h, w)] -> float32 [shape=(9, 17)]."""
    a = np.asarray(arr, dtype=np.float32)
    if a.ndim != 2 or a.size == 0:
        raise ParameterError(f"grid_means needs a non-empty 2-D map, got shape {a.shape}")
    a = np.where(np.isfinite(a), a, 0.0).astype(np.float32)
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
    of the strongest one flickers from tick to tick (module docstring, point 5).
    """
    cm = np.asarray(cell_motion_)
    shot = np.asarray(shot)
    ticks = np.asarray(ticks, dtype=np.int64)
    n = cm.shape[0]
    if cm.ndim != 3 or shot.shape != (n,):
        raise ParameterError(f"smoothed_cell_motion needs (n, rows, cols) cells and (n,) shots, "
                             f"got {cm.shape} and {shot.shape}")
    if ticks.size and (ticks.min() < 0 or ticks.max() >= n):
        raise ParameterError(f"ticks must lie in 0..{n - 1}")
    offsets, gauss = _gaussian(float(params.cell_sigma_ticks))
    out = np.zeros((ticks.size,) + cm.shape[1:], np.float64)
    own = shot[ticks] if ticks.size else np.zeros(0, shot.dtype)
    for d, g in zip(offsets, gauss):
        src = ticks + d
        ok = (src >= 0) & (src < n)
        src = np.clip(src, 0, n - 1)
        ok &= (shot[src] == own) & (shot[src] >= 0)
        if d == 0:  # the tick itself always counts (a cut tick asked for keeps its own cells)
            ok = np.ones(ticks.size, bool)
        if ok.any():
            out += np.where(ok, g, 0.0)[:, None, None] * np.nan_to_num(cm[src].astype(np.float64))
    sx = float(params.cell_sigma_cells)
    if sx > 0 and out.size:
        out = _blur_axis(_blur_axis(out, 1, sx), 2, sx)
    return np.clip(out, 0.0, None).astype(np.float32)


def _gaussian(sigma: float) -> tuple[np.ndarray, np.ndarray]:
    """Offsets -r..r (r = ceil(3 sigma), 0 for sigma <= 0) and their Gaussian weights, summing to 1."""
    r = int(math.ceil(3.0 * sigma)) if sigma > 0 else 0
    offsets = np.arange(-r, r + 1)
    if not r:
        return offsets, np.ones(1)
    with np.errstate(over="ignore"):  # a tiny sigma: the neighbours' weights underflow to 0
        g = np.exp(-0.5 * (offsets / sigma) ** 2)
    return offsets, g / g.sum()


def _blur_axis(x: np.ndarray, axis: int, sigma: float) -> np.ndarray:
    """Gaussian blur of ``x`` along ``axis`` (standard deviation ``sigma`` samples), the edge value
    repeated beyond the edge. Element-wise sums in a fixed order: a tick's result does not depend
    on which other ticks share the array."""
    offsets, g = _gaussian(sigma)
    size = x.shape[axis]
    out = np.zeros_like(x)
    for d, w in zip(offsets, g):
        out += w * np.take(x, np.clip(np.arange(size) + d, 0, size - 1), axis=axis)
    return out


def is_static(prev_gray: np.ndarray, gray: np.ndarray, *, params: AirflowParams = AirflowParams()) -> bool:
    """True when nothing moved between two frames beyond noise (see AirflowParams)."""
    a, b = _gray(prev_gray), _gray(gray)
    if a.shape != b.shape:
        return False
    changed = cv2.absdiff(a, b) > params.static_level
    return float(changed.mean()) < params.static_fraction


def is_fade(prev_gray: np.ndarray, gray: np.ndarray, *, params: AirflowParams = AirflowParams()) -> bool:
    """True when two frames differ only by a global change of brightness and contrast (a fade, a
    flash, an exposure change), or are both too flat to hold any motion: there is no motion to read.

    Optical flow assumes constant brightness and reads such a change as motion (module docstring:
    the BBB opening's fade in from black read 0.3-0.9 frame widths/s at 640 px). Frames whose luma
    standard deviation is below ``flat_std`` are flat; otherwise the higher-contrast frame's
    brightness and contrast are mapped linearly onto the other's, and the pair is a fade when the
    mean brightness moved by at least ``fade_min_step`` grey levels and the mapped pair is static
    (``is_static``). A cut into or out of black is a cut first (:mod:`autohaptics.cuts`, checked
    before); a dark picture straight after black counts as a fade (no flow to read across it).
    """
    a, b = _gray(prev_gray), _gray(gray)
    if a.shape != b.shape:
        return False
    ma, sa = (float(v[0, 0]) for v in cv2.meanStdDev(a))
    mb, sb = (float(v[0, 0]) for v in cv2.meanStdDev(b))
    if sa < params.flat_std and sb < params.flat_std:
        return True
    if abs(ma - mb) < params.fade_min_step:
        return False
    if sa < sb:  # map the higher-contrast frame down: scaling the flatter one up would amplify its noise
        a, b, ma, sa, mb, sb = b, a, mb, sb, ma, sa
    alpha = sb / sa
    mapped = cv2.convertScaleAbs(a, alpha=alpha, beta=mb - alpha * ma)
    return is_static(mapped, b, params=params)


def motion_threshold(motion: np.ndarray, *, params: AirflowParams = AirflowParams()) -> float:
    """The airflow threshold for a clip, frame widths/s: manual, or adaptive (module docstring)."""
    if params.threshold is not None:
        return float(max(params.threshold, 0.0))
    m = np.asarray(motion, dtype=np.float64)
    m = m[np.isfinite(m) & (m > params.floor)]  # the statistics of the ticks that move
    if m.size == 0:
        return float(params.floor)
    return float(max(params.floor, params.strong_rel * float(np.percentile(m, 95))))


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
    near_ok = near >= params.near_min
    on = (rel >= params.cell_rel) & (rel > 0) & near_ok  # a still cell is never "strong motion"
    levels = np.where(on, rel, 0.0)
    if params.fill_enclosed and on.any():
        holes = _enclosed(on) & near_ok
        if holes.any():
            levels[holes] = float(levels[on].mean())
    return levels.astype(np.float32)


def _enclosed(on: np.ndarray) -> np.ndarray:
    """Cells that are off and cannot reach the grid border through off cells (4-connected)."""
    off = (~on).astype(np.uint8)
    n, labels = cv2.connectedComponents(off, connectivity=4)
    border = np.unique(np.concatenate([labels[0], labels[-1], labels[:, 0], labels[:, -1]]))
    inside = np.ones(n, bool)
    inside[border] = False
    inside[0] = False  # label 0 is the "on" cells
    return inside[labels]


def _gray(x: np.ndarray) -> np.ndarray:
    x = np.asarray(x)
    if x.ndim == 3 and x.shape[2] == 3:
        x = cv2.cvtColor(np.ascontiguousarray(x, dtype=np.uint8), cv2.COLOR_RGB2GRAY)
    if x.ndim != 2 or x.size == 0:
        raise ParameterError(f"expected a gray frame of shape (h, w), got {x.shape}")
    if x.dtype != np.uint8:
        x = np.clip(np.nan_to_num(x.astype(np.float64)), 0, 255).astype(np.uint8)
    return np.ascontiguousarray(x)
