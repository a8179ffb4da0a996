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
inpainting), so the proxies move, change and keep their colours as the film around the overlay does;
a translucent one (a watermark the film shows through) is taken off instead: its opacity and level,
read from how each pixel follows the picture around it across the film's samples, are unblended, so
the film under it stays.
"""

from __future__ import annotations

import base64
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
AROUND = 0.06  # frame widths: the median over this square is the picture around a pixel (wider than a word's line)
MIN_SPREAD = 10.0  # grey levels: a pixel's surroundings must vary this much (sd over samples) to read its opacity
ALPHA_MIN = 0.05  # opacities under this read as none (the fit's noise)
SEE_THROUGH = 0.15, 0.5  # a shape whose strong opacity (its 95th percentile) lies here is translucent
MAX_TRANSLUCENT = 0.5  # translucent shapes covering more are left as picture
LEVEL_FROM = 0.5  # quantile of the strokes' opacities their grey level is read from (a fainter fit leans to the mean)
MAX_ALPHA = 0.75  # opacities are unblended up to this (the film under them amplified at most 4 x)
REPEAT_THUMB = (16, 9)  # px: the thumbnail two shots' first samples are compared on
REPEAT_LEVEL = 1.0  # grey levels: a shot whose first sample is this close (mean absolute difference) repeats


def find_overlays(lumas: Sequence[np.ndarray]) -> "Overlays | None":
    """The overlays in frames sampled far apart, each taken as a shot of its own (:class:`EdgeTally` of
    ``lumas``, then its :meth:`~EdgeTally.find`), at most ``DETECT_WIDTH`` wide; None: none."""
    tally = EdgeTally()
    for luma in lumas:
        tally.add(luma)
    return tally.find()


class EdgeTally:
    """The edges and the luma range of pictures sampled over a film, shot by shot, added one at a
    time (a pass keeps a tally rather than the pictures: a 2-hour film gives thousands). A pixel is
    an edge of a shot where it is one in at least half of the shot's samples; ``n`` counts the
    shots, ``edges`` how many had an edge at each pixel. Shots, not samples: a long shot's scene
    stands still in all its samples, as an overlay does. For the same reason a shot that repeats an
    earlier one (``REPEAT_LEVEL``: a loop, a shot used twice) is passed over: it adds no evidence."""

    def __init__(self):
        self.n = 0
        self.edges: np.ndarray | None = None  # int32 [shape=(h, w)]: shots with an edge at each pixel
        self.lo: np.ndarray | None = None  # uint8: each pixel's least and greatest luma over the samples
        self.hi: np.ndarray | None = None
        # float64 [shape=(4, h, w)]: sums over the samples of each pixel's luma (y) and the picture's around
        # it (x, ``AROUND``): x, y, x * x, x * y (a line y = (1 - opacity) x + opacity x level); ``fitted``
        # counts them. By sample, not by shot: a shot's samples are more points on the same line
        self.fit: np.ndarray | None = None
        self.fitted = 0
        self._shot: tuple = ()  # the current shot: (its id, int32 edge counts, samples)
        self._starts = np.zeros((0, REPEAT_THUMB[0] * REPEAT_THUMB[1]), np.float32)  # shots' first thumbnails
        self._means = np.zeros(0, np.float32)  # their means (two thumbnails' mean difference bounds their distance)
        self._kept = 0  # rows of ``_starts`` in use
        self._seen: tuple = ()  # the shot of the last sample looked at, and whether it repeats an earlier one

    def add(self, luma: np.ndarray, shot: int | None = None) -> None:
        """One picture: uint8 [shape=(height, width)], full-range luma of the active picture (bars
        left out), of shot ``shot`` (None: a shot of its own; pictures of one shot come together).
        Passed over: a dark picture (lit on under ``LIT_SHARE``: a fade, a night, a title card; an
        overlay's dark parts show no edge on it), one of another aspect, and those of a shot that repeats
        an earlier shot (:meth:`_repeated`)."""
        small = _shrunk(np.ascontiguousarray(luma, np.uint8))
        if (self.lo is not None and small.shape != self.lo.shape) or \
                np.count_nonzero(small > LIT_LEVEL) < LIT_SHARE * small.size or self._repeated(small, shot):
            return
        edge = (cv2.Canny(small, EDGE_LOW, EDGE_HIGH) > 0).astype(np.int32)
        x = cv2.medianBlur(small, max(3, int(round(AROUND * small.shape[1])) | 1)).astype(np.float64)
        y = small.astype(np.float64)
        if self.lo is None:
            self.lo, self.hi, self.edges = small.copy(), small.copy(), np.zeros(small.shape, np.int32)
            self.fit = np.zeros((4, *small.shape), np.float64)
        else:
            np.minimum(self.lo, small, out=self.lo)
            np.maximum(self.hi, small, out=self.hi)
        self.fit += np.stack([x, y, x * x, x * y])
        self.fitted += 1
        if shot is None or not self._shot or self._shot[0] != shot:
            self._close()
            self._shot = (shot, edge, 1)
        else:
            self._shot = (shot, self._shot[1] + edge, self._shot[2] + 1)

    def _repeated(self, small: np.ndarray, shot: int | None) -> bool:
        """Whether ``small``'s shot repeats an earlier one (a sample of shot None is a shot of its own),
        judged on its first sample: a shot that does not is kept for those after it. Measured: a looped
        clip's repeats differ by up to 0.26 grey levels, its two shots by 3.6, two shots of the shared
        films by 8.7 or more (docs/BENCHMARKS.md, "Stop 65")."""
        if shot is not None and self._seen and self._seen[0] == shot:
            return self._seen[1]
        thumb = cv2.resize(small, REPEAT_THUMB, interpolation=cv2.INTER_AREA).astype(np.float32).ravel()
        mean = float(thumb.mean())
        near = self._starts[:self._kept][np.abs(self._means[:self._kept] - mean) < REPEAT_LEVEL]  # the only candidates
        repeats = bool(near.size) and float(np.abs(near - thumb).mean(axis=1).min()) < REPEAT_LEVEL
        if not repeats:
            if self._kept == len(self._starts):
                grow = max(64, self._kept)
                self._starts = np.concatenate([self._starts, np.zeros((grow, thumb.size), np.float32)])
                self._means = np.concatenate([self._means, np.zeros(grow, np.float32)])
            self._starts[self._kept], self._means[self._kept] = thumb, mean
            self._kept += 1
        self._seen = (shot, repeats)
        return repeats

    def _close(self) -> None:
        """Count the current shot's edges."""
        if self._shot:
            _, counts, taken = self._shot
            self.edges += (2 * counts >= taken).astype(np.int32)
            self.n += 1
            self._shot = ()

    def opacity(self) -> tuple[np.ndarray, np.ndarray]:
        """Each pixel's opacity over the film around it, float [shape=(h, w)] 0..1 (under ``ALPHA_MIN``,
        or where the surroundings vary less than ``MIN_SPREAD`` over the samples: 0), and its level
        (opacity x the overlay's grey level, 0..255), from the line through the samples' (around, own)
        luma pairs: an overlay of opacity a and level c shows y = (1 - a) x + a c."""
        mx, my, mxx, mxy = self.fit / max(self.fitted, 1)
        spread = mxx - mx * mx
        slope = np.where(spread > MIN_SPREAD ** 2, (mxy - mx * my) / np.maximum(spread, 1e-9), 1.0)
        alpha = np.clip(1.0 - slope, 0.0, 1.0)
        alpha[alpha < ALPHA_MIN] = 0.0
        return alpha, np.where(alpha > 0, my - slope * mx, 0.0)

    def find(self) -> "Overlays | None":
        """The overlays the shots show, at the samples' size (at most ``DETECT_WIDTH`` wide); None when
        there are none, or too few shots (``MIN_SHOTS``) to tell.

        An overlay is made of edges found in at least ``PERSIST`` of the shots; those closer than ``CLOSE`` are
        joined, each shape's convex hull filled (a box with its digits, those that change every frame too; a
        word; a logo), shapes of fewer standing edge pixels than ``MIN_EDGES`` frame widths dropped (scenes that
        share a sample or two of their edges), the rest widened by ``MARGIN``. Nothing is found when under
        ``MIN_CHANGING`` of the pixels outside the shapes change across the samples (a clip of one scene keeps
        its own edges in every shot). Shapes covering up to ``MAX_COVER`` are filled: that takes little film,
        and leaves no trace of them. Over it, filling would take more film than the overlay hides: a shape
        whose strong opacity (:meth:`opacity`, its 95th percentile) lies in ``SEE_THROUGH`` is unblended (a
        watermark across the picture; up to ``MAX_TRANSLUCENT``), the others are filled if they fit in
        ``MAX_COVER``, or left as picture (docs/BENCHMARKS.md, "Stop 63", "Stop 64").
        """
        self._close()
        if self.n < MIN_SHOTS or self.edges is None or min(self.edges.shape) < 16:
            return None
        region = self._shapes()
        if region is None:
            return None
        changing = (self.hi.astype(np.int16) - self.lo) > CHANGE_LEVEL
        if changing[~region].mean() < MIN_CHANGING:
            return None
        if region.mean() <= MAX_COVER:
            return Overlays(region)
        alpha, level = self.opacity()
        n, labels = cv2.connectedComponents(region.astype(np.uint8))
        see_through = np.zeros(n, bool)
        for k in range(1, n):
            q95 = float(np.quantile(alpha[labels == k], 0.95))
            see_through[k] = SEE_THROUGH[0] <= q95 <= SEE_THROUGH[1]
        translucent = see_through[labels]
        mask = region & ~translucent
        if mask.mean() > MAX_COVER:
            mask[:] = False
        if translucent.mean() > MAX_TRANSLUCENT:
            translucent[:] = False
        strong = translucent & (alpha >= SEE_THROUGH[0])
        if not strong.any():
            return Overlays(mask) if mask.any() else None
        strong &= alpha >= np.quantile(alpha[strong], LEVEL_FROM)
        colour = float(np.median(level[strong] / alpha[strong]))
        return Overlays(mask, np.where(translucent, alpha, 0.0), colour)

    def _shapes(self) -> np.ndarray | None:
        """The standing edges' shapes, hulled and widened (:meth:`find`): bool [shape=(h, w)], or None."""
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
        return cv2.dilate(shapes, _disc(MARGIN * w)) > 0 if shapes.any() else None


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
    """A film's overlays (:meth:`EdgeTally.find`) taken off any proxy of its frames, at any size, gray
    or RGB: ``mask`` (bool [shape=(h, w)]) filled from the picture around it, ``alpha`` (uint8, opacity
    x 255; None: no translucent overlay) unblended with the overlay's grey level ``colour`` (0..255).
    The maps at each size are made once (thread-safe)."""

    def __init__(self, mask: np.ndarray, alpha: np.ndarray | None = None, colour: float = 0.0):
        self.mask = np.asarray(mask, bool)
        self.alpha = None if alpha is None else _alpha_u8(alpha)
        if self.alpha is not None and not self.alpha.any():
            self.alpha = None
        self.colour = float(np.clip(colour, 0.0, 255.0))
        self._filled = bool(self.mask.any())
        self._sized: dict[tuple, object] = {}
        self._lock = threading.Lock()

    @property
    def share(self) -> float:
        """The share of the picture filled, 0..1."""
        return float(self.mask.mean())

    @property
    def translucent(self) -> float:
        """The share of the picture unblended, 0..1."""
        return 0.0 if self.alpha is None else float(np.count_nonzero(self.alpha) / self.alpha.size)

    def boxes(self, width: int, height: int) -> list[list[int]]:
        """Each overlay's bounding box [x, y, w, h] px in a picture ``width`` x ``height``."""
        covered = self.mask_at(height, width)
        if self.alpha is not None:  # a translucent overlay's strokes, joined as its shapes were (``CLOSE``)
            strokes = (self.alpha_at(height, width) > 0).astype(np.uint8)
            covered = covered | (cv2.morphologyEx(strokes, cv2.MORPH_CLOSE, _disc(CLOSE * width)) > 0)
        n, _, stats, _ = cv2.connectedComponentsWithStats(covered)
        return [[int(v) for v in stats[i, :4]] for i in range(1, n)]

    def to_stats(self) -> dict:
        """The overlays as JSON-able stats: {"size": [w, h], "runs": the mask's run lengths, rows joined,
        starting with a clear run; with a translucent one also "alpha" (a PNG of the opacities, base64)
        and "colour"}; :meth:`from_stats` reads them back exactly."""
        flat = self.mask.ravel()
        runs = np.diff(np.concatenate([[0], np.flatnonzero(flat[1:] != flat[:-1]) + 1, [flat.size]]))
        if flat.size and flat[0]:
            runs = np.concatenate([[0], runs])  # the first run is a clear one, here empty
        out = {"size": [int(self.mask.shape[1]), int(self.mask.shape[0])], "runs": [int(r) for r in runs]}
        if self.alpha is not None:
            out["alpha"] = base64.b64encode(cv2.imencode(".png", self.alpha)[1].tobytes()).decode("ascii")
            out["colour"] = round(self.colour, 3)
        return out

    @classmethod
    def from_stats(cls, stats: dict | None) -> "Overlays | None":
        """The overlays :meth:`to_stats` wrote (None: none, or stats without a mask)."""
        if not stats or "runs" not in stats:
            return None
        w, h = (int(v) for v in stats["size"])
        values = np.arange(len(stats["runs"])) % 2 == 1
        mask = np.repeat(values, np.asarray(stats["runs"], np.int64))[:w * h].reshape(h, w)
        alpha = None
        if stats.get("alpha"):
            png = np.frombuffer(base64.b64decode(stats["alpha"]), np.uint8)
            alpha = cv2.imdecode(png, cv2.IMREAD_UNCHANGED)
        return cls(mask, alpha, float(stats.get("colour", 0.0)))

    def mask_at(self, height: int, width: int) -> np.ndarray:
        """The mask at ``height`` x ``width`` px: uint8 0/1, every pixel an overlay touches set."""
        key = ("mask", int(height), int(width))
        with self._lock:
            got = self._sized.get(key)
            if got is None:
                got = (cv2.resize(self.mask.astype(np.float32), (key[2], key[1]), interpolation=cv2.INTER_AREA)
                       > 0).astype(np.uint8)
                self._sized[key] = got
        return got

    def alpha_at(self, height: int, width: int) -> np.ndarray:
        """The opacities at ``height`` x ``width`` px: float32 0..1 (area-averaged to a smaller size, as a
        proxy averages the picture; at most ``MAX_ALPHA``), 0 without a translucent overlay."""
        key = ("alpha", int(height), int(width))
        with self._lock:
            got = self._sized.get(key)
            if got is None:
                if self.alpha is None:
                    got = np.zeros((key[1], key[2]), np.float32)
                else:
                    small = key[2] < self.alpha.shape[1]
                    got = cv2.resize(self.alpha.astype(np.float32) / 255.0, (key[2], key[1]),
                                     interpolation=cv2.INTER_AREA if small else cv2.INTER_LINEAR)
                    np.minimum(got, MAX_ALPHA, out=got)
                self._sized[key] = got
        return got

    def fill(self, picture: np.ndarray) -> np.ndarray:
        """``picture`` (uint8 [shape=(h, w)] or [shape=(h, w, 3)]: a proxy) with the overlays taken off: a
        translucent one unblended (the film under it: (picture - opacity x colour) / (1 - opacity), for
        each channel), the mask filled from the picture around it: a new array."""
        a = np.ascontiguousarray(picture, np.uint8)
        if self.alpha is not None:
            band, gain, offset = self._unblend_at(*a.shape[:2])
            a = a.copy()
            if a.ndim == 3:
                gain, offset = gain[:, :, None], offset[:, :, None]
            a[band] = np.clip(a[band] * gain - offset + 0.5, 0, 255).astype(np.uint8)
        if not self._filled:
            return a
        return cv2.inpaint(a, self.mask_at(*a.shape[:2]), FILL_RADIUS, cv2.INPAINT_TELEA)

    def _unblend_at(self, height: int, width: int) -> tuple[slice, np.ndarray, np.ndarray]:
        """The rows a translucent overlay touches at ``height`` x ``width`` px, and over them the gain
        1 / (1 - opacity) and offset opacity x colour x gain of :meth:`fill` (float32), made once a size."""
        key = ("unblend", int(height), int(width))
        with self._lock:
            got = self._sized.get(key)
        if got is None:
            alpha = self.alpha_at(height, width)
            rows = np.flatnonzero(alpha.any(axis=1))
            band = slice(int(rows[0]), int(rows[-1]) + 1) if rows.size else slice(0, 0)
            gain = (1.0 / (1.0 - alpha[band])).astype(np.float32)
            got = (band, gain, (alpha[band] * self.colour * gain).astype(np.float32))
            with self._lock:
                self._sized[key] = got
        return got


def _alpha_u8(alpha: np.ndarray) -> np.ndarray:
    """Opacities as stored: uint8 0..255 (a float map 0..1 is scaled; uint8 kept as it is)."""
    a = np.asarray(alpha)
    if a.dtype == np.uint8:
        return np.ascontiguousarray(a)
    return np.clip(np.rint(a * 255.0), 0, 255).astype(np.uint8)
