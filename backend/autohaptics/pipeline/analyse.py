"""The analysis: decode each stream once and compute the feature cache, skipping what a scene does
not need.

The audio pass computes the four psychoacoustic features per 20 ms frame, in a forked child beside
the video pass (one after the other where a process cannot fork). Which ticks need saliency follows
from the audio intensity (saliency only where the chair vibrates, unless the mode needs every
tick), so the video pass decides its analysed frames' saliency in order once the audio says
(:mod:`.saliency_queue`).
"""

from __future__ import annotations

import dataclasses
import hashlib
import logging
import threading
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

from autohaptics import intensity as inten
from autohaptics import media
from autohaptics.errors import MediaError
from autohaptics.intensity import features as af
from autohaptics.params import GenerateParams
from autohaptics.pipeline.cache import Analysis
from autohaptics.pipeline.child import Child, ChildFailed, can_fork
from autohaptics.pipeline.saliency_queue import AbandonedMask, LaterMask
from autohaptics.pipeline.ticks import VideoAnalysis
from autohaptics.pipeline.video import video_pass
from autohaptics.progress import CancelToken, ProgressFn, check_cancel, null_progress
from autohaptics.records import params_to_dict
from autohaptics.timebase import FRAMES_PER_TICK, n_ticks as ticks_for

log = logging.getLogger(__name__)
_AUDIO_SHARE = 0.15  # share of the progress bar given to the audio pass when there is video


def file_sha256(path: str | Path, *, chunk: int = 1 << 20, stop: threading.Event | None = None) -> str:
    """SHA-256 of a file, read in 1 MiB chunks; "" when ``stop`` is set before the end."""
    h = hashlib.sha256()
    with open(path, "rb") as fh:
        while True:
            if stop is not None and stop.is_set():
                return ""
            b = fh.read(chunk)
            if not b:
                break
            h.update(b)
    return h.hexdigest()


class _HashBeside:
    """A file's SHA-256 computed in a thread while the passes run: reading and hashing let go of the
    interpreter lock, and a film of tens of GB takes a minute to hash, which then no longer stands
    before the passes. :meth:`result` waits for it; :meth:`abandon` stops it."""

    def __init__(self, path: str | Path):
        self._stop = threading.Event()
        self._value: str | None = None
        self._error: BaseException | None = None
        self.seconds = 0.0
        self._thread = threading.Thread(target=self._run, args=(path,), name="autohaptics-hash", daemon=True)
        self._thread.start()

    def _run(self, path: str | Path) -> None:
        t0 = time.perf_counter()
        try:
            self._value = file_sha256(path, stop=self._stop)
        except BaseException as exc:  # handed to the caller by result()
            self._error = exc
        self.seconds = time.perf_counter() - t0

    def result(self) -> str:
        self._thread.join()
        if self._error is not None:
            raise self._error
        return self._value

    def abandon(self) -> None:
        self._stop.set()
        self._thread.join()


def analyse(path: str | Path, params: GenerateParams | None = None, *, progress: ProgressFn | None = None,
            cancel: CancelToken | None = None, info: media.MediaInfo | None = None,
            between_passes: Callable[[], Any] | None = None) -> Analysis:
    """Decode ``path`` once per stream and compute the feature cache.

    between_passes : called after each pass (the process's owner returns freed memory there).
    Raises MediaError for unusable input (missing, not media, truncated, no audio in audio mode).
    """
    params = params or GenerateParams()
    info = info or media.probe(path)
    n = ticks_for(info.duration_s)
    stats: dict[str, Any] = {}
    hashing = _HashBeside(path)
    try:
        audio, video = _passes(info, params, n, stats, progress or null_progress, cancel, between_passes)
    except BaseException:
        hashing.abandon()
        raise
    sha = hashing.result()
    stats["hash"] = {"seconds": hashing.seconds}
    return Analysis(info=info.to_dict(), sha256=sha, n_ticks=n, params=params_to_dict(params),
                    audio=audio, video=video, stats=stats)


def _passes(info: media.MediaInfo, params: GenerateParams, n: int, stats: dict, progress: ProgressFn,
            cancel: CancelToken | None, between_passes: Callable[[], Any] | None):
    """The passes of :func:`analyse`, each where it can run; the truncation check. Returns (audio, video)."""
    check_cancel(cancel)

    need_colour = "temperature" in params.tracks and info.video is not None
    need_flow = "fans" in params.tracks and info.video is not None
    need_vib = "vibration" in params.tracks
    if info.audio is None and params.mode == "audio" and need_vib:
        raise MediaError(f"{info.path}: no audio stream (mode 'audio' needs one)")
    if info.video is None and params.mode == "visual" and need_vib:
        raise MediaError(f"{info.path}: no video stream (mode 'visual' needs one)")
    needs = dict(need_vib=need_vib, need_colour=need_colour, need_flow=need_flow)
    # the audio pass in a child process beside the video pass, at any length (on 2 cores the decoder
    # leaves the analysis time to spare); one after the other where a process cannot fork
    beside = info.audio is not None and (need_colour or need_flow) and can_fork()
    if beside:
        try:
            audio, video = _both_passes(info, params, n, stats, progress, cancel, **needs)
        except ChildFailed as exc:  # the child was killed (e.g. out of memory): the passes in turn
            log.warning("%s: the audio pass beside the video pass failed (%s); analysing in turn", info.path, exc)
            beside = False
    if not beside:
        audio, video = _one_after_the_other(info, params, n, stats, progress, cancel, between_passes, **needs)
    if between_passes is not None and video is not None:
        between_passes()
    if not params.allow_truncated:
        _check_truncation(info, audio_end=stats["audio"].get("decoded_s") if audio is not None else None,
                          video_end=(video.stats["frames"]["last_time_s"] + 1.0 / max(info.video.fps, 1.0))
                          if video is not None else None)
    progress("done", 1.0)
    return audio, video


def _one_after_the_other(info: media.MediaInfo, params: GenerateParams, n: int, stats: dict, progress: ProgressFn,
                         cancel: CancelToken | None, between_passes: Callable[[], Any] | None, *, need_vib: bool,
                         need_colour: bool, need_flow: bool):
    """The audio pass, then the video pass where a track needs the picture. Returns (audio, video)."""
    audio = video = None
    audio_share = _AUDIO_SHARE if info.video is not None else 1.0
    if info.audio is None:
        stats["audio"] = {"skipped": "no audio stream"}
    else:
        audio = _audio_pass(info, params, n, stats, progress, cancel, share=audio_share)
        if between_passes is not None:
            between_passes()
    need_saliency = _saliency_needed(params, audio, n) if (need_vib and info.video is not None) else np.zeros(n, bool)
    if info.video is None:
        stats["video"] = {"skipped": "no video stream"}
    elif need_colour or need_flow or need_saliency.any():
        video = _video_pass(info, params, n, stats, _share_of(progress, audio_share, 1.0), cancel,
                            need_saliency=need_saliency, need_colour=need_colour, need_flow=need_flow)
    else:
        stats["video"] = {"skipped": "no track needs the picture"}
    return audio, video


def _share_of(progress: ProgressFn, start: float, end: float) -> ProgressFn:
    """``progress`` for a part of the run that fills ``start``..``end`` of the bar."""
    return lambda stage, fraction: progress(stage, start + (end - start) * fraction)


def _video_pass(info: media.MediaInfo, params: GenerateParams, n: int, stats: dict, progress: ProgressFn,
                cancel: CancelToken | None, **needs) -> VideoAnalysis:
    t0 = time.perf_counter()
    video = video_pass(info, n, params=params, progress=progress, cancel=cancel, **needs)
    stats["video"] = {"seconds": time.perf_counter() - t0, **video.stats}
    return video


def _both_passes(info: media.MediaInfo, params: GenerateParams, n: int, stats: dict, progress: ProgressFn,
                 cancel: CancelToken | None, *, need_vib: bool, need_colour: bool, need_flow: bool):
    """The audio pass in a forked child beside the video pass, with the same results as one after
    the other (:mod:`.saliency_queue`). Returns (audio features, VideoAnalysis)."""
    later = LaterMask()
    heard = [0.0]  # the audio pass's own fraction done

    def audio_job(report):
        audio_stats: dict = {}
        audio = _audio_pass(info, params, n, audio_stats, lambda _s, f: report(f / _AUDIO_SHARE), None,
                            share=_AUDIO_SHARE)
        return audio, audio_stats["audio"], _saliency_needed(params, audio, n) if need_vib else np.zeros(n, bool)

    def video_progress(stage: str, fraction: float) -> None:
        if (failed := child.failure()) is not None:
            raise failed  # the audio pass failed: the film cannot be analysed, stop now
        progress(stage, _AUDIO_SHARE * heard[0] + (1.0 - _AUDIO_SHARE) * fraction)

    video_stats: dict = {}
    with Child(audio_job, on_progress=lambda f: heard.__setitem__(0, f),
               on_result=lambda value: later.set(value[2]), on_end=later.close) as child:
        try:
            video = _video_pass(info, params, n, video_stats, video_progress, cancel, need_saliency=later,
                                need_colour=need_colour, need_flow=need_flow)
        except AbandonedMask:
            child.result()  # the audio pass's own error: it is why the mask was abandoned
            raise
        audio, stats["audio"], _ = child.result(cancel)
    stats["video"] = video_stats["video"]
    return audio, video


def _check_truncation(info: media.MediaInfo, *, audio_end: float | None, video_end: float | None) -> None:
    """MediaError when the decoded streams end clearly before the file says they should.

    A file cut short ends every stream early; a film whose audio simply outlasts its picture (or
    the reverse) is not truncated: the LATEST decoded end is compared with the container's
    duration. A stream decoded alone is compared with its own declared duration when the
    container gives one (else with the container's, when it is the only stream).
    """
    ends = {name: end for name, end in (("audio", audio_end), ("video", video_end)) if end is not None}
    if not ends:
        return
    if len(ends) == 2 or (info.audio is None) != (info.video is None):
        name = max(ends, key=ends.get)
        media.check_truncation(info, ends[name], name if len(ends) == 1 else "audio and video")
        return
    (name, end), = ends.items()
    declared = getattr(info, name).duration_s
    if declared:
        media.check_truncation(dataclasses.replace(info, duration_s=declared), end, name)


def _saliency_needed(params: GenerateParams, audio: dict | None, n: int) -> np.ndarray:
    """Ticks whose saliency the mode needs: every tick for "visual" (and for "multimodal" without
    skipping); for "multimodal" every tick the threshold sliders could make vibrate (all four at
    0: the loudness gate and silence still decide), so a threshold commit finds its weights in the
    cache instead of decoding again (docs/BENCHMARKS.md, "Saliency up front"); none otherwise."""
    if params.mode == "visual" or (params.mode == "multimodal" and not params.video.skip):
        return np.ones(n, bool)
    if params.mode != "multimodal" or audio is None:
        return np.zeros(n, bool)
    floor = dataclasses.replace(params.intensity, thresholds={name: 0.0 for name in inten.FEATURES}, density=None)
    return inten.audio_intensity(audio, n, params=floor)[0] > 0


def _audio_pass(info: media.MediaInfo, params: GenerateParams, n: int, stats: dict,
                progress: ProgressFn, cancel: CancelToken | None, *, share: float) -> dict[str, np.ndarray]:
    t0 = time.perf_counter()
    report = media.AudioReport()
    duration = info.duration_s

    def chunk_progress(seconds_done: float) -> None:
        check_cancel(cancel)
        progress("audio", share * min(1.0, seconds_done / duration))

    chunks = media.iter_audio(info.path, info=info, lfe_gain_db=params.lfe_gain_db, report=report)
    feats = af.compute_audio_features(chunks, params=params.audio, progress=chunk_progress, cancel=cancel)
    n_frames = n * FRAMES_PER_TICK
    out = {}
    for name in inten.FEATURES:
        x = np.asarray(getattr(feats, name), dtype=np.float64)
        x = np.where(np.isfinite(x), np.maximum(x, 0.0), 0.0)
        if x.size < n_frames:
            x = np.concatenate([x, np.zeros(n_frames - x.size)])
        out[name] = x[:n_frames]
    stats["audio"] = {
        "seconds": time.perf_counter() - t0, "frames": int(n_frames), "decoded_s": round(report.duration_s, 4),
        "nonfinite_samples_repaired": report.nonfinite_samples, "decode_errors": report.decode_errors,
        "downmix": {"main_channels": report.main_channels, "lfe_channel": report.lfe_channel,
                    "weights": report.downmix_weights, "lfe_gain_db": params.lfe_gain_db},
    }
    return out
