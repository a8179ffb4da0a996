"""The video pass: which frames are analysed, at what size, and which stages run on them.

Per 100 ms tick k the pass takes the decoded frame nearest the tick's centre (``video.analysis``
"tick") and the frame that follows it (a flow pair over one frame interval), or every decoded
frame ("every", the reference: colour, motion and depth are averaged over the tick's frames;
saliency stays on the centre frame, because averaging salient positions across a tick would put
weight where no object ever was). Results per tick (:class:`~.ticks.VideoAnalysis`):

- ``mean_rgb``   mean colour, float32 [shape=(n, 3)], 0..255 (temperature)
- ``cut``, ``static``  a hard cut at tick k; the flow pair is identical up to noise (no flow)
- ``motion``     mean flow magnitude, frame widths/s, float32 [shape=(n,)]
- ``cell_motion``, ``nearness``  per fan cell, float16 [shape=(n, 9, 17)] (nearness only where depth ran)
- ``beta``       actuator weights from saliency fusion, 0..1, only where saliency ran, [shape=(n, 9)]
- ``signature``  the analysed frame's cut signature, packed (``cuts.pack_signature``), uint8
  [shape=(n, 192)], zeros where none (shot detection); None in caches written before it existed

Skipping (``video.skip``): saliency where the audio intensity is zero (unless the mode needs every
tick), flow on static pairs and across cuts, depth where the motion is below the airflow floor. Proxies
are made only when a stage runs, from the active picture (``video.active_area``: the rectangle inside
black bars, found before the pass; ``stats["active_area"]``), so no stage reads the bars; overlays burnt
in over it (``video.overlays``, ``stats["overlays"]``) are filled in each proxy. A film too short to
search before the pass is searched by it, shot by shot (:class:`~.picture.ShotSampler`), and run again
with what it finds filled. A tick without a frame of its own (below 10 fps, or a later tick of a
``video.stride`` group) holds the values of the analysed tick before it.
"""

from __future__ import annotations

import time
from collections import deque
from dataclasses import dataclass, replace

import cv2
import numpy as np

from autohaptics import fusion, media
from autohaptics.airflow import cuts, depth
from autohaptics.airflow.cadence import Cadence
from autohaptics.airflow.flow import is_static
from autohaptics.airflow.pair import PairParams
from autohaptics.fusion import saliency
from autohaptics.imaging import resized
from autohaptics.params import GenerateParams
from autohaptics.pipeline.pairs import PairJudge
from autohaptics.media.overlays import Overlays
from autohaptics.pipeline.picture import ShotSampler, decode_mode, read_picture, shown_aspect
from autohaptics.pipeline.saliency_queue import LaterMask, SaliencyQueue
from autohaptics.pipeline.ticks import TickSums, VideoAnalysis, centre_frames, hold_missing
from autohaptics.progress import CancelToken, ProgressFn, check_cancel
from autohaptics.temperature import mean_colour
from autohaptics.timebase import TICK_S, tick_of_time

# Cut signatures are always taken from an RGB proxy this wide, so every two frames compare alike
# (a histogram of a 128 px proxy is wider than one of a 48 px proxy of the same picture).
SIGNATURE_WIDTH = 48
SMALL_PICTURE_PX = 1280  # up to this width OpenCV runs single-threaded (docs/BENCHMARKS.md, issue 21)
STAGES = ("decode_wait", "proxy", "overlays", "cuts", "static", "colour", "saliency", "flow", "depth")


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


def video_pass(info: media.MediaInfo, n: int, *, params: GenerateParams, need_saliency: np.ndarray | LaterMask,
               need_flow: bool, need_colour: bool, progress: ProgressFn | None = None,
               cancel: CancelToken | None = None) -> VideoAnalysis:
    """Decode the video once and run the per-tick stages (module docstring).

    need_saliency : bool [shape=(n,)], ticks whose saliency is needed (already reflects skipping),
        or a :class:`LaterMask` another thread sets while the pass runs.
    need_flow : compute motion and depth at all (the fans track is wanted).
    need_colour : compute the mean colour (the temperature track is wanted).
    """
    threads = cv2.getNumThreads()
    if info.video is not None and info.video.display_size[0] <= SMALL_PICTURE_PX:
        cv2.setNumThreads(1)  # each call is small: OpenCV's worker threads would cost more than they give
    vp = None
    try:
        vp = _Pass(info, n, params, need_saliency, need_flow, need_colour, cancel=cancel)
        share = 0.5 if vp.sampler is not None else 1.0  # the second half of the bar for a pass run again
        out = _run(vp, info, params, progress, cancel, 0.0, share)
        found = vp.sampler.found() if vp.sampler is not None else None
        if found is None:
            return out
        vp.pairs.close()
        vp = _Pass(info, n, params, need_saliency, need_flow, need_colour, cancel=cancel, decode=vp.decode, overlays=found)
        vp.found_by = "pass"
        return _run(vp, info, params, progress, cancel, share, 1.0 - share)
    finally:
        if vp is not None:
            vp.pairs.close()
        cv2.setNumThreads(threads)


def _run(vp: _Pass, info: media.MediaInfo, params: GenerateParams, progress: ProgressFn | None,
         cancel: CancelToken | None, start: float, share: float) -> VideoAnalysis:
    """One pass over the decoded frames (progress from ``start``, ``share`` of the bar)."""
    stream = media.iter_video(info.path, info=info, prefetch=params.video.prefetch, decode=vp.decode,
                              prepare=vp.prepare, crop=vp.area, shown_aspect=vp.shown_aspect)
    duration = max(info.duration_s, 1e-9)
    for frame, centre_tick in centre_frames(vp.timed(stream), vp.n, int(params.video.stride)):
        vp.frame(frame, centre_tick)
        if frame.index % 16 == 0:
            check_cancel(cancel)
            if progress is not None:
                progress("video", start + share * min(1.0, frame.time_s / duration))
    return vp.finish()


@dataclass(frozen=True)
class _Successor:
    """What a held flow pair keeps of its successor frame: its time, s, and ``Frame.ahead``."""
    time_s: float
    ahead: bool


class _Pass:
    """One video pass's state: the stages' parameters and backends, the previous frame's cut
    signature and saliency luma, and the flow pair waiting for its successor frame."""

    def __init__(self, info: media.MediaInfo, n: int, params: GenerateParams, need_saliency: np.ndarray | LaterMask,
                 need_flow: bool, need_colour: bool, *, cancel: CancelToken | None = None, decode: str | None = None,
                 overlays: Overlays | None | str = "find"):
        """overlays : "find" (as ``video.overlays`` says, :func:`~.picture.read_picture`), or the ones to fill."""
        t0 = time.perf_counter()
        picture = read_picture(info, params if overlays == "find" else replace(
            params, video=replace(params.video, overlays="keep")))
        # (x, y, w, h) px read of each frame (None: all of it), and the 3D packing ("": 2D)
        self.area, self.stereo = picture.area, picture.packing
        self.overlays = picture.overlays if overlays == "find" else overlays
        self.found_by = "samples" if self.overlays is not None and overlays == "find" else ""
        self.sampler = ShotSampler() if picture.tally else None  # the pass's own search, shot by shot
        self.shown_aspect = shown_aspect(info, self.area, self.stereo)
        self.area_s = time.perf_counter() - t0
        self.decode = decode or decode_mode(info, params, need_flow)  # every frame for a film's conversion
        self.decode_s = time.perf_counter() - t0 - self.area_s
        self.frame_size = tuple(int(v) for v in info.video.display_size) if info.video is not None else (0, 0)
        flow_params = params.flow
        if info.video is not None:  # the gray proxy's width follows the picture's (FlowParams.width_for)
            width = self.area[2] if self.area is not None else info.video.display_size[0]
            flow_params = replace(flow_params, proxy_width=flow_params.width_for(width))
        self.n, self.params, self.flow_params = n, params, flow_params
        self.need_flow, self.need_colour = need_flow, need_colour
        self.stages = {name: _Stage() for name in STAGES}
        self.stride = int(params.video.stride)
        self.depth_backend = depth.make_depth_backend(params.depth) if need_flow else None
        pair_params = PairParams(flow=flow_params, airflow=params.airflow, cuts=params.cuts, depth=params.depth,
                                 floor=float(params.airflow.floor) if params.video.skip else -1.0, skip=params.video.skip)
        self.sal_luma_size = saliency.working_size(params.saliency)
        # a backend fed the full frame's luma (spectral) needs only the proxy's size for its map: its
        # RGB proxy is then not made wider than the luma it is resampled from
        sal_width = params.saliency.proxy_width if self.sal_luma_size is None else min(
            params.saliency.proxy_width, flow_params.proxy_width)
        self.rgb_width = max(sal_width, params.depth.proxy_width if need_flow else 0)
        self.every = params.video.analysis == "every"
        self.out = VideoAnalysis.empty(n)
        self.acc = TickSums(self.out)
        # without the motion cue a frame's weights depend on its own proxies alone: they may be
        # computed before the audio says whether they are needed (a long film's mask comes late)
        self.saliency = SaliencyQueue(need_saliency, self.weights, self.acc.add_beta, stride=self.stride,
                                      ahead=float(params.saliency.motion_weight) == 0.0, cancel=cancel)
        self.sal_backend = saliency.make_saliency_backend(params.saliency) if self.saliency.may_need() else None
        self.pairs = PairJudge(pair_params, self.acc.add_pair, depth_backend=self.depth_backend,
                               timer=lambda name, fn, *a, **kw: self.stages[name].run(fn, *a, **kw),
                               luma_signature=self.luma_signature, on_flow=self._flow_done)
        self.prev_sig = None  # signature of the previous analysed frame (cut detection)
        self.prev_sal_gray = None  # luma of the previous saliency proxy (the saliency motion cue)
        self.pending = None  # (tick, gray, rgb, sig, time) waiting for its successor frame (flow pair)
        self.luma_sigs: list = []  # (gray proxy, its cut signature) of the last two
        self.last_time = 0.0
        self.repeats = 0  # successor frames passed over as repeats of their pair's first frame
        fps = float(info.video.fps) if info.video is not None and info.video.fps else 0.0
        # a pair's least span, s; a variable-rate stream has no frame period to span: its next frame
        self.min_span_s = float(flow_params.min_span_frames) / fps if fps > 0 and not info.video.variable_rate else 0.0
        self.held: deque = deque()  # flow pairs waiting for their successors to be judged (cadence), oldest first
        self.between = None  # (frame, colour signature or None): the last pair's successor, if not analysed
        self.spread = 0  # changes between two ticks' frames read as a cut but spread over both steps
        self.cadence = Cadence(1.0 / fps if fps > 0 else 0.0, flow_params.cadence_ratio if need_flow else 0.0,
                               variable=info.video is not None and info.video.variable_rate)

    def prepare(self, frame: media.Frame) -> None:
        """Make a frame's gray, RGB and saliency luma planes ahead, in the decoding thread (the same
        arrays :meth:`_proxies` would make; a frame that needs none wastes them)."""
        frame.prepare(self.flow_params.proxy_width, self.rgb_width, self.sal_luma_size if self.sal_backend else None)

    def timed(self, stream):
        """``stream``'s frames, the time spent waiting for each counted as ``decode_wait``."""
        wait = self.stages["decode_wait"]
        t = time.perf_counter()
        for f in stream:
            wait.seconds += time.perf_counter() - t
            yield f
            t = time.perf_counter()

    def frame(self, frame: media.Frame, centre_tick: int | None) -> None:
        """Take one decoded frame: the successor of the waiting flow pair, an analysed frame, both or neither."""
        self.last_time = frame.time_s
        if self.cadence.ratio:
            self.cadence.add(frame.time_s, frame.luma_sample())
            settled = self.cadence.settled_s
            while self.held and self.held[0][1].time_s <= settled:  # its successor is judged now (a repeat or not)
                self._motion(*self.held.popleft())
        k = min(int(tick_of_time(frame.time_s)), self.n - 1)
        analyse_this = k >= 0 and (centre_tick is not None or self.every)
        # a successor closer than the pair's least span (flow.min_span_frames; in steps under repeats) is passed over
        span = self.cadence.least_span_s(self.flow_params.min_span_frames) if self.min_span_s and self.cadence.ratio \
            else self.min_span_s
        is_successor = self.pending is not None and (analyse_this or frame.time_s - self.pending[4] >= span)
        if not (analyse_this or is_successor):
            return
        if centre_tick is not None:
            k = centre_tick
        want_sal = centre_tick is not None and self.sal_backend is not None
        rgb, gray, luma, sig = self._proxies(frame, analyse_this, want_sal)
        if is_successor:
            self._pair(frame, gray, sig, analyse_this)
        if analyse_this:
            self._analyse(frame, k, rgb, gray, luma, sig, centre=centre_tick is not None)

    def _proxies(self, frame, analyse_this: bool, want_sal: bool):
        st, fw = self.stages, self.flow_params.proxy_width
        rgb = luma = None
        if analyse_this and (self.need_colour or want_sal or self.need_flow):
            if want_sal and self.sal_luma_size is not None:
                rgb, gray, luma = st["proxy"].run(frame.rgb_and_gray, self.rgb_width, fw, luma_size=self.sal_luma_size)
            else:
                rgb, gray = st["proxy"].run(frame.rgb_and_gray, self.rgb_width, fw)
        else:
            gray = st["proxy"].run(frame.gray, fw)
        if self.overlays is not None:
            rgb, gray, luma = (None if a is None else st["overlays"].run(self.overlays.fill, a) for a in (rgb, gray, luma))
        return rgb, gray, luma, None if rgb is None else self._signature(rgb)

    def _frame_signature(self, frame):
        """A frame's colour cut signature read from its gray plane (a frame not analysed has no RGB proxy)."""
        rgb = self.stages["proxy"].run(frame.rgb, self.rgb_width, self.flow_params.proxy_width)
        return self._signature(rgb if self.overlays is None else self.stages["overlays"].run(self.overlays.fill, rgb))

    def _signature(self, rgb):
        """A frame's colour cut signature from its RGB proxy (all at ``SIGNATURE_WIDTH``)."""
        return self.stages["cuts"].run(cuts.frame_signature, resized(rgb, SIGNATURE_WIDTH))

    def _pair(self, frame, gray, sig, analysed: bool) -> None:
        """The waiting flow pair's motion, now that its successor frame is here; or, when that frame
        repeats the pair's first one (a frame-rate conversion, pulldown), wait for the next frame
        (``flow.repeat_wait_s``; an analysed frame starts a pair of its own, so it never waits).
        With ``flow.cadence_ratio`` the pair is held until the frames after its successor tell
        whether that is a repeat (:mod:`autohaptics.airflow.cadence`, ``REACH`` frames): its time
        depends on that. A successor that cannot be judged (the frames before it skipped) is not held."""
        pgray, pt = self.pending[1], self.pending[4]
        if not analysed and frame.time_s - pt < self.flow_params.repeat_wait_s and \
                self.stages["static"].run(is_static, pgray, gray, params=self.params.airflow):
            self.repeats += 1
            return
        first, self.pending = self.pending, None
        self.between = None if analysed else (frame, sig)
        if self.held or self.cadence.judges_newest:  # pairs stay in order
            # held without its decoded frame (a decoder's buffers are few): the successor's signature now
            sig = sig if sig is not None else self._frame_signature(frame)
            self.held.append((first, _Successor(frame.time_s, frame.ahead), gray, sig))
        else:
            self._motion(first, frame, gray, sig)

    def _motion(self, first, frame, gray, sig) -> None:
        """A flow pair's motion and depth, added to its tick (:mod:`.pairs`)."""
        pk, pgray, prgb, psig, pt = first

        def successor_sig():  # colour matters for the in-pair cut check (a green and a grey shot
            # can share their luma): read only when the pair moves enough to matter, from its gray plane
            return sig if sig is not None else self._frame_signature(frame)

        self.pairs.add(pk, pgray, gray, prgb, psig, successor_sig, self.cadence.pair_time(pt, frame.time_s),
                       ahead=frame.ahead)

    def _flow_done(self, seconds: float) -> None:
        """A flow computed beside the pass (:mod:`.pairs`), counted with the pass's own."""
        self.stages["flow"].seconds += seconds
        self.stages["flow"].computed += 1

    def _analyse(self, frame, k: int, rgb, gray, luma, sig, *, centre: bool) -> None:
        """Colour, the cut against the previous analysed frame, saliency, and the flow pair to come."""
        out, st, params = self.out, self.stages, self.params
        out.frame_mask[k] = True
        if sig is None:
            sig = st["cuts"].run(cuts.frame_signature, gray)
        if self.prev_sig is not None and self.prev_sig.shape == sig.shape and \
                cuts.is_cut(self.prev_sig, sig, params=params.cuts) and self._cut_in_a_step(sig):
            out.cut[k] = True
        self.prev_sig, self.between = sig, None
        if self.sampler is not None:
            st["overlays"].run(self.sampler.add, k, frame.time_s, bool(out.cut[k]), gray)
        if centre or not out.signature[k].any():
            packed = cuts.pack_signature(sig)
            if packed is not None:
                out.signature[k] = packed
        if self.need_colour:
            self.acc.add_colour(k, st["colour"].run(mean_colour, rgb))
        if centre and self.sal_backend is not None:
            self.saliency.add(k, frame.width, rgb, luma)
        if self.need_flow:
            self.pending = (k, gray, rgb, sig, frame.time_s)

    def _cut_in_a_step(self, sig) -> bool:
        """Whether a change between the previous analysed frame and this one (``sig``) that reads as a
        cut also reads as one over one of the two steps through the frame decoded between them (the
        previous pair's successor), where there is one. Why: skipping decodes leave analysed frames up to
        4 frame intervals apart, over which fast action (a wing sweeping past) changes a picture as a cut
        does; a cut changes it within one step, or between the two fields of the frame between (3:2
        pulldown): docs/BENCHMARKS.md, "Stop 56"."""
        if self.between is None or not self.params.cuts.in_one_step:
            return True
        frame, mid = self.between
        mid = mid if mid is not None else self._frame_signature(frame)
        if mid.shape != sig.shape:
            return True
        cut = self.params.cuts
        if cuts.is_cut(self.prev_sig, mid, params=cut) or cuts.is_cut(mid, sig, params=cut):
            return True
        top, bottom = (self._signature(f) for f in frame.fields(self.rgb_width))  # a telecined frame at a
        if cuts.is_cut(top, bottom, params=cut):  # cut holds both shots, one in each field: a cut between them
            return True
        self.spread += 1
        return False

    def luma_signature(self, gray: np.ndarray) -> np.ndarray:
        """A gray proxy's cut signature, kept for the last two proxies (a successor frame that is
        also analysed starts the next pair with the same proxy)."""
        for held, sig in self.luma_sigs:
            if held is gray:
                return sig
        sig = cuts.frame_signature(gray)
        self.luma_sigs = [self.luma_sigs[-1], (gray, sig)] if self.luma_sigs else [(gray, sig)]
        return sig

    def weights(self, width: int, rgb, luma) -> np.ndarray:
        """The actuator weights of a frame ``width`` px wide from its saliency map (``rgb``, ``luma``:
        its proxies)."""
        params = self.params
        # no wider than the picture itself: upsampling a 64 px film to a 256 px map adds
        # nothing but work (16x the pixels on each of a 2-hour film's 72,000 ticks)
        sal_rgb = resized(rgb, min(params.saliency.proxy_width, max(1, width)))
        sal_gray = cv2.cvtColor(sal_rgb, cv2.COLOR_RGB2GRAY) if params.saliency.motion_weight > 0 else None
        smap = self.stages["saliency"].run(saliency.saliency_map, sal_rgb, params=params.saliency,
                                           backend=self.sal_backend, prev_gray=self.prev_sal_gray, luma=luma)
        self.prev_sal_gray = sal_gray
        return fusion.actuator_weights(smap, params=params.fusion)

    def finish(self) -> VideoAnalysis:
        """The per-tick results with their stats (ticks held, skipped, computed per stage)."""
        out, n = self.out, self.n
        self.cadence.finish()
        while self.held:  # the last pairs, their successors judged by the frames before them
            self._motion(*self.held.popleft())
        self.pairs.finish()
        self.saliency.finish(n)
        self.acc.finish()
        if self.pending is not None and self.pending[0] > 0 and self.acc.motion_n[self.pending[0]] == 0:
            # the clip ended before the last analysed frame's successor: its motion is unknown, so the
            # tick holds the previous analysed one's (the rule for ticks without a frame of their own)
            k = self.pending[0]
            before = np.flatnonzero(out.frame_mask[:k])
            if before.size:
                for name in ("motion", "cell_motion", "nearness", "depth_mask", "static"):
                    getattr(out, name)[k] = getattr(out, name)[before[-1]]
        computed = {"saliency": out.saliency_mask.copy(), "flow": out.flow_mask.copy(), "depth": out.depth_mask.copy()}
        sources = hold_missing(out)
        out.stats = {name: {"seconds": round(st.seconds, 4), "computed": st.computed} for name, st in self.stages.items()}
        for name, mask in computed.items():
            # held: ticks without a frame of their own that took the values of the analysed tick before
            # them, where that tick computed the stage; one that copied a tick which skipped it counts as skipped
            done, held = int(mask.sum()), int(mask[sources].sum())
            out.stats[name].update({"ticks_computed": done, "ticks_held": held, "ticks_skipped": int(n - done - held)})
        out.stats["saliency"].update({"weighed_ahead": self.saliency.weighed_ahead, "unused": self.saliency.unused})
        out.stats["flow"]["proxy_width"] = int(self.flow_params.proxy_width)
        out.stats["static"]["ticks_static"] = int(out.static.sum())
        out.stats["flow"]["repeats_skipped"] = int(self.repeats)
        out.stats["flow"]["cadence_repeats"] = int(self.cadence.found)
        out.stats["cuts"].update({"cuts": int(out.cut.sum()), "spread": int(self.spread)})
        out.stats["frames"] = {"ticks_with_frame": int(out.frame_mask.sum()), "ticks": n,
                               "last_time_s": round(self.last_time, 6), "decode": self.decode,
                               "decode_choice_s": round(self.decode_s, 4)}
        rect = self.area if self.area is not None else (0, 0, *self.frame_size)
        out.stats["active_area"] = {"rect": [int(v) for v in rect], "frame": list(self.frame_size),
                                    "mode": self.params.video.active_area, "stereo": self.stereo or "2d",
                                    "seconds": round(self.area_s, 4)}
        ov = self.overlays
        out.stats["overlays"] = {"mode": self.params.video.overlays, "found_by": self.found_by,
                                 "share": round(ov.share, 4) if ov is not None else 0.0,
                                 "translucent": round(ov.translucent, 4) if ov is not None else 0.0,
                                 "boxes": ov.boxes(*rect[2:]) if ov is not None else [],
                                 **(ov.to_stats() if ov is not None else {})}
        return out



def frame_weights(info: media.MediaInfo, n: int, ticks: np.ndarray, *, params: GenerateParams,
                  need_flow: bool, need_colour: bool, cancel: CancelToken | None = None,
                  group_s: float = 10.0, decode: str | None = None,
                  overlays: Overlays | None | str = "find") -> dict[int, np.ndarray]:
    """The actuator weights of the frames the video pass analyses for ``ticks`` (ticks with a frame
    of their own: the first of a ``video.stride`` group), decoding only around them.

    Each run of ticks (runs less than ``group_s`` seconds apart share one) is decoded from the
    keyframe before it; the proxies are made as in :func:`video_pass` with the same ``need_flow``
    and ``need_colour``, so the weights are the ones a full pass computes (with
    ``saliency.motion_weight`` 0: the motion cue depends on the frame analysed before). decode : the
    pass's ``stats["frames"]["decode"]`` (None: chosen again, :func:`~.picture.decode_mode`); overlays :
    the pass's (``Overlays.from_stats(stats["overlays"])``), or "find" them again. Returns {tick: float32 [shape=(9,)]}.
    """
    targets = np.unique(np.asarray(ticks, dtype=np.int64))
    mask = np.zeros(n, bool)
    mask[targets] = True
    vp = _Pass(info, n, params, mask, need_flow, need_colour, decode=decode, overlays=overlays)
    out: dict[int, np.ndarray] = {}
    breaks = np.flatnonzero(np.diff(targets) * TICK_S > group_s) + 1
    for run in np.split(targets, breaks) if targets.size else []:
        first, last = int(run[0]), int(run[-1])
        stream = media.iter_video(info.path, info=info, decode=vp.decode,
                                  start_s=max(0.0, (first - vp.stride - 1) * TICK_S), crop=vp.area,
                                  shown_aspect=vp.shown_aspect)
        try:
            for frame, k in centre_frames(stream, n, vp.stride):
                if frame.time_s > (last + vp.stride + 2) * TICK_S:
                    break
                if k is not None and mask[k] and k not in out:
                    rgb, _, luma, _ = vp._proxies(frame, True, True)
                    out[k] = vp.weights(frame.width, rgb, luma).astype(np.float32)
                    check_cancel(cancel)
        finally:
            stream.close()
    return out
