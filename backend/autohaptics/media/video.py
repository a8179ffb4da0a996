"""Decoding the video stream: every frame, or only the reference frames, optionally ahead of the
caller in a background thread. Nothing is converted here (:mod:`autohaptics.media.frames`)."""

from __future__ import annotations

import math
import os
import queue
import sys
import threading
from collections.abc import Callable, Iterator

from autohaptics.errors import MediaError, ParameterError
from autohaptics.media import clock
from autohaptics.media.frames import Frame
from autohaptics.media.probe import AudioReport, MediaInfo, decode_tolerant, norm_rotation, open_container, probe, stream_by_index


DECODE_MODES = ("full", "nonref", "fast", "sparse")
# "sparse" skips every B-frame (reference or not) only from this frame rate up: with an encoder's
# usual 3 B-frames per reference frame the I/P-frames alone still come at 10 fps or more there,
# one per 100 ms tick; below it "sparse" decodes like "fast".
SPARSE_MIN_FPS = 40.0
# from this rate up to SPARSE_MIN_FPS a stream may hold a film shown by repeated pictures (24 or 25 fps
# at 30): "nonref" and "fast" decode every frame there, since the repeats are told from each frame's
# difference to the one before (airflow.cadence) and a skipped B-frame hides them. From 40 fps up the
# pipeline asks for every frame only where a few stretches show repeats (pipeline.picture.decode_mode).
REPEAT_MIN_FPS = 29.0
# the interpreter's switch interval while a decoding thread runs beside the caller, s: each return of
# that thread from FFmpeg needs the interpreter lock, which a caller busy in Python otherwise keeps
# for up to the default 5 ms (300 1080p frames decoded beside a Python loop: 5.9 s instead of 1.2 s
# alone, 2.1 s at 1 ms); docs/BENCHMARKS.md, "Full-frame 1080p", eleventh stop
SWITCH_INTERVAL_S = 0.001
# "nonref" and "fast" skip the non-reference frames only while the frames decoded stay at most this many
# frame intervals apart (one frame skipped between two: x264's B-frames). From the first wider gap on,
# every frame is decoded: MPEG-2's two B-frames between references, or x265's four with one of them a
# reference, leave gaps of 3 frames (125 ms at 24 fps, longer than a tick), so ticks go without their
# own frame and flow pairs span three frames (docs/BENCHMARKS.md, "Stop 55").
SKIP_GAP_MAX = 2.5


def iter_video(path: str | os.PathLike, *, info: MediaInfo | None = None, prefetch: int = 0,
               decode: str = "full", start_s: float = 0.0,
               prepare: Callable[[Frame], None] | None = None,
               crop: tuple[int, int, int, int] | None = None, shown_aspect: float | None = None) -> Iterator[Frame]:
    """Decode the video stream frame by frame (presentation order); nothing is converted here.

    decode : "full" decodes every frame exactly; "nonref" asks FFmpeg to skip non-reference frames (in
        H.264/HEVC typically the B-frames: about half the frames; formats without them, such as VP8 or
        intra-only video, decode every frame), the others exactly; "fast" also skips the in-loop deblocking
        filter (invisible on small proxies, not decoded exactly); "sparse" (the fast preset) also skips the
        reference B-frames at ``SPARSE_MIN_FPS`` and above (H.264 B-pyramids; only I- and P-frames are decoded,
        about a quarter of the frames at 60 fps): a P-frame that used a skipped B-frame as reference comes out
        approximate (mean 3, at most 5.6 grey levels off on the shared 1080p60 clip). Frames keep their true
        timestamps. No frame is skipped in a variable-rate stream, nor, but in "sparse", at 29 to 40 fps (a
        film's repeats) or after skipping left two frames in a row out (``SKIP_GAP_MAX``; "sparse" below 40 fps).
    prefetch : when > 0, decode in a background thread up to this many frames ahead, so the decoder keeps
        working while the caller analyses a frame (PyAV releases the GIL while decoding); FFmpeg then gets
        its threads by :func:`decoder_threads`. Frames stay valid after the step that yielded them then.
    start_s : when > 0, seek to the keyframe at or before this time (s) first; the frames then
        decode exactly as in a pass from the start, but ``Frame.index`` counts from the seek.
    prepare : with ``prefetch``, called on each frame in the decoding thread while that thread is
        at least half the queue ahead of the caller (it has time to spare), e.g.
        :meth:`Frame.prepare`, so the work runs beside the caller's analysis; never when the
        caller waits for frames. ``Frame.ahead``: the queue was still half full when it was taken.
    crop : (x, y, width, height) px in display orientation, even: each frame is that rectangle of
        the picture (:class:`Frame`; e.g. the active picture of :func:`autohaptics.media.active.find_active_area`).
    shown_aspect : that picture's width / height on screen, which its proxies keep (:class:`Frame`).
    Raises MediaError when there is no video stream or no frame decodes.
    """
    info = info or probe(path)
    if info.video is None:
        raise MediaError(f"{info.path}: no video stream")
    if decode not in DECODE_MODES:
        raise ParameterError(f"decode must be one of {DECODE_MODES}, got {decode!r}")
    if prefetch > 0:
        yield from _prefetched(lambda: _iter_video(info, decode, start_s, True, crop, shown_aspect), prefetch,
                               prepare)
    else:
        yield from _iter_video(info, decode, start_s, crop=crop, shown_aspect=shown_aspect)


def decoder_threads(stream, decode: str, fps: float) -> int:
    """FFmpeg's decoder threads for frames decoded ahead of an analysis that holds one core.

    One fewer than the cores (on 2 cores: one thread, without frame threading's hand-overs) where
    the decoder has the lighter load: it skips the non-reference frames of a stream with B-frames
    below ``SPARSE_MIN_FPS``. Else 0, FFmpeg's own count: an intra-only or P-only stream decodes
    every frame, and from 40 fps there are four or more frames per tick (docs/BENCHMARKS.md, issue 21).
    """
    if decode not in ("nonref", "fast") or not stream.codec_context.has_b_frames or not 0 < fps < SPARSE_MIN_FPS:
        return 0
    try:
        cores = len(os.sched_getaffinity(0))
    except (AttributeError, OSError):
        cores = os.cpu_count() or 1
    return max(1, cores - 1)


def _iter_video(info: MediaInfo, decode: str = "full", start_s: float = 0.0, beside: bool = False,
                crop: tuple[int, int, int, int] | None = None, shown_aspect: float | None = None) -> Iterator[Frame]:
    """The frames of :func:`iter_video`. beside : decoded ahead of an analysis (:func:`decoder_threads`).

    Where skipping the non-reference frames leaves a gap wider than ``SKIP_GAP_MAX`` the stream is
    opened again to decode every frame (with the decoder threads of a full decode) from the keyframe
    before the last frame given, and goes on after that frame."""
    report = AudioReport()
    n = 0
    last_t = -math.inf
    resume_after = None  # after a reopening: the frames up to this time were given already
    skip_allowed = True
    while True:
        with open_container(info.path) as c:
            stream = stream_by_index(c, info.video.index)
            watch_gaps = _configure(stream, info, decode, beside, skip_allowed)
            seek_s = start_s if resume_after is None else resume_after
            if seek_s > 0:
                clock.seek(c, stream, info.clock, seek_s + info.start_s)
            for frame in decode_tolerant(c, stream, report, info.path, clock=info.clock):
                t = float(frame.time) - info.start_s if frame.time is not None else n / max(info.video.fps, 1e-9)
                if resume_after is not None:
                    if t <= resume_after:
                        continue
                    resume_after = None
                if t <= last_t:  # broken timestamps: keep frames ordered
                    t = last_t + 1.0 / max(info.video.fps, 1e-9)
                if watch_gaps and n and (t - last_t) * info.video.fps > SKIP_GAP_MAX:
                    resume_after = last_t
                    break
                last_t = t
                yield Frame(frame, n, t, norm_rotation(getattr(frame, "rotation", info.video.rotation)), crop,
                            shown_aspect, (info.video.width, info.video.height))
                n += 1
        if resume_after is None:
            break
        skip_allowed = False
    if n == 0:
        reason = f" ({report.first_error})" if report.first_error else ""
        raise MediaError(f"{info.path}: the video stream holds no decodable frames{reason}")


def _configure(stream, info: MediaInfo, decode: str, beside: bool, skip_allowed: bool = True) -> bool:
    """Set ``stream``'s decoder up for ``decode`` (:func:`iter_video`); True where it skips the
    non-reference frames, so the gaps between the frames it gives are to be watched (``SKIP_GAP_MAX``).
    skip_allowed : False decodes every frame whatever ``decode`` says (its loop filter as it says)."""
    stream.thread_type = "AUTO"
    # a variable-rate stream's frames are already few and irregular: skipping some leaves gaps of 0.1-0.3 s
    skips = skip_allowed and decode in ("nonref", "fast", "sparse") and not info.video.variable_rate \
        and (decode == "sparse" or not REPEAT_MIN_FPS <= info.video.fps < SPARSE_MIN_FPS)
    sparse = skips and decode == "sparse" and info.video.fps >= SPARSE_MIN_FPS
    if skips:
        stream.codec_context.skip_frame = "BIDIR" if sparse else "NONREF"
        if sparse:
            # a chain of P-frames gains nothing from frame threads (each waits for the one
            # before; measured: 2.49 s, one thread 2.42 s); slice threads do where the encoder
            # cut frames into slices (1.52 s on the 30 s 1080p BBB loop) and cost nothing where not
            stream.thread_type = "SLICE"
    threads = decoder_threads(stream, decode if skips else "full", info.video.fps) if beside else 0
    if threads:
        stream.codec_context.thread_count = threads
    if decode in ("fast", "sparse"):
        stream.codec_context.options = {"skip_loop_filter": "all"}
    return skips and not sparse and info.video.fps > 0


_END = object()


def _prefetched(make_iter, depth: int, prepare: Callable | None = None) -> Iterator[Frame]:
    """Run an iterator of frames in a daemon thread, ``depth`` items ahead; exceptions reach the
    consumer; closing the consumer stops the producer. ``prepare(item)`` runs in that thread on the
    items made while the queue is at least half full; an item taken while it still is gets
    ``ahead`` set. Meanwhile the interpreter's switch interval is at most ``SWITCH_INTERVAL_S``."""
    q: queue.Queue = queue.Queue(maxsize=depth)
    stop = threading.Event()

    def produce():
        try:
            for item in make_iter():
                if prepare is not None and 2 * q.qsize() >= depth:
                    prepare(item)
                while not stop.is_set():
                    try:
                        q.put(item, timeout=0.1)
                        break
                    except queue.Full:
                        continue
                if stop.is_set():
                    return
            q.put(_END)
        except BaseException as exc:  # handed to the consumer, re-raised there
            q.put(exc)

    worker = threading.Thread(target=produce, name="autohaptics-decode", daemon=True)
    worker.start()
    switch = sys.getswitchinterval()
    sys.setswitchinterval(min(switch, SWITCH_INTERVAL_S))
    try:
        while True:
            item = q.get()
            if item is _END:
                return
            if isinstance(item, BaseException):
                raise item
            item.ahead = 2 * q.qsize() >= depth
            yield item
    finally:
        stop.set()
        while worker.is_alive():
            try:
                q.get(timeout=0.05)
            except queue.Empty:
                pass
        worker.join()
        if sys.getswitchinterval() == min(switch, SWITCH_INTERVAL_S):  # not already restored by another pass
            sys.setswitchinterval(switch)

