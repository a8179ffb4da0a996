"""The video pass: which frames are analysed, at what size, and which stages run on them.

Per 100 ms tick k the pass takes the decoded frame nearest the tick's centre (``analysis="tick"``)
and the frame that follows it (for optical flow over one frame interval), or every decoded frame
(``analysis="every"``, the reference: colour, motion and depth are averaged over the tick's
frames; saliency stays on the centre frame, because averaging salient positions across a tick
would put weight where no object ever was). It computes, per tick:

- ``mean_rgb``   mean colour of the frame (thermal), float32 [shape=(n, 3)], 0..255
- ``cut``        a hard cut happens at tick k (against the previous tick's frame, or inside the flow pair)
- ``static``     the flow pair is identical up to noise (no flow computed)
- ``motion``     mean flow magnitude, frame widths per second, float32 [shape=(n,)]
- ``cell_motion`` per fan cell, frame widths per second, float16 [shape=(n, 9, 17)] (3 digits are
  plenty; a 2-hour film's grids stay at 22 MB each)
- ``nearness``   per fan cell, 0..1 (1 = near), only where depth ran, float16 [shape=(n, 9, 17)]
- ``beta``       actuator weights from saliency fusion, 0..1, only where saliency ran, [shape=(n, 9)]

What is skipped (``skip=True``): saliency where the audio intensity is zero (unless the mode
needs every tick), optical flow on static pairs and across cuts, depth where the motion is below
the airflow floor. Frames are converted to proxies only when a stage runs on them. A tick without
a frame of its own (a frame rate below 10 fps, or a later tick of a group with ``stride`` > 1)
holds the values of the analysed tick before it.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field, replace

import cv2
import numpy as np

from autohaptics import airflow, cuts, depth, fusion, media, saliency, thermal
from autohaptics.errors import ParameterError
from autohaptics.layout import FAN_COLS, FAN_ROWS, N_ACTUATORS
from autohaptics.progress import CancelToken, ProgressFn, check_cancel
from autohaptics.timebase import TICK_S, tick_of_time

ANALYSIS_MODES = ("tick", "every")
# Cut signatures are always taken from an RGB proxy this wide, so every two frames compare alike
# (a histogram of a 128 px proxy is wider than one of a 48 px proxy of the same picture).
SIGNATURE_WIDTH = 48


@dataclass(frozen=True)
class VideoParams:
    """Which frames the video pass analyses. Proxy sizes are the stages' own parameters: the gray
    proxy (static check, flow, in-pair cuts) is ``flow.width_for(picture width)`` wide (at least
    ``flow.proxy_width``; recorded as ``stats["flow"]["proxy_width"]``), the RGB proxy (colour,
    saliency, depth, cuts between ticks) is ``max(saliency.proxy_width, depth.proxy_width)`` wide,
    except that the spectral saliency (which reads the full frame's luma at 64 x 64) counts with
    at most the gray proxy's width: its map is made ``saliency.proxy_width`` wide from that proxy.

    analysis : "tick" (one frame plus its successor per 100 ms tick) or "every" (every decoded
        frame; the reference preset).
    skip : skip what a scene does not need (see the module docstring). False computes everything.
    prefetch : frames decoded ahead in a background thread, overlapping decoding with analysis
        (0 = decode in the calling thread).
    decode : "full" (every frame, exactly), "nonref" (default: FFmpeg skips non-reference frames,
        about half the decoding work on H.264; the frames it decodes are exact), "fast" (also skips
        the deblocking filter) or "sparse" (the fast preset: also every B-frame at 40 fps and up,
        so P-frames that referenced one come out approximate; see :func:`media.iter_video`).
        With skipped frames the analysed frame is the decoded one nearest the tick's centre and a
        flow pair spans the next decoded frame, with its true interval.
    stride : ticks per analysed frame, 1..10 (default 1; the fast preset: 3). With ``stride`` s the
        ticks are taken in groups of s, the frame nearest the group's centre is analysed (plus its
        successor for flow) and every tick of the group gets its values: the picture is read at
        10/s Hz instead of 10 Hz, and each tick's frame is at most s x 50 ms off its own centre.
        Audio features stay at 10 Hz. Only with ``analysis="tick"``.
    """

    analysis: str = "tick"
    skip: bool = True
    prefetch: int = 8
    decode: str = "nonref"
    stride: int = 1

    def __post_init__(self):
        if self.decode not in media.DECODE_MODES:
            raise ParameterError(f"video.decode must be one of {media.DECODE_MODES}, got {self.decode!r}")
        if not (0 <= int(self.prefetch) <= 256):
            raise ParameterError(f"video.prefetch must lie in 0..256 frames, got {self.prefetch!r}")
        if self.analysis not in ANALYSIS_MODES:
            raise ParameterError(f"video.analysis must be one of {ANALYSIS_MODES}, got {self.analysis!r}")
        if isinstance(self.stride, bool) or not isinstance(self.stride, int) or not (1 <= self.stride <= 10):
            raise ParameterError(f"video.stride must be a whole number of ticks in 1..10, got {self.stride!r}")
        if self.stride > 1 and self.analysis != "tick":
            raise ParameterError(f"video.stride={self.stride} needs video.analysis='tick' "
                                 f"(the 'every' analysis reads every frame), got {self.analysis!r}")


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

    ARRAYS = ("mean_rgb", "cut", "static", "motion", "cell_motion", "nearness", "depth_mask", "flow_mask",
              "beta", "saliency_mask", "frame_mask")

    @classmethod
    def empty(cls, n: int) -> "VideoAnalysis":
        return cls(
            mean_rgb=np.zeros((n, 3), np.float32), cut=np.zeros(n, bool), static=np.zeros(n, bool),
            motion=np.zeros(n, np.float32), cell_motion=np.zeros((n, FAN_ROWS, FAN_COLS), np.float16),
            nearness=np.zeros((n, FAN_ROWS, FAN_COLS), np.float16), depth_mask=np.zeros(n, bool),
            flow_mask=np.zeros(n, bool), beta=np.zeros((n, N_ACTUATORS), np.float32),
            saliency_mask=np.zeros(n, bool), frame_mask=np.zeros(n, bool))

    def arrays(self) -> dict[str, np.ndarray]:
        return {name: getattr(self, name) for name in self.ARRAYS}

    @classmethod
    def from_arrays(cls, arrays: dict[str, np.ndarray], stats: dict | None = None) -> "VideoAnalysis":
        return cls(**{name: arrays[name] for name in cls.ARRAYS}, stats=stats or {})


class _Stage:
    """Seconds and tick counts of one stage."""

    def __init__(self):
        self.seconds = 0.0
        self.computed = 0

    def run(self, fn, *args, **kwargs):
        t0 = time.perf_counter()
        try:
            return fn(*args, **kwargs)
        finally:
            self.seconds += time.perf_counter() - t0
            self.computed += 1


def video_pass(info: media.MediaInfo, n: int, *, video: VideoParams, saliency_params: saliency.SaliencyParams,
               fusion_params: fusion.FusionParams, flow_params: airflow.FlowParams,
               airflow_params: airflow.AirflowParams, cut_params: cuts.CutParams, depth_params: depth.DepthParams,
               need_saliency: np.ndarray, need_flow: bool, need_colour: bool,
               progress: ProgressFn | None = None, cancel: CancelToken | None = None) -> VideoAnalysis:
    """Decode the video once and run the per-tick stages (module docstring).

    need_saliency : bool [shape=(n,)], ticks whose saliency is needed (already reflects skipping).
    need_flow : compute motion and depth at all (the fans track is wanted).
    need_colour : compute the mean colour (the temperature track is wanted).
    """
    out = VideoAnalysis.empty(n)
    if info.video is not None:  # the gray proxy's width follows the picture's (FlowParams.width_for)
        flow_params = replace(flow_params, proxy_width=flow_params.width_for(info.video.display_size[0]))
    stages = {name: _Stage() for name in
              ("decode_wait", "proxy", "cuts", "static", "colour", "saliency", "flow", "depth")}
    sal_backend = saliency.make_saliency_backend(saliency_params) if need_saliency.any() else None
    depth_backend = depth.make_depth_backend(depth_params) if need_flow else None
    floor = float(airflow_params.floor) if video.skip else -1.0
    sal_luma_size = saliency.working_size(saliency_params)
    # a backend fed the full frame's luma (spectral) needs only the proxy's size for its map: its
    # RGB proxy is then not made wider than the luma it is resampled from
    sal_width = saliency_params.proxy_width if sal_luma_size is None else min(
        saliency_params.proxy_width, flow_params.proxy_width)
    rgb_width = max(sal_width, depth_params.proxy_width if need_flow else 0)
    every = video.analysis == "every"
    duration = max(info.duration_s, 1e-9)

    prev_sig = None  # signature of the previous analysed frame (cut detection)
    prev_sal_gray = None  # luma of the previous saliency proxy (the saliency motion cue)
    pending = None  # (tick, gray, rgb, sig, time) waiting for its successor frame (flow pair)
    acc = _Accumulator(out)
    last_time = 0.0
    stream = media.iter_video(info.path, info=info, prefetch=video.prefetch, decode=video.decode)
    timer = {"t": time.perf_counter()}

    def timed_frames():
        for f in stream:
            stages["decode_wait"].seconds += time.perf_counter() - timer["t"]
            yield f
            timer["t"] = time.perf_counter()

    stride = int(video.stride)
    for frame, centre_tick in _centre_frames(timed_frames(), n, stride):
        last_time = frame.time_s
        k = min(int(tick_of_time(frame.time_s)), n - 1)
        analyse_this = k >= 0 and (centre_tick is not None or every)
        is_successor = pending is not None
        if not (analyse_this or is_successor):
            continue
        if centre_tick is not None:
            k = centre_tick
        want_sal = centre_tick is not None and bool(need_saliency[k:k + stride].any())
        rgb = sig_rgb = luma = None
        if analyse_this and (need_colour or want_sal or need_flow):
            if want_sal and sal_luma_size is not None:
                rgb, gray, luma = stages["proxy"].run(frame.rgb_and_gray, rgb_width, flow_params.proxy_width,
                                                      luma_size=sal_luma_size)
            else:
                rgb, gray = stages["proxy"].run(frame.rgb_and_gray, rgb_width, flow_params.proxy_width)
            sig_rgb = _resized(rgb, SIGNATURE_WIDTH)
        else:
            gray = stages["proxy"].run(frame.gray, flow_params.proxy_width)
        sig = stages["cuts"].run(cuts.frame_signature, sig_rgb) if sig_rgb is not None else None
        if is_successor:
            pk, pgray, prgb, psig, pt = pending
            pending = None
            dt = max(frame.time_s - pt, 1e-3)

            def successor_sig(frame=frame, sig=sig):
                # colour matters for the in-pair cut check (a green and a grey shot can share their
                # luma); read only when the pair moves enough to matter
                return sig if sig is not None else stages["cuts"].run(
                    cuts.frame_signature, stages["proxy"].run(frame.proxy, SIGNATURE_WIDTH))

            _flow_pair(pk, pgray, gray, prgb, psig, successor_sig, dt, out, acc, stages, flow_params,
                       airflow_params, cut_params, depth_params, depth_backend, floor, video.skip)
        if analyse_this:
            out.frame_mask[k] = True
            if sig is None:
                sig = stages["cuts"].run(cuts.frame_signature, gray)
            if prev_sig is not None and prev_sig.shape == sig.shape and cuts.is_cut(prev_sig, sig, params=cut_params):
                out.cut[k] = True
            prev_sig = sig
            if need_colour:
                acc.add_colour(k, stages["colour"].run(thermal.mean_colour, rgb))
            if want_sal:
                # no wider than the picture itself: upsampling a 64 px film to a 256 px map adds
                # nothing but work (16x the pixels on each of a 2-hour film's 72,000 ticks)
                sal_rgb = _resized(rgb, min(saliency_params.proxy_width, max(1, frame.width)))
                sal_gray = cv2.cvtColor(sal_rgb, cv2.COLOR_RGB2GRAY) if saliency_params.motion_weight > 0 else None
                smap = stages["saliency"].run(saliency.saliency_map, sal_rgb, params=saliency_params,
                                              backend=sal_backend, prev_gray=prev_sal_gray, luma=luma)
                prev_sal_gray = sal_gray
                acc.add_beta(k, fusion.actuator_weights(smap, params=fusion_params))
            if need_flow:
                pending = (k, gray, rgb, sig, frame.time_s)
        if frame.index % 16 == 0:
            check_cancel(cancel)
            if progress is not None:
                progress("video", min(1.0, frame.time_s / duration))

    acc.finish()
    if pending is not None and pending[0] > 0 and acc.motion_n[pending[0]] == 0:
        # the clip ended before the last analysed frame's successor: its motion is unknown, so the
        # tick holds the previous analysed one's (the rule for ticks without a frame of their own)
        k = pending[0]
        before = np.flatnonzero(out.frame_mask[:k])
        if before.size:
            for name in ("motion", "cell_motion", "nearness", "depth_mask", "static"):
                getattr(out, name)[k] = getattr(out, name)[before[-1]]
    computed = {"saliency": out.saliency_mask.copy(), "flow": out.flow_mask.copy(), "depth": out.depth_mask.copy()}
    sources = _hold_missing(out)
    out.stats = {
        name: {"seconds": round(st.seconds, 4), "computed": st.computed} for name, st in stages.items()
    }
    for name, mask in computed.items():
        # held: ticks without a frame of their own (stride, or a frame rate below 10 fps) that
        # took the values of the analysed tick before them, where that tick computed the stage;
        # one that copied a tick which skipped the stage counts as skipped
        done, held = int(mask.sum()), int(mask[sources].sum())
        out.stats[name].update({"ticks_computed": done, "ticks_held": held, "ticks_skipped": int(n - done - held)})
    out.stats["flow"]["proxy_width"] = int(flow_params.proxy_width)
    out.stats["static"]["ticks_static"] = int(out.static.sum())
    out.stats["cuts"]["cuts"] = int(out.cut.sum())
    out.stats["frames"] = {"ticks_with_frame": int(out.frame_mask.sum()), "ticks": n,
                           "last_time_s": round(last_time, 6)}
    return out


def _centre_frames(frames, n: int, stride: int = 1):
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


def _flow_pair(k, gray0, gray1, rgb0, sig0, successor_sig, dt, out: VideoAnalysis, acc: "_Accumulator", stages,
               flow_params, airflow_params, cut_params, depth_params, depth_backend, floor, skip) -> None:
    """Motion (and depth when the motion is high enough) for tick k from one frame pair.

    Cut checks: luma first (cheap, both proxies are there); when the pair moves past the floor,
    colour too (``successor_sig()`` reads the successor's colour only then)."""
    if cuts.is_cut(cuts.frame_signature(gray0), cuts.frame_signature(gray1), params=cut_params):
        out.cut[k] = True
        return
    if (skip and stages["static"].run(airflow.is_static, gray0, gray1, params=airflow_params)) or \
            stages["static"].run(airflow.is_fade, gray0, gray1, params=airflow_params):
        out.static[k] = True  # nothing moved beyond noise, or only the brightness changed (a fade)
        acc.add_motion(k, 0.0, np.zeros((FAN_ROWS, FAN_COLS), np.float32))
        return
    flow = stages["flow"].run(airflow.optical_flow, gray0, gray1, params=flow_params)
    mag = airflow.motion_magnitude(flow, dt_s=dt, width_px=gray0.shape[1])
    score = airflow.motion_score(mag)
    if score > floor:
        sig1 = successor_sig()
        if sig0 is not None and sig0.shape == sig1.shape and cuts.is_cut(sig0, sig1, params=cut_params):
            out.cut[k] = True
            return
    cells = airflow.cell_motion(mag)
    out.flow_mask[k] = True
    acc.add_motion(k, score, cells)
    if score > floor:
        near = stages["depth"].run(depth.nearness_map, _resized(rgb0, depth_params.proxy_width),
                                   params=depth_params, backend=depth_backend, flow=flow, dt_s=dt)
        acc.add_near(k, airflow.grid_means(near))
        out.depth_mask[k] = True


def _resized(rgb: np.ndarray, width: int) -> np.ndarray:
    """``rgb`` scaled to ``width`` px (aspect kept); the same array when it already has that width."""
    h, w = rgb.shape[:2]
    if w == width:
        return rgb
    height = max(1, int(round(width * h / w)))
    return cv2.resize(rgb, (width, height), interpolation=cv2.INTER_AREA if width < w else cv2.INTER_LINEAR)


class _Accumulator:
    """Per-tick sums written straight into the output arrays (several frames per tick in the
    'every' analysis), divided by the counts at the end: no second set of (n, 9, 17) arrays."""

    def __init__(self, out: VideoAnalysis):
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


def _hold_missing(out: VideoAnalysis) -> np.ndarray:
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
    for name in ("mean_rgb", "motion", "cell_motion", "nearness", "depth_mask", "beta", "saliency_mask", "static"):
        arr = getattr(out, name)
        arr[rows] = arr[src[rows]]
    return src[rows]
