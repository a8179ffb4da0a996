"""Shot boundaries from the analysis's per-tick arrays: hard cuts, fades through a flat picture
(black, white) and cross-dissolves, each one boundary (the first tick of the new shot).

- **Cuts**: in a run of ticks the video pass flagged (``cut``), each tick whose stored signature
  is in another shot than the tick before's by the cut rule (``airflow.cuts``) starts a shot (a
  flag of the flow pair alone is none). Flag runs up to ``flash_ticks`` apart whose outer ticks
  are in the same shot are a flash (a few bright frames inside a shot): no boundary. Where the
  cut rule sees only brightness (a flat tick: a title card, a dim picture), two ticks with some
  detail whose layouts differ are a cut, and so is a steady picture next to an empty run.
- **Fades**: a run of flat ticks (thumbnail standard deviation below ``flat_std``; its empty
  ticks where it has some) that the picture ramps into or out of over ``min_ramp`` ticks or more,
  with different shots at the ramps' outer ends; the boundary is the run's middle.
- **Dissolves**: a tick c whose thumbnail, in 3 x 4 blocks, is the mean of those w ticks before
  and after (residual below ``linear_max`` of their difference) where those two are in different
  shots by the cut rule, for at least two w in ``widths``, with no cut or fade between; runs whose
  spans overlap are one. The span is widened to the contrast dip it sits in and the boundary is
  where the blend is half-way (:mod:`.blend`).

A slow pan keeps its palette (the cut rule's colour test) and fast action within a shot does not
blend linearly, so neither makes a boundary. Without signatures (caches written before they were
kept) fades are found from the mean colour (dark runs) and every flagged run is a cut.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from autohaptics.airflow import cuts
from autohaptics.errors import ParameterError
from autohaptics.shots import blend

KINDS = ("start", "cut", "fade", "dissolve")  # how a shot begins; codes are indices
CUT, FADE, DISSOLVE = 1, 2, 3
_LUMA = np.array([0.299, 0.587, 0.114])


@dataclass(frozen=True)
class ShotParams:
    """flat_std : thumbnail standard deviation (grey levels) below which a tick is flat (5).
    empty_std : the same below which a flat tick is empty (1): a flat run holding empty ticks is a
        fade through them, its other flat ticks are low-detail pictures (title cards, dim ramps).
    card_corr : thumbnail correlation up to which two ticks with detail, one of them flat, are
        different pictures (0.5; the cut rule only weighs the brightness of flat ticks).
    still_corr, change_corr : a cut between two still shots of one palette: the thumbnails
        across it correlate <= change_corr (0.6), and each side with its other neighbour >=
        still_corr (0.9): a change 4x what either shot moves in a tick (action moves on).
    dark_level : mean luma (grey levels) below which a tick is flat without signatures (16).
    min_ramp : ticks of gradual change into or out of a flat run that make it a fade (2).
    max_ramp : longest ramp followed outward from a flat run or a dissolve's contrast dip, ticks (30).
    widths : half-widths (ticks) of the windows a dissolve is looked for in.
    linear_max : largest residual of a dissolve's middle against its ends' mean, as a share of
        the ends' difference (0.2; a hard cut gives 0.5).
    haze_weight : a dissolve whose two shots' fitted weights sum below this somewhere passes
        through a third picture (a haze) and is placed like a fade (0.5; :mod:`.blend`).
    min_shot : shortest shot, ticks; a boundary closer to the previous one is dropped (2).
    flash_ticks : longest flash, ticks: cut flags this close that leave the shot as it was are a flash (5).
    """

    flat_std: float = 5.0
    empty_std: float = 1.0
    card_corr: float = 0.5
    still_corr: float = 0.9
    change_corr: float = 0.6
    dark_level: float = 16.0
    min_ramp: int = 2
    max_ramp: int = 30
    widths: tuple[int, ...] = (2, 3, 4, 6, 8, 12)
    linear_max: float = 0.2
    haze_weight: float = 0.5
    min_shot: int = 2
    flash_ticks: int = 5
    cut_params: cuts.CutParams = cuts.CutParams()


@dataclass(frozen=True)
class Boundaries:
    """tick : first tick of each shot after the first, int32 [shape=(m,)], increasing, in 1..n-1.
    kind : code of each boundary (index into KINDS: 1 cut, 2 fade, 3 dissolve), uint8 [shape=(m,)].
    span : the transition's ticks [s0, s1), int32 [shape=(m, 2)] (a cut: [tick, tick + 1)).
    """

    tick: np.ndarray
    kind: np.ndarray
    span: np.ndarray

    @classmethod
    def build(cls, found: list[tuple[int, int, int, int]]) -> "Boundaries":
        """From (tick, kind, s0, s1) tuples in any order."""
        rows = sorted(found)
        arr = np.asarray(rows, np.int64).reshape(-1, 4)
        return cls(tick=arr[:, 0].astype(np.int32), kind=arr[:, 1].astype(np.uint8),
                   span=arr[:, 2:4].astype(np.int32))


def detect(*, cut: np.ndarray, signature: np.ndarray | None = None, mean_rgb: np.ndarray | None = None,
           frame_mask: np.ndarray | None = None, params: ShotParams = ShotParams()) -> Boundaries:
    """The shot boundaries of a film from the video pass's per-tick arrays.

    cut : bool [shape=(n,)], the video pass's cut flags.
    signature : packed cut signatures uint8 [shape=(n, 192)] (rows of zeros: none), or None.
    mean_rgb : mean colour 0..255 [shape=(n, 3)], used where signatures are missing, or None.
    frame_mask : bool [shape=(n,)], ticks with a frame of their own (None: all). The others hold
        their values (below 10 fps, ``video.stride``): detection runs on the analysed ticks and a
        boundary lands midway between the last analysed tick before it and the first after.
    """
    cut = np.asarray(cut, bool)
    n = cut.size
    if signature is not None and np.shape(signature) != (n, cuts.PACKED_SIZE):
        raise ParameterError(f"signatures must have shape ({n}, {cuts.PACKED_SIZE}), got {np.shape(signature)}")
    rows = np.arange(n) if frame_mask is None else np.flatnonzero(np.asarray(frame_mask, bool))
    if rows.size < n:
        cut = cut[rows]
        signature = None if signature is None else np.asarray(signature)[rows]
        mean_rgb = None if mean_rgb is None else np.asarray(mean_rgb)[rows]
    found = []
    for pos, kind, s0, s1 in _detect(cut, signature, mean_rgb, params):
        # pos: where the boundary lies in row units (row k's frame at k); a row's frame sits at
        # its tick's centre (tick + 0.5), the boundary tick is the nearest tick edge
        tick = int(np.floor(np.interp(pos, np.arange(rows.size), rows + 0.5) + 0.5))
        found.append((tick, kind, min(tick, int(rows[s0])), max(tick + 1, int(rows[s1 - 1]) + 1)))
    return Boundaries.build(_spaced(found, n, params.min_shot))


def _detect(cut: np.ndarray, signature, mean_rgb, params: ShotParams) -> list[tuple[float, int, int, int]]:
    """(position in rows, kind, first row, end row) of each boundary over rows that each have a frame."""
    n = cut.size
    sigs, valid = _signatures(signature, n)
    level, flat = _flatness(sigs, valid, mean_rgb, n, params)
    found: list[tuple[float, int, int, int]] = []
    claimed = np.zeros(n, bool)  # rows inside a fade's ramps
    card, step = _low_detail_cuts(sigs, valid, level, mean_rgb, params)
    for s0, s1, pos in _fades(level, flat, cut, card, sigs, valid, mean_rgb, params):
        found.append((pos, FADE, s0, s1))
        claimed[s0 + 1:s1] = True  # cut flags between the span's rows; one at s0 is a cut into it
    for k in _cuts((cut | card) & ~claimed, sigs, valid, mean_rgb, params):
        found.append((k - 0.5, CUT, k, k + 1))
    cut_rows = {s0 for _, kind, s0, _ in found if kind == CUT}
    for k in np.flatnonzero((step | _still_cuts(sigs, valid, level, params)) & ~claimed).tolist():
        if not cut_rows & {k - 1, k, k + 1}:
            found.append((k - 0.5, CUT, k, k + 1))
    busy = claimed.copy()
    for _, kind, s0, _ in found:
        if kind == CUT:
            busy[s0] = True
    for s0, s1, pos in _dissolves(sigs, valid, level, flat | busy, params):
        found.append((pos, DISSOLVE, s0, s1))
    return found


def _signatures(signature: np.ndarray | None, n: int) -> tuple[np.ndarray | None, np.ndarray]:
    if signature is None:
        return None, np.zeros(n, bool)
    packed = np.asarray(signature)
    valid = packed[:, :3 * 16].any(axis=1)
    return cuts.unpack_signatures(packed), valid


def _flatness(sigs, valid, mean_rgb, n, params) -> tuple[np.ndarray, np.ndarray]:
    """A per-tick level that grows with the picture's content (thumbnail std, else luma) and
    whether the tick is flat."""
    luma = np.zeros(n) if mean_rgb is None else np.asarray(mean_rgb, np.float64).reshape(n, 3) @ _LUMA
    if sigs is None:
        return luma, (luma <= params.dark_level) if mean_rgb is not None else np.zeros(n, bool)
    std = cuts.thumbnails(sigs).std(axis=1).astype(np.float64)
    return np.where(valid, std, np.inf), valid & (std < params.flat_std)


def _runs(mask: np.ndarray) -> list[tuple[int, int]]:
    """Inclusive (first, last) of each run of True."""
    m = np.concatenate([[False], mask, [False]]).astype(np.int8)
    edges = np.flatnonzero(np.diff(m))
    return [(int(a), int(b) - 1) for a, b in zip(edges[::2], edges[1::2])]


def _same_shot(i: int, j: int, sigs, valid, mean_rgb, params, *, either: bool = False) -> bool:
    """Ticks i and j show the same shot: the cut rule finds no cut between their signatures (a
    little below 0.5 for the rounding of packed rows; ``either`` as in ``cuts.cut_scores``), else
    their mean colours are within 20 levels."""
    if sigs is not None and valid[i] and valid[j]:
        if _pictures_differ(sigs[[i, j]], params)[0]:
            return False
        return float(cuts.cut_scores(sigs[i], sigs[j], params=params.cut_params, either=either)[0]) < 0.45
    if mean_rgb is not None:
        rgb = np.asarray(mean_rgb, np.float64)
        return float(np.abs(rgb[i] - rgb[j]).max()) < 20.0
    return False


def _ramp(level: np.ndarray, stop: np.ndarray, start: int, step: int, params: ShotParams) -> int:
    """From tick ``start`` (just outside a flat run) outward by ``step``: the last tick of the
    ramp, where the content stops growing or a cut (``stop[k]``: a cut between k - 1 and k) ends it."""
    j, n = start, level.size
    while 0 <= j + step < n and abs(j + step - start) < params.max_ramp and \
            level[j + step] > 1.05 * level[j] + min(0.5, 0.1 * level[j]) and not stop[max(j, j + step)]:
        j += step
    return j


def _fades(level, flat, cut, card, sigs, valid, mean_rgb, params):
    """(s0, s1, tick) of each fade through a flat picture: the span covers both ramps. A ramp
    ends at a cut flagged between two ticks with content (the flat rule flags fast fades) or at
    a layout change next to a flat tick (``card``)."""
    n = level.size
    stop = (cut & ~flat & ~np.roll(flat, 1)) | card
    for a, b in _cores(flat, level < params.empty_std):
        if a == 0 or b == n - 1:
            continue  # the film opens or ends on it: no shot on one side
        left, right = _ramp(level, stop, a - 1, -1, params), _ramp(level, stop, b + 1, 1, params)
        if max(a - left, right - b) < params.min_ramp:
            continue  # cut to a flat shot and back: the cut rule's
        if min(a - left, right - b) < params.min_ramp and card[a:b + 2].any() and level[a:b + 1].max() >= params.empty_std:
            continue  # a picture dims (not to black) and cuts to another: the cut's
        if _same_shot(left, right, sigs, valid, mean_rgb, params, either=True):
            continue  # a dip (or a flash) inside one shot
        yield left, right + 1, 0.5 * (a + b)


def _cores(flat: np.ndarray, empty: np.ndarray) -> list[tuple[int, int]]:
    """The runs a fade may pass through: each flat run, or its empty runs where it holds some
    (the flat ticks around them are then pictures of little detail: a title card, a dim ramp)."""
    out = []
    for a, b in _runs(flat):
        inner = [(a + c, a + d) for c, d in _runs(empty[a:b + 1])]
        out.extend(inner or [(a, b)])
    return out


def _pictures_differ(pair: np.ndarray, params: ShotParams) -> np.ndarray:
    """For signature pairs [shape=(m, 2, 192)] (or one pair (2, 192)): both thumbnails have detail
    (std >= ``empty_std``), at least one is flat and their layouts differ (correlation <=
    ``card_corr``). The cut rule weighs only the brightness of a flat tick, which a dark card or a
    dim picture barely moves; bool [shape=(m,)]."""
    th = cuts.thumbnails(pair.reshape(-1, cuts.PACKED_SIZE)).astype(np.float64)
    th = th.reshape(-1, 2, th.shape[1])
    dev = th - th.mean(axis=2, keepdims=True)
    ss = (dev * dev).sum(axis=2)
    std = np.sqrt(ss / th.shape[2])
    corr = (dev[:, 0] * dev[:, 1]).sum(axis=1) / np.sqrt(np.maximum(ss[:, 0] * ss[:, 1], 1e-12))
    return (std.min(axis=1) >= params.empty_std) & (std.min(axis=1) < params.flat_std) & (corr <= params.card_corr)


def _low_detail_cuts(sigs, valid, level, mean_rgb, params) -> tuple[np.ndarray, np.ndarray]:
    """Cuts the cut rule cannot see, per row k (between k - 1 and k), bool [shape=(n,)] each:
    ``card``: :func:`_pictures_differ`; ``step``: a steady picture with some detail (std >= 3x
    ``empty_std``, its other neighbour within 20 %) next to a run of empty ticks whose far side
    is another shot or the film's end (a cut to or from an empty picture that its brightness does
    not show; a fade ramps over ticks instead, a flash returns to the same shot)."""
    n = level.size
    card, step = np.zeros(n, bool), np.zeros(n, bool)
    if sigs is None or n < 3:
        return card, step
    lo = np.minimum(level[1:], level[:-1])
    cand = np.flatnonzero(valid[1:] & valid[:-1] & (lo >= params.empty_std) & (lo < params.flat_std)) + 1
    if cand.size:
        card[cand] = _pictures_differ(np.stack([sigs[cand - 1], sigs[cand]], axis=1), params)
    lv = np.where(valid, level, 0.0)

    def steady(k: int, far: int) -> bool:
        return 0 <= far < n and valid[k] and valid[far] and lv[k] >= 3 * params.empty_std and \
            abs(lv[k] - lv[far]) <= 0.2 * lv[k]

    for a, b in _runs(valid & (level < params.empty_std)):
        if 0 < a and b + 1 < n and _same_shot(a - 1, b + 1, sigs, valid, mean_rgb, params):
            continue  # a flash or a dip inside one shot
        step[a] = a > 0 and steady(a - 1, a - 2)
        if b + 1 < n:
            step[b + 1] = steady(b + 1, b + 2)
    return card, step


def _still_cuts(sigs, valid, level, params) -> np.ndarray:
    """Per row k, bool [shape=(n,)]: a cut between rows k - 1 and k that the cut rule's colour
    test misses (two shots of one palette), seen because the layout changes at k alone: rows
    k - 2, k - 1 and k, k + 1 each correlate >= ``still_corr``, rows k - 1, k and k - 2, k + 1
    <= ``change_corr``; all four have detail (std >= ``flat_std``)."""
    n = level.size
    out = np.zeros(n, bool)
    if sigs is None or n < 4:
        return out
    ok = valid & (level >= params.flat_std)
    corr1, corr3 = np.ones(n), np.ones(n)  # corr1[k]: rows k - 1, k; corr3[k]: rows k - 2, k + 1
    for i in range(0, n, _CHUNK):  # unit-norm centred thumbnails in chunks (72,000 rows: 41 MB at once)
        lo, hi = max(0, i - 2), min(n, i + _CHUNK + 1)
        th = cuts.thumbnails(sigs[lo:hi]).astype(np.float64)
        th -= th.mean(axis=1, keepdims=True)
        th /= np.maximum(np.sqrt((th * th).sum(axis=1, keepdims=True)), 1e-9)
        k = np.arange(max(i, 1), min(n, i + _CHUNK))
        corr1[k] = np.einsum("ij,ij->i", th[k - 1 - lo], th[k - lo])
        k3 = k[(k >= 2) & (k + 1 < hi)]
        corr3[k3] = np.einsum("ij,ij->i", th[k3 - 2 - lo], th[k3 + 1 - lo])
    k = np.arange(2, n - 1)
    hit = ok[k - 2] & ok[k - 1] & ok[k] & ok[k + 1] & (corr1[k] <= params.change_corr) & \
        (corr3[k] <= params.change_corr) & (corr1[k - 1] >= params.still_corr) & (corr1[k + 1] >= params.still_corr)
    out[k[hit]] = True
    return out


def _cuts(cut: np.ndarray, sigs, valid, mean_rgb, params):
    """The boundary tick of each run of cut flags whose two sides are different shots. Runs less
    than ``flash_ticks`` apart are tried together first: a flash flags its start and its end."""
    runs = [r for r in _runs(cut) if r[0] > 0]
    i = 0
    while i < len(runs):
        a, b = runs[i]
        j = i
        while j + 1 < len(runs) and runs[j + 1][0] - runs[j][1] <= params.flash_ticks:
            j += 1
        comparable = sigs is not None and valid[a - 1]
        flash = next((m for m in range(j, i - 1, -1) if (m > i or b > a or comparable and valid[b])
                      and _same_shot(a - 1, runs[m][1], sigs, valid, mean_rgb, params)), None)
        if flash is not None:
            i = flash + 1  # runs i..flash start and end one flash
            continue
        if sigs is None or not valid[a - 1:b + 1].all():
            if b == a or not _same_shot(a - 1, b, sigs, valid, mean_rgb, params):
                yield b  # nothing to compare tick by tick: the run is one cut (one flag: the pass's rule)
        else:  # a run may hold several cuts (shots of a few ticks); a flag of the flow pair alone is none
            for k in range(a, b + 1):
                if not _same_shot(k - 1, k, sigs, valid, mean_rgb, params):
                    yield k
        i += 1


_CHUNK = 4096  # rows of signatures compared at once (float64 copies: 6 MB a side)


def _dissolves(sigs, valid, level, blocked, params):
    """(s0, s1, tick) of each cross-dissolve (module docstring)."""
    if sigs is None:
        return
    n = valid.size
    blocks = blend.coarse(sigs)
    usable = valid & ~blocked
    bad = np.concatenate([[0], np.cumsum(~usable)])  # prefix count of unusable ticks: a window in O(1)
    best_r = np.full(n, np.inf)
    best_w = np.zeros(n, np.int64)
    widths = np.zeros(n, np.int64)  # how many widths find tick c linear
    for w in sorted(params.widths):
        if 2 * w + 1 > n:
            break
        c = np.arange(w, n - w)
        c = c[bad[c + w + 1] - bad[c - w] == 0]
        ends = blocks[c + w] - blocks[c - w]
        mid = blocks[c] - 0.5 * (blocks[c - w] + blocks[c + w])
        r = np.sqrt((mid * mid).sum(axis=1) / np.maximum((ends * ends).sum(axis=1), 1e-9))
        c, r = c[r <= params.linear_max], r[r <= params.linear_max]  # the cheap test first
        apart = np.zeros(c.size, bool)
        for i in range(0, c.size, _CHUNK):  # in chunks: a still film passes the cheap test everywhere
            part = c[i:i + _CHUNK]
            apart[i:i + _CHUNK] = cuts.cut_scores(sigs[part - w], sigs[part + w], params=params.cut_params) >= 0.5
        c, r = c[apart], r[apart]
        widths[c] += 1
        better = r < best_r[c]
        best_r[c[better]], best_w[c[better]] = r[better], w
    spans = []  # (s0, s1, k) of each run; runs whose spans overlap are one transition
    for a, b in _runs(np.isfinite(best_r)):
        if widths[a:b + 1].max() < 2:
            continue  # linear at one width only: a slow camera move, not a blend
        k = a + int(np.argmin(best_r[a:b + 1]))
        w = int(best_w[a:b + 1].max())
        s0, s1 = max(0, a - w), min(n, b + w + 1)
        if spans and s0 < spans[-1][1] and usable[spans[-1][1] - 1:s0 + 1].all():
            p0, _, pk = spans.pop()
            s0, k = p0, (pk if best_r[pk] <= best_r[k] else k)
        spans.append((s0, s1, k))
    for s0, s1, k in spans:
        s0, s1 = blend.widened(level, usable, s0, s1, params.max_ramp)
        yield s0, s1, blend.half_way(blocks, s0, s1 - 1, k, blend.between(best_r, k), params.haze_weight)


def _spaced(found, n: int, min_shot: int):
    """Boundaries in order, inside 1..n-1, each at least ``min_shot`` ticks after the one before
    (an earlier boundary wins)."""
    out, last = [], 0
    for tick, kind, s0, s1 in sorted(found):
        if tick <= 0 or tick >= n or tick - last < min_shot:
            continue
        if n - tick < min_shot:
            continue
        out.append((tick, kind, s0, s1))
        last = tick
    return out
