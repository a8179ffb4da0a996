"""Optical flow on the gray proxy, and the checks that spare it (ALGORITHM.md section 5, steps 1-2).

Motion is measured in frame widths per second (flow px / proxy width / frame interval), so one
threshold holds at any proxy size and frame rate. OpenCV DIS at its "medium" preset by default,
Farneback as a variant. A static pair (nothing changed beyond noise) or a fade (a global change of
brightness and contrast, or two flat frames) has no motion and no flow is computed: optical flow
reads a brightness ramp as motion. docs/BENCHMARKS.md ("Fans") has the measurements behind these
choices.
"""

from __future__ import annotations

import math
import threading
from dataclasses import dataclass
from typing import ClassVar

import cv2
import numpy as np

from autohaptics.airflow.fans import AirflowParams
from autohaptics.errors import ParameterError
from autohaptics.records import ANALYSIS
from autohaptics.imaging import as_gray, finite32, noise_over, noise_response, noise_sd

FLOW_METHODS = ("dis", "farneback")
DIS_PRESETS = {"ultrafast": cv2.DISOPTICAL_FLOW_PRESET_ULTRAFAST, "fast": cv2.DISOPTICAL_FLOW_PRESET_FAST,
               "medium": cv2.DISOPTICAL_FLOW_PRESET_MEDIUM}
_MIN_FLOW_SIDE = 16  # px; smaller proxies have no room for a flow patch: motion reads 0
GRAIN_MOST = 6.0  # grey levels on the gray proxy: the most noise the static test allows for (is_static)


@dataclass(frozen=True)
class FlowParams:
    """Optical flow.

    method : "dis" (OpenCV DIS, default) | "farneback" (the reference).
    proxy_width : width of the gray proxy the flow runs on, px (default 160); the least width
        when ``proxy_fraction`` asks for more (:meth:`width_for`).
    dis_preset : "ultrafast" | "fast" | "medium" (default; see the module docstring).
    dis_descent, dis_refine : DIS's gradient-descent (1..100) and variational refinement (0..100) iterations;
        None (default) = the preset's (medium: 25, 5); fewer cost less (docs/BENCHMARKS.md, "Stop 65").
    proxy_fraction : the proxy is at least this fraction of the picture's width as shown, in multiples of
        16 px, 0..1 (default 1/8: 240 px at 1920, 480 at 3840, ``proxy_width`` up to 1280; 0 = always
        ``proxy_width``). Module docstring, "Decisions".
    repeat_wait_s : a flow pair's successor frame that repeats its first frame (static, see
        ``airflow.static_level``) is passed over for the next decoded frame while it lies less than this after
        the first frame, s, 0..1 (default 0.1, one tick: frame-rate conversion by repeated frames, 3:2
        pulldown to 60 fps, animation on twos, also where the decoder skips the non-reference frames
        between; 0 = always the next frame, the thesis).
    min_span_frames : a flow pair's successor is the first decoded frame at least this many frame
        intervals (the stream's average rate; a variable-rate stream: its next frame; under a repeat
        cadence this many of the picture's steps, :meth:`Cadence.least_span_s`) after its first, 0..10
        (an analysed frame always ends the pair before it). 0 = the next decoded frame (the thesis); 1.5
        (default) pairs frames two apart whether or not the decoder skips the non-reference frames
        (quick flutter reads otherwise over one): docs/BENCHMARKS.md, "Screener encodes".
    cadence_ratio : a frame that differs from the one before by under this share of the steps around it is a
        repeat: a pair's time counts the picture's steps (:mod:`.cadence`); 0..1 (default 0.35; 0 = the thesis).
    """

    STAGE: ClassVar[str] = ANALYSIS

    method: str = "dis"
    proxy_width: int = 160
    dis_preset: str = "medium"
    proxy_fraction: float = 0.125
    repeat_wait_s: float = 0.1
    min_span_frames: float = 1.5
    cadence_ratio: float = 0.35
    dis_descent: int | None = None
    dis_refine: int | None = None

    def __post_init__(self):
        if self.method not in FLOW_METHODS:
            raise ParameterError(f"flow.method must be one of {FLOW_METHODS}, got {self.method!r}")
        if self.dis_preset not in DIS_PRESETS:
            raise ParameterError(f"flow.dis_preset must be one of {sorted(DIS_PRESETS)}, got {self.dis_preset!r}")
        if not (8 <= int(self.proxy_width) <= 7680):
            raise ParameterError(f"flow.proxy_width must lie in 8..7680 px, got {self.proxy_width!r}")
        for name in ("proxy_fraction", "repeat_wait_s", "cadence_ratio"):
            if not (0.0 <= float(getattr(self, name)) <= 1.0):  # NaN fails too
                raise ParameterError(f"flow.{name} must lie in 0..1, got {getattr(self, name)!r}")
        for name, least in (("dis_descent", 1), ("dis_refine", 0)):
            v = getattr(self, name)
            if v is not None and not (isinstance(v, int) and not isinstance(v, bool) and least <= v <= 100):
                raise ParameterError(f"flow.{name} must be a whole number in {least}..100 or None, got {v!r}")
        if not (0.0 <= float(self.min_span_frames) <= 10.0):
            raise ParameterError(f"flow.min_span_frames must lie in 0..10, got {self.min_span_frames!r}")

    def width_for(self, picture_width: int) -> int:
        """The gray proxy's width for a picture ``picture_width`` px wide as shown, px:
        ``max(proxy_width, proxy_fraction x picture_width rounded to 16 px)``, at most 7680."""
        scaled = 16 * int(round(float(self.proxy_fraction) * max(int(picture_width), 0) / 16.0))
        return int(min(max(int(self.proxy_width), scaled), 7680))


_THREAD = threading.local()  # each thread's DIS objects


def _dis(params: FlowParams, h: int, w: int):
    """One DIS object per setting AND frame size, per thread: OpenCV's DIS keeps buffers across
    calls, and a call at another size changes later results (up to 0.06 px on a 160x68 pair; on
    the Sintel trailer analysed after other sizes, per-tick motion moved by up to 0.19 frame
    widths/s); two threads calling one object at once corrupt each other's. Per size, results
    depend on the inputs only (tests/airflow/test_airflow.py), whichever thread computes them."""
    held = getattr(_THREAD, "dis", None)
    if held is None:
        held = _THREAD.dis = {}
    key = (params.dis_preset, params.dis_descent, params.dis_refine, h, w)
    if key not in held:
        if len(held) >= 16:  # sizes of films analysed before
            held.clear()
        dis = cv2.DISOpticalFlow_create(DIS_PRESETS[params.dis_preset])
        if params.dis_descent is not None:
            dis.setGradientDescentIterations(params.dis_descent)
        if params.dis_refine is not None:
            dis.setVariationalRefinementIterations(params.dis_refine)
        held[key] = dis
    return held[key]


def optical_flow(prev_gray: np.ndarray, gray: np.ndarray, *, params: FlowParams = FlowParams()) -> np.ndarray:
    """Dense flow from ``prev_gray`` to ``gray`` (uint8 [shape=(h, w)]), px per frame interval.

    Returns float32 [shape=(h, w, 2)] (dx, dy); zeros when the proxy is too small for flow.
    """
    a, b = as_gray(prev_gray), as_gray(gray)
    if a.shape != b.shape:
        raise ParameterError(f"flow needs two frames of one size, got {a.shape} and {b.shape}")
    h, w = a.shape
    if min(h, w) < _MIN_FLOW_SIDE:
        return np.zeros((h, w, 2), np.float32)
    if params.method == "dis":
        flow = _dis(params, h, w).calc(a, b, None)
    else:
        win = max(5, int(round(w / 40)) | 1)
        levels = max(1, min(5, int(math.log2(min(h, w) / 8))))
        flow = cv2.calcOpticalFlowFarneback(a, b, None, 0.5, levels, win, 3, 5, 1.1, 0)
    flow = np.asarray(flow, dtype=np.float32)
    return finite32(flow)


def motion_magnitude(flow: np.ndarray, *, dt_s: float, width_px: int) -> np.ndarray:
    """Flow magnitude in frame widths per second. flow [shape=(h, w, 2)] px -> float32 [shape=(h, w)]."""
    if not (dt_s > 0 and width_px > 0):
        raise ParameterError(f"motion_magnitude needs dt_s > 0 and width_px > 0, got {dt_s}, {width_px}")
    flow = np.asarray(flow, dtype=np.float32)
    mag = np.sqrt(flow[..., 0] ** 2 + flow[..., 1] ** 2) / (float(width_px) * float(dt_s))
    return finite32(mag)


def motion_score(mag: np.ndarray) -> float:
    """A frame's motion: the mean magnitude, frame widths per second (0 for an empty map)."""
    mag = np.asarray(mag, dtype=np.float64)
    return float(mag.mean()) if mag.size else 0.0


def is_static(prev_gray: np.ndarray, gray: np.ndarray, *, params: AirflowParams = AirflowParams()) -> bool:
    """True when nothing moved between two frames beyond noise: under ``static_fraction`` of the pixels
    differ by more than a level, ``static_level`` or, where higher, ``static_noise`` x the pair's noise
    as the difference's spread (see AirflowParams).

    The pair's noise (:func:`~autohaptics.imaging.noise_sd`) is the least of the difference's and each
    frame's x sqrt(2): texture reads as noise in a frame's own estimate and motion in the difference's,
    film grain (new every frame) in all three. It counts up to :data:`GRAIN_MOST` per frame: grain of sd 8
    on a 640 px picture reads 2-4 on its proxy, and "noise" past 6 is a picture's own fine texture (gravel,
    leaves), which must not hide its motion. It is estimated only for a pair that changed beyond
    ``static_level`` but not beyond the level that bound allows: the first frame's, then the second's and
    the difference's while each could still raise the level (a clean frame reads too little).
    """
    a, b = as_gray(prev_gray), as_gray(gray)
    if a.shape != b.shape:
        return False
    diff = cv2.absdiff(a, b)
    if float((diff > params.static_level).mean()) < params.static_fraction:
        return True  # a higher level changes nothing
    k = float(params.static_noise)
    most = k * math.sqrt(2) * GRAIN_MOST  # the highest level any noise raises it to
    if not most > params.static_level or float((diff > most).mean()) >= params.static_fraction:
        return False  # changed beyond that too: moving whatever the noise (no estimate needed)
    clean = params.static_level / (k * math.sqrt(2))  # a frame's noise that leaves the level where it is
    response_a = noise_response(a)
    if not noise_over(response_a, clean):
        return False  # a clean frame (most of them), told by one count
    response_b = noise_response(b)
    if not noise_over(response_b, clean):
        return False
    noise = min(math.sqrt(2) * min(noise_sd(response_a), noise_sd(response_b)),
                noise_sd(response_a - response_b))  # int16 responses: |difference| <= 8160
    level = min(k * noise, most)
    return level > params.static_level and float((diff > level).mean()) < params.static_fraction


def is_fade(prev_gray: np.ndarray, gray: np.ndarray, *, params: AirflowParams = AirflowParams()) -> bool:
    """True when two frames differ only by a global change of brightness and contrast (a fade, a
    flash, an exposure change), or are both too flat to hold any motion: there is no motion to read.

    Optical flow assumes constant brightness and reads such a change as motion (module docstring:
    the BBB opening's fade in from black read 0.3-0.9 frame widths/s at 640 px). Frames whose luma
    standard deviation is below ``flat_std`` are flat; otherwise the higher-contrast frame's
    brightness and contrast are mapped linearly onto the other's, and the pair is a fade when the
    mean brightness moved by at least ``fade_min_step`` grey levels and the mapped pair is static
    (``is_static``). A cut into or out of black is a cut first (:mod:`autohaptics.airflow.cuts`, checked
    before); a dark picture straight after black counts as a fade (no flow to read across it).
    """
    a, b = as_gray(prev_gray), as_gray(gray)
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
