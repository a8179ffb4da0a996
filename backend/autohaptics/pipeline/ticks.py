"""The video pass's ticks: which decoded frame is analysed for each (:func:`centre_frames`), and its
per-tick results (:class:`VideoAnalysis`): several frames' values summed
into one tick and divided at the end (:class:`TickSums`), and the ticks without a frame of their
own filled from the analysed tick before them (:func:`hold_missing`)."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from autohaptics.airflow import cuts
from autohaptics.layout import FAN_COLS, FAN_ROWS, N_ACTUATORS
from autohaptics.timebase import TICK_S, tick_of_time


@dataclass
class VideoAnalysis:
    """Per-tick results of the video pass (see the module docstring for units)."""

    mean_rgb: np.ndarray
    cut: np.ndarray
    static: np.ndarray
    motion: np.ndarray
    cell_motion: np.ndarray
    nearness: np.ndarray
    depth_mask: np.ndarray
    flow_mask: np.ndarray
    beta: np.ndarray
    saliency_mask: np.ndarray
    frame_mask: np.ndarray
    stats: dict = field(default_factory=dict)
    signature: np.ndarray | None = None

    ARRAYS = ("mean_rgb", "cut", "static", "motion", "cell_motion", "nearness", "depth_mask", "flow_mask",
              "beta", "saliency_mask", "frame_mask")
    OPTIONAL = ("signature",)  # absent from older caches

    @classmethod
    def empty(cls, n: int) -> "VideoAnalysis":
        return cls(
            mean_rgb=np.zeros((n, 3), np.float32), cut=np.zeros(n, bool), static=np.zeros(n, bool),
            motion=np.zeros(n, np.float32), cell_motion=np.zeros((n, FAN_ROWS, FAN_COLS), np.float16),
            nearness=np.zeros((n, FAN_ROWS, FAN_COLS), np.float16), depth_mask=np.zeros(n, bool),
            flow_mask=np.zeros(n, bool), beta=np.zeros((n, N_ACTUATORS), np.float32),
            saliency_mask=np.zeros(n, bool), frame_mask=np.zeros(n, bool),
            signature=np.zeros((n, cuts.PACKED_SIZE), np.uint8))

    def arrays(self) -> dict[str, np.ndarray]:
        out = {name: getattr(self, name) for name in self.ARRAYS}
        out.update({name: getattr(self, name) for name in self.OPTIONAL if getattr(self, name) is not None})
        return out

    @classmethod
    def from_arrays(cls, arrays: dict[str, np.ndarray], stats: dict | None = None) -> "VideoAnalysis":
        return cls(**{name: arrays[name] for name in cls.ARRAYS}, stats=stats or {},
                   **{name: arrays[name] for name in cls.OPTIONAL if name in arrays})


class TickSums:
    """Per-tick sums written straight into the output arrays (several frames per tick in the
    'every' analysis), divided by the counts at the end: no second set of (n, 9, 17) arrays."""

    def __init__(self, out):
        self.out = out
        n = out.motion.size
        self.colour_n = np.zeros(n, np.int32)
        self.beta_n = np.zeros(n, np.int32)
        self.motion_n = np.zeros(n, np.int32)
        self.near_n = np.zeros(n, np.int32)

    def add_colour(self, k, rgb_mean):
        self.out.mean_rgb[k] += rgb_mean
        self.colour_n[k] += 1

    def add_beta(self, k, beta):
        self.out.beta[k] += beta
        self.beta_n[k] += 1

    def add_motion(self, k, score, cells):
        self.out.motion[k] += score
        self.out.cell_motion[k] += cells
        self.motion_n[k] += 1

    def add_near(self, k, near):
        self.out.nearness[k] += near
        self.near_n[k] += 1

    def add_pair(self, k, res) -> None:
        """A flow pair's :class:`~autohaptics.airflow.pair.PairMotion` for tick ``k``: a cut, or its
        motion (static or moving) and its nearness where depth ran."""
        out = self.out
        if res.cut:
            out.cut[k] = True
            return
        if res.static:
            out.static[k] = True  # nothing moved beyond noise, or only the brightness changed (a fade)
        else:
            out.flow_mask[k] = True
        self.add_motion(k, res.score, res.cells)
        if res.near is not None:
            self.add_near(k, res.near)
            out.depth_mask[k] = True

    def finish(self) -> None:
        out = self.out

        def mean(arr, count):
            many = count > 1
            if many.any():
                arr[many] /= count[many].reshape((-1,) + (1,) * (arr.ndim - 1)).astype(arr.dtype)
            return count > 0

        mean(out.mean_rgb, self.colour_n)
        ok = mean(out.beta, self.beta_n)
        many = self.beta_n > 1
        if many.any():  # the mean of several frames' weights: strongest actuator back to 1
            peak = out.beta[many].max(axis=1, keepdims=True)
            out.beta[many] = np.where(peak > 0, out.beta[many] / np.maximum(peak, 1e-12), out.beta[many])
        out.saliency_mask[:] = ok
        mean(out.motion, self.motion_n)
        mean(out.cell_motion, self.motion_n)
        mean(out.nearness, self.near_n)


def hold_missing(out) -> np.ndarray:
    """Ticks without a frame of their own (``video.stride`` > 1, a frame rate below 10 fps) take the
    values of the analysed tick before them. Returns the analysed tick each filled tick copied,
    int [shape=(filled,)]."""
    missing = ~out.frame_mask
    if not missing.any() or not out.frame_mask.any():
        return np.zeros(0, np.int64)
    idx = np.where(out.frame_mask, np.arange(out.frame_mask.size), -1)
    src = np.maximum.accumulate(idx)
    fill = missing & (src >= 0)
    rows = np.flatnonzero(fill)
    for name in ("mean_rgb", "motion", "cell_motion", "nearness", "depth_mask", "beta", "saliency_mask", "static",
                 "signature"):
        arr = getattr(out, name)
        if arr is not None:
            arr[rows] = arr[src[rows]]
    return src[rows]


def centre_frames(frames, n: int, stride: int = 1):
    """Yield every frame once, in order, as (frame, tick) where ``tick`` is the tick whose CENTRE
    (0.1 k + 0.05 s) this frame is nearest to among the tick's frames, else (frame, None).

    The vibration of tick k goes with the picture at that instant, so that is the frame analysed
    for it (saliency; colour and flow too in the tick analysis); the frame is known one frame late
    (one frame of look-ahead). With ``stride`` s > 1 the ticks go in groups of s (the last one may
    be shorter): the frame nearest the group's centre is chosen, and ``tick`` is the group's first.
    """
    held = None  # (frame, tick): the best candidate so far for its tick (group), not yet yielded
    done = -1  # last tick (group's first tick) whose frame was chosen
    for f in frames:
        k = min(int(tick_of_time(f.time_s)), n - 1)
        if stride > 1 and k >= 0:
            k -= k % stride
        if held is not None:
            hf, hk = held
            centre = (hk + 0.5 * min(stride, n - hk)) * TICK_S
            if k == hk and abs(f.time_s - centre) < abs(hf.time_s - centre):
                yield hf, None
                held = (f, k)
                continue
            yield hf, hk
            done = hk
            held = None
        if k > done and k >= 0:
            held = (f, k)
        else:
            yield f, None
    if held is not None:
        yield held
