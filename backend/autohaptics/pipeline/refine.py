"""Incremental refinement: the saliency a derive lacks, computed for just those ticks.

The analysis computes saliency only where the chair vibrates (``video.skip``), so a derive at a
lower threshold wakes ticks whose fusion weights it must estimate (``fusion.modes.weights_for``).
:func:`refine` computes exactly those: it decodes only the frames that stand for the ticks lacking
saliency (seeking to the keyframe before each run of them), reuses every other cached array, and
merges the new weights into the cache. Which ticks vibrate comes from the derived timeline's
intensity, whatever the intensity rule; the result equals a fresh analysis at the same parameters
(the same frames, proxies and saliency maps) when ``saliency.motion_weight`` is 0.
"""

from __future__ import annotations

import dataclasses
import time
from pathlib import Path

import numpy as np

from autohaptics import media
from autohaptics.media.overlays import Overlays
from autohaptics.params import GenerateParams
from autohaptics.pipeline.cache import Analysis
from autohaptics.pipeline.ticks import VideoAnalysis
from autohaptics.pipeline.video import frame_weights
from autohaptics.progress import CancelToken, ProgressFn, null_progress


def frame_sources(frame_mask: np.ndarray) -> np.ndarray:
    """Per tick, the tick whose analysed frame stands for it (itself when it has a frame of its
    own, else the analysed tick before it; -1 before the first frame), int64 [shape=(n,)]."""
    idx = np.where(frame_mask, np.arange(frame_mask.size), -1)
    return np.maximum.accumulate(idx) if idx.size else idx.astype(np.int64)


def lacking_saliency(video: VideoAnalysis | None, wanted: np.ndarray) -> np.ndarray:
    """The ticks of ``wanted`` (bool [shape=(n,)], those that vibrate) without saliency of their
    own or held from their frame, that a refinement can give them (a tick before the film's first
    frame has none to analyse). All False without a picture."""
    if video is None:
        return np.zeros(wanted.size, bool)
    return wanted & ~video.saliency_mask & (frame_sources(video.frame_mask) >= 0)


def refinable(params: GenerateParams) -> bool:
    """Whether :func:`refine` reproduces a fresh analysis for ``params``: multimodal with skipping
    (otherwise the analysis computed every tick's saliency) and no motion cue in the saliency map
    (it compares a frame with the frame analysed before it, which a refinement changes)."""
    return params.mode == "multimodal" and bool(params.video.skip) and params.saliency.motion_weight == 0


def refine(path: str | Path, analysis: Analysis, params: GenerateParams, wanted: np.ndarray, *,
           progress: ProgressFn | None = None, cancel: CancelToken | None = None) -> Analysis:
    """``analysis`` with the saliency of the ticks of ``wanted`` that lack it computed and merged
    (a new :class:`Analysis`; the given one is not modified). ``analysis`` must be reusable for
    ``params`` (:func:`~autohaptics.pipeline.cache.reusable`) and ``path`` its media file.

    ``stats["refine"]`` accumulates over refinements: ``runs`` (refinements that computed
    something), ``ticks`` (ticks given saliency), ``frames`` (frames analysed), ``seconds``.
    """
    progress = progress or null_progress
    video = analysis.video
    lacking = lacking_saliency(video, np.asarray(wanted, bool))
    if not lacking.any():
        progress("done", 1.0)
        return analysis
    t0 = time.perf_counter()
    sources = frame_sources(video.frame_mask)
    targets = np.unique(sources[lacking])
    progress("saliency", 0.0)
    info = media.probe(path)
    weights = frame_weights(info, analysis.n_ticks, targets, params=params, cancel=cancel,
                            need_flow="fans" in params.tracks, need_colour="temperature" in params.tracks,
                            decode=video.stats.get("frames", {}).get("decode"),
                            overlays=Overlays.from_stats(video.stats.get("overlays")))
    beta, have = video.beta.copy(), video.saliency_mask.copy()
    if weights:  # each analysed tick and the ticks that hold its frame's values take its weights
        keys = np.fromiter(sorted(weights), np.int64, len(weights))
        rows = np.flatnonzero(np.isin(sources, keys))
        beta[rows] = np.stack([weights[int(k)] for k in keys])[np.searchsorted(keys, sources[rows])]
        have[rows] = True
    stats = dict(analysis.stats)
    done = dict(stats.get("refine", {"runs": 0, "ticks": 0, "frames": 0, "seconds": 0.0}))
    done.update(runs=done["runs"] + 1, ticks=done["ticks"] + int((have & ~video.saliency_mask).sum()),
                frames=done["frames"] + len(weights),
                seconds=round(done["seconds"] + time.perf_counter() - t0, 4))
    stats["refine"] = done
    progress("done", 1.0)
    return dataclasses.replace(analysis, video=dataclasses.replace(video, beta=beta, saliency_mask=have),
                               stats=stats)
