"""The active picture: the rectangle of a film's frames inside constant black bars (a letterbox,
a pillarbox or both, a windowbox), so every stage reads the picture and never the bars.

:func:`active_area` decides from a few sampled frames' luma (pure, numpy in); :func:`sample_lumas`
reads those frames (keyframes spread over the film, each a seek and one decoded frame);
:func:`find_active_area` is both; :func:`find_picture` also finds a 3D film's packing and reads one
view. A row (column) belongs to the picture when, in at least one sample, a good share of its pixels
are brighter than black: the maximum over the samples sees through dark scenes, night shots and
fades to black (a bar is black in every sample). Black is the bars' own level: a frame edge that is
flat and dark in every sample (video-range black read as full range, a lifted master: 16-30) lifts
it. Burnt-in subtitles in a bar light too small a share of its rows to count, or, bold or boxed, a
short stretch of rows apart from the picture by black ones. Bars are accepted on an axis only when
they are clearly bars (both sides at least ``MIN_BAR`` of the size and roughly equal); otherwise
that axis keeps the full frame, as a film without bars does.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import av
import cv2
import numpy as np

from autohaptics.errors import MediaError
from autohaptics.media import clock
from autohaptics.media.frames import Frame
from autohaptics.media.probe import AudioReport, MediaInfo, decode_tolerant, norm_rotation, open_container, stream_by_index
from autohaptics.media.stereo import MIN_SAMPLES, PACKINGS, SAME, SAME_FEW, halves, view_rect, views_alike
from autohaptics.quantiles import median, percentile

Rect = tuple[int, int, int, int]  # (x, y, width, height) px in display orientation

SAMPLES = 9  # frames sampled, spread evenly over the film
BLACK_LEVEL = 12  # full-range luma 0..255: brighter than this is lit (a bar: about 0, +-3 of noise)
COVER_SHARE = 0.5  # a row or column is picture when its largest lit share reaches this share of the best one's
MIN_BAR = 0.015  # a bar covers at least this fraction of the size (1.85:1 in 16:9 leaves 1.9 % per side)
BAR_BALANCE = 0.5  # the smaller bar of an axis is at least this fraction of the larger
EDGE = 2  # the outermost rows (columns) on each side that tell a bar's own level, px
BAR_MAX_LEVEL = 32  # full-range luma: a flat edge darker than this may be a bar (lifted blacks: 16-30)
BAR_SPREAD = 12  # a flat edge: 90 % of its pixels (all samples) lie within this of its median
BAR_MATCH = 4  # the two edges' medians differ by at most this (bars are one level; sky and ground are not)
GAP_COVER = 0.1  # a row (column) lit less than this share of the best one's parts picture from a bar's subtitle
STRAY = 0.25  # an outer lit stretch shorter than this share of the longest is not picture (a subtitle)
DARK_SHARE = 0.5  # keyframes lit on less than this share of their pixels, all of them: frames after are read too
FORWARD_FRAMES = 300  # at most this many frames decoded from the start for them
DETECT_WIDTH = 480  # px: the sampled pictures are looked at this wide for a 3D packing (:func:`picture_packing`)


def active_area(lumas: Sequence[np.ndarray], *, black_level: float = BLACK_LEVEL, cover_share: float = COVER_SHARE,
                min_bar: float = MIN_BAR, balance: float = BAR_BALANCE) -> Rect:
    """The picture inside black bars of frames whose full-range luma ``lumas`` holds (each uint8
    [shape=(height, width)], 0..255, display orientation, all one size).

    Per sample, each row's (column's) share of pixels above ``black_level`` plus the bars' level
    on that axis (:func:`bar_level`); its largest over the samples is its cover. The picture is
    what lies between the outermost rows (columns) whose cover reaches ``cover_share`` x the
    axis's largest, leaving out an outer stretch shorter than ``STRAY`` x the longest that black
    rows (cover below ``GAP_COVER`` x the largest) part from the rest; the bars are the rest,
    rounded up to even px (the crop errs into the picture). An axis keeps its full size unless
    both bars are at least ``min_bar`` of it and the smaller is at least ``balance`` x the larger.
    Returns (x, y, width, height) px; (0, 0, width, height) when there are no bars or no sample.
    """
    if not lumas:
        raise ValueError("active_area needs at least one sampled frame")
    h, w = lumas[0].shape[:2]
    if any(luma.shape[:2] != (h, w) for luma in lumas):
        raise ValueError(f"sampled frames differ in size: {[lu.shape[:2] for lu in lumas]}")
    rows, cols = np.zeros(h), np.zeros(w)
    row_black, col_black = black_level + bar_level(lumas, 0), black_level + bar_level(lumas, 1)
    for luma in lumas:
        lit = (luma > row_black).view(np.uint8)
        np.maximum(rows, cv2.reduce(lit, 1, cv2.REDUCE_AVG, dtype=cv2.CV_32F)[:, 0], out=rows)
        if col_black != row_black:
            lit = (luma > col_black).view(np.uint8)
        np.maximum(cols, cv2.reduce(lit, 0, cv2.REDUCE_AVG, dtype=cv2.CV_32F)[0], out=cols)
    y, hh = _axis(rows, cover_share, min_bar, balance)
    x, ww = _axis(cols, cover_share, min_bar, balance)
    return x, y, ww, hh


def bar_level(lumas: Sequence[np.ndarray], axis: int) -> float:
    """The level (full-range luma, 0..``BAR_MAX_LEVEL``) of the bars at both ends of ``axis`` (0:
    top and bottom, 1: left and right): the larger median of the two ``EDGE``-px edges over all
    samples when both are flat (``BAR_SPREAD``), dark and alike (``BAR_MATCH``); 0 otherwise (no
    bars there, or black)."""
    mids = []
    for side in (slice(0, EDGE), slice(-EDGE, None)):
        edge = np.concatenate([(lu[side] if axis == 0 else lu[:, side].T).ravel() for lu in lumas])
        lo, mid, hi = percentile(edge, (5, 50, 95))
        if mid > BAR_MAX_LEVEL or mid - lo > BAR_SPREAD or hi - mid > BAR_SPREAD:
            return 0.0
        mids.append(float(mid))
    return max(mids) if abs(mids[0] - mids[1]) <= BAR_MATCH else 0.0


def _axis(cover: np.ndarray, share: float, min_bar: float, balance: float) -> tuple[int, int]:
    """(start, length) px of the picture along one axis from its rows' (columns') cover."""
    n = cover.size
    best = float(cover.max()) if n else 0.0
    if best <= 0.0:
        return 0, n
    picture = np.flatnonzero(cover >= share * best)
    # stretches of rows apart from each other by black ones, each as (first, last) picture row
    cut = np.flatnonzero(np.diff(picture) > 1)
    runs = [(int(a), int(b)) for a, b in zip(picture[np.r_[0, cut + 1]], picture[np.r_[cut, -1]])]
    if len(runs) > 1:
        runs = _merged(runs, cover, GAP_COVER * best)
        longest = max(b - a + 1 for a, b in runs)
        kept = [i for i, (a, b) in enumerate(runs) if b - a + 1 >= STRAY * longest]
        runs = runs[kept[0]:kept[-1] + 1]
    lead, trail = runs[0][0], n - 1 - runs[-1][1]
    lead, trail = lead + lead % 2, trail + trail % 2
    if min(lead, trail) < max(2, min_bar * n) or min(lead, trail) < balance * max(lead, trail):
        return 0, n
    return lead, n - lead - trail


def _merged(runs: list[tuple[int, int]], cover: np.ndarray, black: float) -> list[tuple[int, int]]:
    """``runs`` with each two neighbours joined unless some row between them is lit below ``black``."""
    out = [runs[0]]
    for a, b in runs[1:]:
        if cover[out[-1][1] + 1:a].min() < black:
            out.append((a, b))
        else:
            out[-1] = (out[-1][0], b)
    return out


def sample_lumas(info: MediaInfo, samples: int = SAMPLES) -> list[np.ndarray]:
    """The full-range luma (uint8 [shape=(height, width)], display orientation) of up to
    ``samples`` keyframes spread evenly over the film: at each of the times (i + 0.5) / samples
    of the duration, the keyframe at or before it, or the first keyframe after it not sampled yet
    (before the next time). Only those keyframes are decoded (a seek, reading packets, one
    picture each), so a film with fewer keyframes than ``samples`` (a clip of a few seconds)
    gives fewer samples; a keyframe that fails to decode is passed over. When there are fewer
    and every one is dark (lit on under ``DARK_SHARE`` of its pixels: a clip whose one GOP
    opens on black), the frames at those times within the first ``FORWARD_FRAMES`` are added."""
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
                clock.seek(c, stream, info.clock, times[i] + info.start_s)
            frame = _next_keyframe(c, stream, seen, times[i + 1] + info.start_s if base else math.inf, info.clock)
            if frame is not None:
                rotation = norm_rotation(getattr(frame, "rotation", info.video.rotation))
                out.append(Frame(frame, i, times[i], rotation, size=(info.video.width, info.video.height)).luma())
    if len(out) < n and all(np.count_nonzero(lu > BLACK_LEVEL) < DARK_SHARE * lu.size for lu in out):
        out += _forward_lumas(info, times[:n])
    return out


def _forward_lumas(info: MediaInfo, times: list[float]) -> list[np.ndarray]:
    """The luma of the first frame decoded at or after each of ``times`` (s from the film's
    start, ascending), reading from the start, within its first ``FORWARD_FRAMES`` frames."""
    out: list[np.ndarray] = []
    k = 0
    with open_container(info.path) as c:
        stream = stream_by_index(c, info.video.index)
        stream.thread_type = "AUTO"
        try:
            for j, frame in enumerate(decode_tolerant(c, stream, AudioReport(), info.path, clock=info.clock)):
                if j >= FORWARD_FRAMES or k >= len(times):
                    break
                t = (frame.time - info.start_s) if frame.time is not None else j / max(info.video.fps or 1.0, 1e-3)
                if t >= times[k]:
                    rotation = norm_rotation(getattr(frame, "rotation", info.video.rotation))
                    out.append(Frame(frame, j, t, rotation, size=(info.video.width, info.video.height)).luma())
                    while k < len(times) and times[k] <= t:
                        k += 1
        except MediaError:
            pass  # what was decoded stands
    return out


def _next_keyframe(c, stream, seen: set, before_s: float, file_clock: clock.Clock | None = None):
    """The picture of the first keyframe packet read from ``c`` (after a seek) whose timestamp is
    not in ``seen`` (then added) and is before ``before_s`` (on the file's clock: ``file_clock``); None when
    there is none."""
    try:
        for pkt in c.demux(stream):
            if pkt.pts is None:
                if pkt.size == 0:
                    return None  # the end
                continue
            if file_clock is not None:
                file_clock.fix(pkt)
            if pkt.pts * pkt.time_base >= before_s:
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
    return find_picture(info, "2d", samples)[0]


def find_picture(info: MediaInfo, stereo: str = "auto", samples: int = SAMPLES,
                 lumas: Sequence[np.ndarray] | None = None) -> tuple[Rect, str]:
    """What the analysis reads of ``info``'s video: (the rectangle, the 3D packing it is read under).

    stereo : "2d" (one picture), "side_by_side" or "top_bottom" (two views packed so), or "auto" (the
        packing the file declares, else the one the sampled pictures show inside their bars,
        :func:`~autohaptics.media.stereo.picture_packing`).
    The rectangle is the active picture (:func:`active_area`) of the first view (the whole picture in
    2D); the view itself when nothing could be sampled. The packing is "" in 2D. lumas : the
    samples when the caller has read them (:func:`sample_lumas`), else they are read here."""
    w, h = info.video.display_size if info.video is not None else (0, 0)
    lumas = sample_lumas(info, samples) if lumas is None else lumas
    if lumas:
        h, w = lumas[0].shape[:2]
    packing = "" if stereo == "2d" else stereo
    if stereo == "auto":
        packing = info.video.stereo if info.video is not None else ""
        if not packing and lumas:
            packing = picture_packing(lumas)
    vx, vy, vw, vh = view_rect(int(w), int(h), packing)
    if not lumas:
        return (vx, vy, vw, vh), packing
    x, y, ww, hh = active_area([lu[vy:vy + vh, vx:vx + vw] for lu in lumas])
    return (vx + x, vy + y, ww, hh), packing


def picture_packing(lumas: Sequence[np.ndarray]) -> str:
    """The 3D packing the sampled frames' luma pictures (whole frames, one size; looked at ``DETECT_WIDTH``
    wide) show: the one whose two halves, each cut to its own active picture (:func:`active_area`: each
    view's own bars), are alike (:func:`~autohaptics.media.stereo.views_alike`) with a median over at least
    ``MIN_SAMPLES`` telling samples reaching ``SAME`` (fewer: each reaching ``SAME_FEW``); "" for a 2D film
    (its halves are two parts of one scene, and a letterbox's bars lie on opposite sides of its top and
    bottom halves)."""
    small = [_shrunk(lu, DETECT_WIDTH) for lu in lumas]
    for packing in PACKINGS:
        parts = [[halves(lu, packing)[k] for lu in small] for k in (0, 1)]
        rects = [active_area(p) for p in parts]
        if max(abs(a - b) for a, b in zip(rects[0][2:], rects[1][2:])) > 2:
            continue  # the views of one film have the same bars
        cut = [[lu[y:y + h, x:x + w] for lu in p] for p, (x, y, w, h) in zip(parts, rects)]
        alike = np.asarray([v for v in (views_alike(a, b) for a, b in zip(*cut)) if v is not None])
        if alike.size >= MIN_SAMPLES and float(median(alike)) >= SAME:
            return packing
        if 0 < alike.size < MIN_SAMPLES and float(alike.min()) >= SAME_FEW:
            return packing
    return ""


def _shrunk(luma: np.ndarray, width: int) -> np.ndarray:
    """``luma`` area-averaged to at most ``width`` px wide (its aspect kept)."""
    h, w = luma.shape[:2]
    if w <= width:
        return luma
    return cv2.resize(luma, (width, max(2, int(round(h * width / w)))), interpolation=cv2.INTER_AREA)
