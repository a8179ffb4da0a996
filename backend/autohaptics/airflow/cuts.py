"""Shot-cut detection on small proxies (not in the thesis: flow across a cut is meaningless).

A frame's signature is its normalised colour histogram (16 bins per RGB channel; 32 luma bins for
a gray frame) plus a 16 x 9 luma thumbnail. Two frames are in different shots when

- both have structure (thumbnail standard deviation >= ``flat_std``): the colour distribution
  changed (half the histogram L1 distance >= ``hist_threshold``) AND the layout changed (the
  zero-mean correlation of the thumbnails <= ``corr_threshold``). A fade changes the histogram
  but keeps the layout; a pan keeps the histogram; a hard cut changes both. Colour matters: a
  green shot and a grey shot can have the same luma.
- one of them is flat (black, a title card): the mean brightness jumps by ``flat_jump`` grey
  levels or more (a fade from black moves a few levels per frame, a cut from black jumps).

:func:`cut_score` condenses this into one number in 0..1 (>= 0.5 means cut) for reports.

A cut between two shots of the SAME palette is missed on purpose: between ticks 0.1 s apart fast
action decorrelates the layout as much while keeping the palette, and a layout-only rule would
chop action scenes into cuts (docs/BENCHMARKS.md, "Cuts", has the figures). A miss costs the flow
of one pair computed across the cut.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import ClassVar

import cv2
import numpy as np

from autohaptics.errors import ParameterError
from autohaptics.records import ANALYSIS, Record, param

_BINS = 32  # luma bins of a gray frame
_RGB_BINS = 16  # bins per channel of an RGB frame
_THUMB = (16, 9)
_THUMB_N = _THUMB[0] * _THUMB[1]


@dataclass(frozen=True)
class CutParams(Record):
    """hist_threshold : histogram distance (0..1) from which the colours count as changed (0.25).
    corr_threshold : thumbnail correlation (-1..1) up to which the layout counts as changed (0.5).
    flat_std : thumbnail standard deviation (grey levels) below which a frame is flat (4).
    flat_jump : mean brightness jump (grey levels) that makes a cut next to a flat frame (40).
    in_one_step : a change between two ticks' analysed frames is a cut only if it is one over one of the
        two steps through the frame decoded between them, or between that frame's two fields (a telecined
        frame), where the video pass has one (default True; False: the two frames alone, the rule before
        issue 31; :mod:`autohaptics.pipeline.video`).
    """

    STAGE: ClassVar[str] = ANALYSIS
    GROUP: ClassVar[str] = "cuts"

    hist_threshold: float = param(0.25, hi=1.0, gt=0.0)
    corr_threshold: float = param(0.5, -1.0, 1.0)
    flat_std: float = param(4.0, 0.0, 255.0, unit="grey levels")
    flat_jump: float = param(40.0, hi=255.0, gt=0.0, unit="grey levels")
    in_one_step: bool = True


def frame_signature(frame: np.ndarray) -> np.ndarray:
    """Signature of a frame, gray uint8 [shape=(h, w)] or RGB uint8 [shape=(h, w, 3)].

    Returns float32: the histogram (32 luma bins, or 3 x 16 colour bins, summing to 1) followed by
    the 144 thumbnail values (0..255). Compare only signatures of the same kind.
    """
    f = np.asarray(frame)
    if f.ndim not in (2, 3) or f.size == 0 or (f.ndim == 3 and f.shape[2] != 3):
        raise ParameterError(f"expected a gray (h, w) or RGB (h, w, 3) frame, got {f.shape}")
    f = np.ascontiguousarray(f, dtype=np.uint8)
    if f.ndim == 2:
        gray = f
        hist = np.bincount((gray >> 3).ravel(), minlength=_BINS).astype(np.float32)
        hist /= max(1.0, float(hist.sum()))
    else:
        gray = cv2.cvtColor(f, cv2.COLOR_RGB2GRAY)
        codes = (f >> 4).reshape(-1, 3).astype(np.int64) + np.array([0, _RGB_BINS, 2 * _RGB_BINS])
        hist = np.bincount(codes.ravel(), minlength=3 * _RGB_BINS).astype(np.float32)
        hist /= max(1.0, float(hist.sum()))
    thumb = cv2.resize(gray, _THUMB, interpolation=cv2.INTER_AREA).astype(np.float32).ravel()
    return np.concatenate([hist, thumb])


def _centred(thumb: np.ndarray) -> tuple[np.ndarray, float, float]:
    """A thumbnail (float64) less its mean, its mean and its sum of squared deviations: the
    figures numpy's ``mean``, ``std`` and the correlation below are made of, each summed once."""
    mean = np.add.reduce(thumb) / thumb.size
    centred = thumb - mean
    return centred, float(mean), float(np.add.reduce(centred * centred))


def cut_score(sig_a: np.ndarray, sig_b: np.ndarray, *, params: CutParams = CutParams()) -> float:
    """How clearly two frames belong to different shots, 0..1; 0.5 or more is a cut (see is_cut)."""
    a, b = np.asarray(sig_a, np.float32), np.asarray(sig_b, np.float32)
    if a.shape != b.shape:
        raise ParameterError(f"signatures differ in shape (gray vs colour?): {a.shape} vs {b.shape}")
    nh = a.size - _THUMB_N
    (da, ma, sa), (db, mb, sb) = _centred(a[nh:].astype(np.float64)), _centred(b[nh:].astype(np.float64))
    if math.sqrt(min(sa, sb) / _THUMB_N) < params.flat_std:
        return float(min(1.0, 0.5 * abs(ma - mb) / params.flat_jump))
    hist = 0.5 * float(np.add.reduce(np.abs(a[:nh] - b[:nh])))
    colour = min(1.0, 0.5 * hist / params.hist_threshold)
    den = math.sqrt(sa * sb)
    corr = float(np.add.reduce(da * db)) / den if den > 0 else 1.0
    layout = min(1.0, 0.5 * (1.0 - corr) / max(1e-6, 1.0 - params.corr_threshold))
    return float(min(colour, layout))


def is_cut(sig_a: np.ndarray, sig_b: np.ndarray, *, params: CutParams = CutParams()) -> bool:
    """True when the two frames' signatures belong to different shots (module docstring)."""
    return cut_score(sig_a, sig_b, params=params) >= 0.5


# ------------------------------------------------------------------ signatures kept per tick
_HIST_N = 3 * _RGB_BINS
PACKED_SIZE = _HIST_N + _THUMB_N
_HIST_SCALE = 3 * 255.0  # each channel's 16 bins sum to 1/3: a channel's packed bins sum to 255


def pack_signature(sig: np.ndarray) -> np.ndarray | None:
    """A colour signature as uint8 [shape=(192,)]: the 48 histogram bins scaled so each channel
    sums to 255, then the 144 thumbnail grey levels, both rounded. None for a gray signature
    (its histogram cannot be compared with a colour one); a packed row of zeros means "none"."""
    s = np.asarray(sig, np.float32)
    if s.size != PACKED_SIZE:
        return None
    out = np.empty(PACKED_SIZE, np.float32)
    out[:_HIST_N] = s[:_HIST_N] * _HIST_SCALE
    out[_HIST_N:] = s[_HIST_N:]
    return np.clip(np.rint(out), 0, 255).astype(np.uint8)


def unpack_signatures(packed: np.ndarray) -> np.ndarray:
    """Packed rows uint8 [shape=(m, 192)] back to colour signatures float32 [shape=(m, 192)]."""
    out = np.array(packed, np.float32).reshape(-1, PACKED_SIZE)  # one new array, scaled in place
    out[:, :_HIST_N] /= _HIST_SCALE
    return out


def thumbnails(sigs: np.ndarray) -> np.ndarray:
    """The 16 x 9 luma thumbnails (grey levels, row-major 9 rows of 16) of colour signatures
    [shape=(m, 192)], float32 [shape=(m, 144)]."""
    return np.asarray(sigs, np.float32).reshape(-1, PACKED_SIZE)[:, _HIST_N:]


def cut_scores(sigs_a: np.ndarray, sigs_b: np.ndarray, *, params: CutParams = CutParams(),
               either: bool = False) -> np.ndarray:
    """:func:`cut_score` of each row pair of two arrays of colour signatures [shape=(m, 192)],
    float64 [shape=(m,)] in 0..1 (the same rule, over rows; float rounding may differ in the
    last digits). ``either``: the colours OR the layout changed is enough (for frames on either
    side of a transition that hid the cut itself, such as a fade through black)."""
    a = np.asarray(sigs_a, np.float64).reshape(-1, PACKED_SIZE)
    b = np.asarray(sigs_b, np.float64).reshape(-1, PACKED_SIZE)
    if a.shape != b.shape:
        raise ParameterError(f"signature arrays differ in shape: {a.shape} vs {b.shape}")
    ta, tb = a[:, _HIST_N:], b[:, _HIST_N:]
    ma, mb = ta.mean(axis=1), tb.mean(axis=1)
    da, db = ta - ma[:, None], tb - mb[:, None]
    sa, sb = (da * da).sum(axis=1), (db * db).sum(axis=1)
    flat = np.sqrt(np.minimum(sa, sb) / _THUMB_N) < params.flat_std
    hist = 0.5 * np.abs(a[:, :_HIST_N] - b[:, :_HIST_N]).sum(axis=1)
    colour = np.minimum(1.0, 0.5 * hist / params.hist_threshold)
    den = np.sqrt(sa * sb)
    corr = np.where(den > 0, (da * db).sum(axis=1) / np.where(den > 0, den, 1.0), 1.0)
    layout = np.minimum(1.0, 0.5 * (1.0 - corr) / max(1e-6, 1.0 - params.corr_threshold))
    jump = np.minimum(1.0, 0.5 * np.abs(ma - mb) / params.flat_jump)
    return np.where(flat, jump, np.maximum(colour, layout) if either else np.minimum(colour, layout))
