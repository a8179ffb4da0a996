"""The active picture: the rectangle of a film's frames inside constant black bars (a letterbox,
a pillarbox or both, a windowbox), so every stage reads the picture and never the bars.

:func:`active_area` decides from a few sampled frames' luma (pure, numpy in); :func:`sample_lumas`
reads those frames (keyframes spread over the film, each a seek and one decoded frame);
:func:`find_active_area` is both. A row (column) belongs to the picture when, in at least one
sample, a good share of its pixels are brighter than black: the maximum over the samples sees
through dark scenes, night shots and fades to black (a bar is black in every sample), and burnt-in
subtitles in a bar light too small a share of its rows to count. Bars are accepted on an axis only
when they are clearly bars (both sides at least ``MIN_BAR`` of the size and roughly equal);
otherwise that axis keeps the full frame, as a film without bars does.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import av
import cv2
import numpy as np

from autohaptics.media.frames import Frame
from autohaptics.media.probe import MediaInfo, norm_rotation, open_container, stream_by_index

Rect = tuple[int, int, int, int]  # (x, y, width, height) px in display orientation

SAMPLES = 9  # frames sampled, spread evenly over the film
BLACK_LEVEL = 12  # full-range luma 0..255: brighter than this is lit (a bar: about 0, +-3 of noise)
COVER_SHARE = 0.5  # a row or column is picture when its largest lit share reaches this share of the best one's
MIN_BAR = 0.015  # a bar covers at least this fraction of the size (1.85:1 in 16:9 leaves 1.9 % per side)
BAR_BALANCE = 0.5  # the smaller bar of an axis is at least this fraction of the larger


def active_area(lumas: Sequence[np.ndarray], *, black_level: float = BLACK_LEVEL, cover_share: float = COVER_SHARE,
                min_bar: float = MIN_BAR, balance: float = BAR_BALANCE) -> Rect:
    """The picture inside black bars of frames whose full-range luma ``lumas`` holds (each uint8
    [shape=(height, width)], 0..255, display orientation, all one size).

    Per sample, each row's (column's) share of pixels above ``black_level``; its largest over the
    samples is its cover. The bar on each side is the run of outer rows (columns) whose cover is
    below ``cover_share`` x the largest cover of the axis, rounded up to even px (the crop errs
    into the picture). An axis keeps its full size unless both bars are at least ``min_bar`` of
    it and the smaller is at least ``balance`` x the larger.
    Returns (x, y, width, height) px; (0, 0, width, height) when there are no bars or no sample.
    """
    if not lumas:
        raise ValueError("active_area needs at least one sampled frame")
    h, w = lumas[0].shape[:2]
    rows, cols = np.zeros(h), np.zeros(w)
    for luma in lumas:
        if luma.shape[:2] != (h, w):
            raise ValueError(f"sampled frames differ in size: {luma.shape[:2]} and {(h, w)}")
        lit = (luma > black_level).view(np.uint8)
        np.maximum(rows, cv2.reduce(lit, 1, cv2.REDUCE_AVG, dtype=cv2.CV_32F)[:, 0], out=rows)
        np.maximum(cols, cv2.reduce(lit, 0, cv2.REDUCE_AVG, dtype=cv2.CV_32F)[0], out=cols)
    y, hh = _axis(rows, cover_share, min_bar, balance)
    x, ww = _axis(cols, cover_share, min_bar, balance)
    return x, y, ww, hh


def _axis(cover: np.ndarray, share: float, min_bar: float, balance: float) -> tuple[int, int]:
    """(start, length) px of the picture along one axis from its rows' (columns') cover."""
    n = cover.size
    best = float(cover.max()) if n else 0.0
    if best <= 0.0:
        return 0, n
    picture = np.flatnonzero(cover >= share * best)
    lead, trail = int(picture[0]), int(n - 1 - picture[-1])
    lead, trail = lead + lead % 2, trail + trail % 2
    if min(lead, trail) < max(2, min_bar * n) or min(lead, trail) < balance * max(lead, trail):
        return 0, n
    return lead, n - lead - trail


def sample_lumas(info: MediaInfo, samples: int = SAMPLES) -> list[np.ndarray]:
    """The full-range luma (uint8 [shape=(height, width)], display orientation) of up to
    ``samples`` keyframes spread evenly over the film: at each of the times (i + 0.5) / samples
    of the duration, the keyframe at or before it, or the first keyframe after it not sampled yet
    (before the next time). Only those keyframes are decoded (a seek, reading packets, one
    picture each), so a film with fewer keyframes than ``samples`` (a clip of a few seconds)
    gives fewer samples; a keyframe that fails to decode is passed over."""
    if info.video is None:
        return []
    n = max(1, int(samples))
    times = [(i + 0.5) / n * max(info.duration_s, 0.0) for i in range(n)] + [math.inf]
    out: list[np.ndarray] = []
    seen: set = set()
    with open_container(info.path) as c:
        stream = stream_by_index(c, info.video.index)
        stream.thread_type = "SLICE"  # no frame threads: a keyframe's picture comes out of its own packet
        base = stream.time_base or 0
        for i in range(n):
            if base:
                c.seek(int((times[i] + info.start_s) / base), backward=True, any_frame=False, stream=stream)
            frame = _next_keyframe(c, stream, seen, (times[i + 1] + info.start_s) / base if base else math.inf)
            if frame is not None:
                rotation = norm_rotation(getattr(frame, "rotation", info.video.rotation))
                out.append(Frame(frame, i, times[i], rotation).luma())
    return out


def _next_keyframe(c, stream, seen: set, before_pts: float):
    """The picture of the first keyframe packet read from ``c`` (after a seek) whose timestamp is
    not in ``seen`` (then added) and is below ``before_pts``; None when there is none."""
    try:
        for pkt in c.demux(stream):
            if pkt.pts is None:
                if pkt.size == 0:
                    return None  # the end
                continue
            if pkt.pts >= before_pts:
                return None
            if not pkt.is_keyframe or pkt.pts in seen:
                continue
            seen.add(pkt.pts)
            frames = list(stream.codec_context.decode(pkt)) + list(stream.codec_context.decode(None))
            stream.codec_context.flush_buffers()
            if frames:
                return frames[0]
    except av.error.FFmpegError:
        stream.codec_context.flush_buffers()
    return None


def find_active_area(info: MediaInfo, samples: int = SAMPLES) -> Rect:
    """The active picture of ``info``'s video (:func:`active_area` of :func:`sample_lumas`); the
    full frame when nothing could be sampled."""
    lumas = sample_lumas(info, samples)
    if not lumas:
        w, h = info.video.display_size if info.video is not None else (0, 0)
        return 0, 0, int(w), int(h)
    return active_area(lumas)
