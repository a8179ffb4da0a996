"""Burnt-in overlays: what a copy lays over the film in one place for its whole length (a screener's
or a daily's timecode box, a watermark, a channel's logo), found so that no stage reads it as the
film's picture.

A timecode's digits change every frame, so no pair of frames is ever static and optical flow reads
motion where the film has none; its box holds the flow's coarse levels still, joins the two sides of
a cut in the cut signatures and draws the saliency (docs/BENCHMARKS.md, "Stop 63").

:class:`EdgeTally` decides from frames sampled shot by shot (pure, numpy in; :func:`overlay_mask`: one
sample a shot): edges that stand in the same place in nearly every shot, across a film whose pictures
otherwise change, joined into the shapes they outline and widened by a margin (an encode's ringing
around them). :class:`Overlays` fills that mask in each proxy from the picture around it (OpenCV's Telea
inpainting), so the proxies move, change and keep their colours as the film around the overlay does.
"""

from __future__ import annotations

import threading
from collections.abc import Sequence

import cv2
import numpy as np

DETECT_WIDTH = 320  # px: the samples are looked at this wide
EDGE_LOW, EDGE_HIGH = 60, 120  # Canny thresholds, grey levels
MIN_SHOTS = 4  # fewer shots sampled tell nothing
PERSIST = 7 / 9  # an edge in at least this share of the shots stands still
CLOSE = 0.02  # frame widths: strokes and borders this close are one shape (a box's digits, a word's letters)
MARGIN = 0.025  # frame widths: the mask reaches this far beyond the shapes (ringing, a box's shadow)
MIN_EDGES = 0.05  # frame widths: a shape with fewer standing edge pixels is a coincidence (a few), not an overlay
BORDER = 0.02  # of the height: edges this near the picture's border are not an overlay's (a bar's, a pixel off)
MAX_COVER = 0.08  # a mask covering more is left as picture: one scene, or a watermark the film shows through
CHANGE_LEVEL = 24  # grey levels: a pixel whose samples span more than this changes across the film
MIN_CHANGING = 0.5  # the pixels outside the mask that change: at least this share, or nothing is found
FILL_RADIUS = 3  # px: the neighbourhood each filled pixel is taken from (cv2.inpaint)
LIT_LEVEL, LIT_SHARE = 12, 0.25  # a sample lit (luma above LIT_LEVEL) on less of its pixels tells nothing


def overlay_mask(lumas: Sequence[np.ndarray]) -> np.ndarray | None:
    """Where overlays lie in frames sampled far apart, each taken as a shot of its own (:class:`EdgeTally`
    of ``lumas``, then its :meth:`~EdgeTally.mask`): bool [shape=(h, w)] at most ``DETECT_WIDTH`` wide, or None."""
    tally = EdgeTally()
    for luma in lumas:
        tally.add(luma)
    return tally.mask()


class EdgeTally:
    """The edges and the luma range of pictures sampled over a film, shot by shot, added one at a
    time (a pass keeps a tally rather than the pictures: a 2-hour film gives thousands). A pixel is
    an edge of a shot where it is one in at least half of the shot's samples; ``n`` counts the
    shots, ``edges`` how many had an edge at each pixel. Shots, not samples: a long shot's scene
    stands still in all its samples, as an overlay does."""

    def __init__(self):
        self.n = 0
        self.edges: np.ndarray | None = None  # int32 [shape=(h, w)]: shots with an edge at each pixel
        self.lo: np.ndarray | None = None  # uint8: each pixel's least and greatest luma over the samples
        self.hi: np.ndarray | None = None
        self._shot: tuple = ()  # the current shot: (its id, int32 edge counts, samples)

    def add(self, luma: np.ndarray, shot: int | None = None) -> None:
        """One picture: uint8 [shape=(height, width)], full-range luma of the active picture (bars
        left out), of shot ``shot`` (None: a shot of its own; pictures of one shot come together).
        Passed over: a dark picture (lit on under ``LIT_SHARE``: a fade, a night, a title card; an
        overlay's dark parts show no edge on it) and one of another aspect."""
        small = _shrunk(np.ascontiguousarray(luma, np.uint8))
        if (self.lo is not None and small.shape != self.lo.shape) or \
                np.count_nonzero(small > LIT_LEVEL) < LIT_SHARE * small.size:
            return
        edge = (cv2.Canny(small, EDGE_LOW, EDGE_HIGH) > 0).astype(np.int32)
        if self.lo is None:
            self.lo, self.hi, self.edges = small.copy(), small.copy(), np.zeros(small.shape, np.int32)
        else:
            np.minimum(self.lo, small, out=self.lo)
            np.maximum(self.hi, small, out=self.hi)
        if shot is None or not self._shot or self._shot[0] != shot:
            self._close()
            self._shot = (shot, edge, 1)
        else:
            self._shot = (shot, self._shot[1] + edge, self._shot[2] + 1)

    def _close(self) -> None:
        """Count the current shot's edges."""
        if self._shot:
            _, counts, taken = self._shot
            self.edges += (2 * counts >= taken).astype(np.int32)
            self.n += 1
            self._shot = ()

    def mask(self) -> np.ndarray | None:
        """Where overlays lie: bool [shape=(h, w)] at the samples' size (at most ``DETECT_WIDTH``
        wide), or None when there are none, or too few shots (``MIN_SHOTS``) to tell.

        An overlay is made of edges found in at least ``PERSIST`` of the shots; those closer than ``CLOSE`` are
        joined, each shape's convex hull filled (a box with its digits, those that change every frame too; a
        word; a logo), shapes of fewer standing edge pixels than ``MIN_EDGES`` frame widths dropped (scenes that
        share a sample or two of their edges), the rest widened by ``MARGIN``. Nothing is found when under
        ``MIN_CHANGING`` of the pixels outside the mask change across the samples (a clip of one scene keeps its
        own edges in every shot), or when the mask would cover more than ``MAX_COVER``: a wide translucent
        watermark, through which the film shows, would take more film from the stages filled than it hides
        (docs/BENCHMARKS.md, "Stop 63").
        """
        self._close()
        if self.n < MIN_SHOTS or self.edges is None or min(self.edges.shape) < 16:
            return None
        h, w = self.edges.shape
        persistent = (self.edges >= PERSIST * self.n - 1e-9).astype(np.uint8)
        b = max(2, int(round(BORDER * h)))  # a bar's edge the active picture's rectangle left in
        persistent[:b], persistent[-b:], persistent[:, :b], persistent[:, -b:] = 0, 0, 0, 0
        if not persistent.any():
            return None
        n, labels = cv2.connectedComponents(cv2.dilate(persistent, _disc(CLOSE * w)))
        held = np.bincount(labels[persistent > 0], minlength=n)  # each shape's standing edge pixels
        shapes = np.zeros((h, w), np.uint8)
        for k in np.flatnonzero(held >= MIN_EDGES * w):
            if k:
                ys, xs = np.nonzero(labels == k)
                cv2.fillConvexPoly(shapes, cv2.convexHull(np.stack([xs, ys], axis=1).astype(np.int32)), 1)
        if not shapes.any():
            return None
        mask = cv2.dilate(shapes, _disc(MARGIN * w)) > 0
        changing = (self.hi.astype(np.int16) - self.lo) > CHANGE_LEVEL
        if mask.mean() > MAX_COVER or changing[~mask].mean() < MIN_CHANGING:
            return None
        return mask


def _disc(diameter: float) -> np.ndarray:
    """An elliptic structuring element about ``diameter`` px across (odd, at least 3)."""
    d = max(3, int(round(diameter)) | 1)
    return cv2.getStructuringElement(cv2.MORPH_ELLIPSE, (d, d))


def _shrunk(luma: np.ndarray) -> np.ndarray:
    """``luma`` area-averaged to ``DETECT_WIDTH`` wide (its aspect kept; a narrower one as it is)."""
    h, w = luma.shape[:2]
    if w <= DETECT_WIDTH:
        return luma
    return cv2.resize(luma, (DETECT_WIDTH, max(2, int(round(h * DETECT_WIDTH / w)))), interpolation=cv2.INTER_AREA)


class Overlays:
    """A film's overlays (:func:`overlay_mask`), filled in any proxy of its frames, at any size, gray
    or RGB. The mask at each size is made once (thread-safe)."""

    def __init__(self, mask: np.ndarray):
        self.mask = np.asarray(mask, bool)
        self._sized: dict[tuple[int, int], np.ndarray] = {}
        self._lock = threading.Lock()

    @property
    def share(self) -> float:
        """The share of the picture the overlays cover, 0..1."""
        return float(self.mask.mean())

    def boxes(self, width: int, height: int) -> list[list[int]]:
        """Each overlay's bounding box [x, y, w, h] px in a picture ``width`` x ``height``."""
        n, _, stats, _ = cv2.connectedComponentsWithStats(self.mask_at(height, width))
        return [[int(v) for v in stats[i, :4]] for i in range(1, n)]

    def to_stats(self) -> dict:
        """The mask as JSON-able stats: {"size": [w, h], "runs": run lengths of the rows joined,
        starting with a clear run}; :meth:`from_stats` reads them back exactly."""
        flat = self.mask.ravel()
        runs = np.diff(np.concatenate([[0], np.flatnonzero(flat[1:] != flat[:-1]) + 1, [flat.size]]))
        if flat.size and flat[0]:
            runs = np.concatenate([[0], runs])  # the first run is a clear one, here empty
        return {"size": [int(self.mask.shape[1]), int(self.mask.shape[0])], "runs": [int(r) for r in runs]}

    @classmethod
    def from_stats(cls, stats: dict | None) -> "Overlays | None":
        """The overlays :meth:`to_stats` wrote (None: none, or stats without a mask)."""
        if not stats or "runs" not in stats:
            return None
        w, h = (int(v) for v in stats["size"])
        values = np.arange(len(stats["runs"])) % 2 == 1
        return cls(np.repeat(values, np.asarray(stats["runs"], np.int64))[:w * h].reshape(h, w))

    def mask_at(self, height: int, width: int) -> np.ndarray:
        """The mask at ``height`` x ``width`` px: uint8 0/1, every pixel an overlay touches set."""
        key = (int(height), int(width))
        with self._lock:
            got = self._sized.get(key)
            if got is None:
                got = (cv2.resize(self.mask.astype(np.float32), (key[1], key[0]), interpolation=cv2.INTER_AREA)
                       > 0).astype(np.uint8)
                self._sized[key] = got
        return got

    def fill(self, picture: np.ndarray) -> np.ndarray:
        """``picture`` (uint8 [shape=(h, w)] or [shape=(h, w, 3)]: a proxy) with the overlays filled
        from the picture around them: a new array."""
        a = np.ascontiguousarray(picture, np.uint8)
        return cv2.inpaint(a, self.mask_at(*a.shape[:2]), FILL_RADIUS, cv2.INPAINT_TELEA)
