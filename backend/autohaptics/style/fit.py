"""Learning a :class:`~autohaptics.style.model.Style` from films a designer edited: each pair is a
film's cached analysis and the designer's edited (composed) timeline of it; ``params`` are the
parameters the designer started from. Fitted on sampled ticks, without decoding:

1. the threshold scale (0.25..4 in 1/24 octaves): the intensity rule applied to the analysis's own
   decision curves (the novelty the thresholds apply to) says which ticks vibrate at each scale;
   each tick votes by how much better "woken, in the style" explains its edited levels than "off"
   (a drawn one-off burst votes near 0), and the scale moves away from 1 only while the ticks it
   changes vote :data:`STEP_SHARE` its way;
2. a floor per body zone (back, armrests, seat: their actuators' levels pooled; the floor of all
   of them where the zone's levels cannot place one) and one for the fans: the level below which
   the edited timelines are off (then 1 and 2 once more with the floors known);
3. a tone curve per actuator and one for the fans, on the levels the derive at that scale has at
   or above the floor: the edit ``edited - derived`` as a piecewise-linear function of the derived
   level, fitted by a robust loss per 2 s block (:data:`BLOCK_TICKS`: a block that does not follow
   the curve weighs as one vote, however many ticks it has), so one-off edits of a scene or two
   do not move it;
4. the temperature: ``edited - derived = offset_c + (scale - 1) * (derived - neutral_c)``, robust
   (least absolute deviations; scale to 0.001, offset to 0.01 C).
Unedited films give the identity style exactly (every fitted edit is exactly 0).
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from autohaptics.errors import ParameterError
from autohaptics.intensity.rule import FEATURES, LEVEL_FEATURES, trigger_depths
from autohaptics.layout import ACTUATORS, ZONES
from autohaptics.params import GenerateParams
from autohaptics.pipeline.cache import Analysis
from autohaptics.pipeline.derive import derive, kept_decision_inputs
from autohaptics.style.apply import shape_vibration
from autohaptics.style.model import KNOTS, TEMP_OFFSET_RANGE_C, TEMP_SCALE_RANGE, THRESHOLD_SCALE_RANGE, Style
from autohaptics.timeline import Timeline

SCALE_GRID = np.unique(np.append(np.geomspace(*THRESHOLD_SCALE_RANGE, 97).round(3), 1.0))  # 1/24 octave
STEP_SHARE = 2 / 3  # of the ticks a threshold or floor changes that must agree with the edits
MAX_TICKS = 6000  # ticks sampled per film (a 2-hour film has 72,000)
OFF_LEVEL = 1 / 255  # a fitted level below one step of the chair's 0..255 levels is off
MAX_FAN_LEVELS = 400_000  # fan levels above 0 fitted at most (sampled evenly)
BLOCK_TICKS = 20  # 2 s: the unit of the robust curve fit (a one-off edit covers a scene, a taste every scene)
SHRINK = 10.0  # levels' worth of evidence per knot an actuator's curve needs to depart from its zone's
_IRLS_STEPS, _IRLS_FLOOR, _RIDGE, _SMOOTH = 12, 0.01, 1e-6, 1e-3

Pair = tuple[Analysis, Timeline]


def learn(pairs: Sequence[Pair], params: GenerateParams | None = None, *, name: str = "",
          max_ticks: int = MAX_TICKS, seed: int = 0) -> Style:
    """The style that turns ``params``' derive of each film into its edited timeline (module doc).

    pairs : (analysis, edited timeline) per film; each timeline has the analysis's n_ticks.
    max_ticks : ticks sampled per film (seeded by ``seed``: the same pairs give the same style).
    """
    params = params or GenerateParams()
    pairs = list(pairs)
    if not pairs:
        raise ParameterError("learning a style needs at least one (film, edited timeline) pair")
    for analysis, edited in pairs:
        _check_pair(analysis, edited)
    rng = np.random.default_rng(seed)
    picks = [np.sort(rng.choice(a.n_ticks, min(a.n_ticks, max_ticks), replace=False)) for a, _ in pairs]
    blocks = np.concatenate([i * (1 << 32) + p // BLOCK_TICKS for i, p in enumerate(picks)])
    vib_y = np.concatenate([e.vibration[p] for (_, e), p in zip(pairs, picks)])
    floors = np.zeros(vib_y.shape[1])
    evidence = _scale_evidence(pairs, params, picks)
    scale, derived = 1.0, None
    for _ in range(2):
        scale, f1 = _threshold_scale(evidence, floors, at=scale)
        if derived != scale:  # the second pass's scale is most often the first's: its derive again
            bases = [derive(a, Style(threshold_scale=scale).apply_params(params)) for a, _ in pairs]
            derived = scale
        vib_x = np.concatenate([b.vibration[p] for b, p in zip(bases, picks)])
        floors = _zone_floors(vib_x, vib_y)
        if not floors.any():
            break
    fan_x = np.concatenate([b.fans[p].reshape(len(p), -1) for b, p in zip(bases, picks)])
    fan_y = np.concatenate([e.fans[p].reshape(len(p), -1) for (_, e), p in zip(pairs, picks)])
    fan_x, fan_y, fan_blocks = _thin(fan_x, fan_y, blocks)
    fan_floor = fit_floor(fan_x, fan_y)
    t_scale, t_offset = _fit_temperature(bases, [e for _, e in pairs], picks, params)
    learned = {"films": len(pairs), "ticks": int(sum(p.size for p in picks)), "vibration_f1": round(f1, 4),
               "mode": params.mode}
    vibration = _zone_curves(vib_x, vib_y, floors, blocks)
    return Style(name=name, threshold_scale=scale, knots=KNOTS, vibration=vibration,
                 fans=fit_curve(fan_x, fan_y, KNOTS, floor=fan_floor, blocks=fan_blocks), temperature_scale=t_scale,
                 temperature_offset_c=t_offset, vibration_floor=tuple(float(f) for f in floors),
                 fans_floor=fan_floor, learned=learned)


def fit_curve(x: np.ndarray, y: np.ndarray, knots: tuple[float, ...] = KNOTS, *, floor: float = 0.0,
              blocks: np.ndarray | None = None, prior: tuple[float, ...] | None = None) -> tuple[float, ...]:
    """The tone curve (levels at ``knots``, 0..1, starting at 0, never decreasing, 4 decimals, below
    :data:`OFF_LEVEL` off) that maps the derived levels ``x`` to the edited levels ``y`` (both 0..1,
    same shape), fitted where ``x > 0`` and ``x >= floor`` by a robust loss: least absolute
    deviations, or with ``blocks`` (a block id per level) the sum over blocks of their residuals'
    norms. ``prior``: a curve (at ``knots``) the fit departs from only as far as the levels insist
    (:data:`SHRINK` levels' worth per knot; no levels: the prior). No edit gives ``knots`` exactly."""
    keep = (x > 0) & (x >= floor)
    x, r = x[keep].astype(np.float64), (y[keep].astype(np.float64) - x[keep])
    base = np.zeros(len(knots)) if prior is None else np.asarray(prior, np.float64) - np.asarray(knots)
    if not np.any(r) and (prior is None or not x.size):
        return tuple(knots) if prior is None else tuple(prior)
    groups = None if blocks is None else np.unique(blocks[keep], return_inverse=True)[1]
    hats = _hats(x, knots)[:, 1:]
    shrink = None if prior is None else SHRINK
    delta = base + np.concatenate([[0.0], _robust_fit(hats, r - hats @ base[1:], _bends(knots), groups, shrink)])
    curve = np.maximum.accumulate(np.clip(np.asarray(knots) + delta, 0.0, 1.0))
    curve[curve < OFF_LEVEL] = 0.0
    return tuple(round(float(v), 4) for v in curve)


def fit_floor(x: np.ndarray, y: np.ndarray) -> float:
    """The level (0..1, 4 decimals) below which the derived levels ``x`` are off (``y`` 0) in the
    edited ones: the cut between two neighbouring levels where ``x > 0`` that misclassifies the
    fewest, taken (else 0) when :data:`STEP_SHARE` of the levels below it are off. No edit gives 0."""
    on = x > 0
    xs, off = x[on].astype(np.float64), y[on] <= 0
    if not off.any():
        return 0.0
    order = np.argsort(xs, kind="stable")
    xs, off = xs[order], off[order]
    below_off = np.concatenate([[0], np.cumsum(off)])  # off among the k lowest, k = 0..n
    k = np.arange(xs.size + 1)
    errors = (k - below_off) + (below_off[-1] - below_off)
    cuts = np.flatnonzero(np.append(xs[1:] > xs[:-1], True)) + 1  # k whose cut falls between two levels
    ok = cuts[below_off[cuts] >= STEP_SHARE * cuts]
    if ok.size == 0 or errors[ok].min() >= errors[0]:
        return 0.0
    best = int(ok[np.argmin(errors[ok])])
    upper = xs[best] if best < xs.size else 1.0
    return round(float(min((xs[best - 1] + upper) / 2, 1.0)), 4)


# ----------------------------------------------------------------------- private
def _check_pair(analysis: Analysis, edited: Timeline) -> None:
    name = edited.source.get("name") or "the edited timeline"
    if edited.n_ticks != analysis.n_ticks:
        raise ParameterError(f"{name}: the edited timeline has {edited.n_ticks} ticks, its film "
                             f"{analysis.n_ticks}: not a timeline of this film")
    sha = edited.source.get("sha256")
    if sha and analysis.sha256 and sha != analysis.sha256:
        raise ParameterError(f"{name}: the edited timeline is of another film (source.sha256 differs)")


def _scale_evidence(pairs: list[Pair], params: GenerateParams,
                    picks: list[np.ndarray]) -> tuple[np.ndarray, ...] | None:
    """On the sampled ticks: which vibrate at each scale of :data:`SCALE_GRID` (bool [shape=(ticks,
    scales)]: the intensity rule on the film's decision curves, computed once, no derive per scale),
    the levels at the lowest scale and the edited ones [shape=(ticks, 9)], and each tick's 2 s block;
    None where the thresholds do not decide which ticks vibrate (a density, the picture modes)."""
    if params.intensity.density is not None or params.mode not in ("multimodal", "audio"):
        return None
    lowest = Style(threshold_scale=THRESHOLD_SCALE_RANGE[0]).apply_params(params)
    rules = [Style(threshold_scale=float(s)).apply_params(params).intensity for s in SCALE_GRID]
    thresholds = [[rule.threshold(f) for f in FEATURES] for rule in rules]
    value_features = FEATURES if params.intensity.rule == "thesis" else LEVEL_FEATURES
    ons, levels, edits, blocks = [], [], [], []
    for i, ((analysis, edited), p) in enumerate(zip(pairs, picks)):
        if analysis.audio is None:
            continue
        norm, curves = kept_decision_inputs(analysis.audio, params.intensity)
        depth = trigger_depths(norm, curves, thresholds, analysis.n_ticks, params=params.intensity,
                               value_features=value_features)
        ons.append(depth[p][:, None] > np.arange(len(SCALE_GRID)))
        levels.append(derive(analysis, lowest).vibration[p])
        edits.append(edited.vibration[p])
        blocks.append(i * (1 << 32) + p // BLOCK_TICKS)
    return tuple(np.concatenate(v) for v in (ons, levels, edits, blocks)) if ons else None


def _votes(evidence: tuple, floors: np.ndarray, at: float) -> tuple[np.ndarray, np.ndarray]:
    """(can, vote) per sampled tick of :func:`_scale_evidence`: ``can`` where the style would vibrate
    the tick if the thresholds woke it (its levels at the lowest scale through the floors and the
    zone curves fitted on the ticks vibrating at scale ``at``); ``vote`` -1..1, how much better
    "woken, in the style" explains the edited levels than "off": (d_off - d_on) / (d_off + d_on),
    d the L1 distances to off and to the styled levels (an edit that is neither, a one-off burst,
    votes near 0)."""
    on, levels, edited, blocks = evidence
    at_k = int(np.argmin(np.abs(SCALE_GRID - at)))
    fit = on[:, at_k] & (levels.max(axis=1) > 0)
    curves = _zone_curves(levels[fit], edited[fit], floors, blocks[fit])
    styled = shape_vibration(levels, KNOTS, curves, tuple(floors))
    d_on = np.abs(edited - styled).sum(axis=1, dtype=np.float64)
    d_off = edited.sum(axis=1, dtype=np.float64)
    can = styled.max(axis=1) > 0
    vote = np.where(can, (d_off - d_on) / np.maximum(d_off + d_on, 1e-12), 0.0)
    return can, vote


def _threshold_scale(evidence: tuple | None, floors: np.ndarray, at: float = 1.0) -> tuple[float, float]:
    """(scale, its pooled vibrating-tick F1) on the ticks that can vibrate, each weighed by its vote
    (:func:`_votes`: ±1 where the edit is clearly on in the style or off): from 1, each sixth-octave
    step down is taken while the ticks it wakes vote on average at least 2 x :data:`STEP_SHARE` - 1
    for "on" (a share of 2/3 of clear votes), else each step up while those it silences vote as
    much for "off" (a one-off edit covers few of the ticks a step changes and a drawn burst votes
    near 0, a taste moves most of them); then, between the last step taken and the first refused,
    the scale of :data:`SCALE_GRID` whose ticks disagree least with their votes (of equals, the
    nearest the step taken)."""
    if evidence is None:
        return 1.0, float("nan")
    can, vote = _votes(evidence, floors, at)
    on, vote, want = evidence[0][can], vote[can], evidence[2][can].max(axis=1) > 0
    need = 2 * STEP_SHARE - 1
    one = int(np.flatnonzero(SCALE_GRID == 1.0)[0])
    pick = stop = one
    for direction in (-1, 1):
        for k in one + direction * np.arange(4, len(SCALE_GRID) // 2 + 1, 4):  # sixth-octave steps
            changed = on[:, k] != on[:, pick]
            if not changed.any():
                continue
            if -direction * vote[changed].mean() < need:
                stop = k
                break
            pick = stop = k
        if pick != one:
            break
    if pick != one and stop != pick:
        lo, hi = sorted((pick, stop))
        errors = np.where(on[:, lo:hi + 1], (1 - vote)[:, None], (1 + vote)[:, None]).sum(axis=0)
        best = lo + np.flatnonzero(errors <= errors.min() + 1e-9)
        pick = int(best[np.argmin(np.abs(best - pick))])
    got = on[:, pick]
    tp, fp, fn = int(np.sum(got & want)), int(np.sum(got & ~want)), int(np.sum(~got & want))
    return float(SCALE_GRID[pick]), 1.0 if tp + fp + fn == 0 else 2 * tp / (2 * tp + fp + fn)


def _zone_floors(x: np.ndarray, y: np.ndarray) -> np.ndarray:
    """A floor per actuator [shape=(9,)]: :func:`fit_floor` of its zone's levels pooled, or of all
    actuators' levels pooled where that one misclassifies no more of the zone's levels (a zone
    whose levels all lie below the floor, or none near it, cannot place it)."""
    pooled = fit_floor(x.reshape(-1), y.reshape(-1))
    floors = np.zeros(x.shape[1])
    for zone in ZONES:
        cols = [i for i, a in enumerate(ACTUATORS) if a.zone == zone]
        zx, zy = x[:, cols].reshape(-1), y[:, cols].reshape(-1)
        own = fit_floor(zx, zy)
        floors[cols] = pooled if _floor_errors(zx, zy, pooled) <= _floor_errors(zx, zy, own) else own
    return floors


def _floor_errors(x: np.ndarray, y: np.ndarray, floor: float) -> int:
    """Levels ``x > 0`` a floor misclassifies: below it but on in ``y``, or at or above it but off."""
    on = x > 0
    return int(np.count_nonzero(on & (x < floor) & (y > 0)) + np.count_nonzero(on & (x >= floor) & (y <= 0)))


def _zone_curves(x: np.ndarray, y: np.ndarray, floors: np.ndarray, blocks: np.ndarray) -> tuple[tuple, ...]:
    """A curve per actuator: its zone's, fitted on the zone's levels pooled (a block across its
    actuators one group), then the actuator's own levels as far as they insist (``prior``)."""
    curves: list = [None] * x.shape[1]
    for zone in ZONES:
        cols = [i for i, a in enumerate(ACTUATORS) if a.zone == zone]
        zone_curve = fit_curve(x[:, cols].reshape(-1), y[:, cols].reshape(-1), KNOTS, floor=floors[cols[0]],
                               blocks=np.repeat(blocks, len(cols)))
        for i in cols:
            curves[i] = fit_curve(x[:, i], y[:, i], KNOTS, floor=floors[i], blocks=blocks, prior=zone_curve)
    return tuple(curves)


def _fit_temperature(bases: list[Timeline], edited: list[Timeline], picks: list[np.ndarray],
                     params: GenerateParams) -> tuple[float, float]:
    """(scale, offset_c) of the edited temperatures against the derived ones, at the sampled ticks
    (those the edit clipped at the device's range left out)."""
    lo, hi = params.thermal.range_c
    x = np.concatenate([b.temperature_c[p] for b, p in zip(bases, picks)]).astype(np.float64)
    y = np.concatenate([e.temperature_c[p] for e, p in zip(edited, picks)]).astype(np.float64)
    keep = ((y > lo) & (y < hi)) | (y == x)
    x, r = x[keep] - params.thermal.neutral_c, y[keep] - x[keep]
    if not np.any(r):
        return 1.0, 0.0
    offset, slope = _robust_fit(np.stack([np.ones_like(x), x], axis=1), r)
    scale = float(np.clip(round(1.0 + float(slope), 3), *TEMP_SCALE_RANGE))
    return scale, float(np.clip(round(float(offset), 2), *TEMP_OFFSET_RANGE_C))


def _robust_fit(a: np.ndarray, r: np.ndarray, bends: np.ndarray | None = None,
                groups: np.ndarray | None = None, shrink: float | None = None) -> np.ndarray:
    """Coefficients c minimising sum |a @ c - r| (with ``groups``, a group index per row: the sum
    over groups of the norm of their residuals; iteratively reweighted least squares) plus a light
    penalty on ``bends @ c`` (so knots without data follow their neighbours' line), a tiny ridge and
    ``shrink`` rows' worth of pull of each coefficient to 0."""
    w = np.ones(r.size)
    penalty = _RIDGE * np.eye(a.shape[1])
    if bends is not None:
        penalty = penalty + bends.T @ bends
    c = np.zeros(a.shape[1])
    for _ in range(_IRLS_STEPS):
        aw = a * w[:, None]
        pull = 0.0 if shrink is None else shrink * w.sum() / r.size * np.eye(a.shape[1])
        c = np.linalg.solve(aw.T @ a + _SMOOTH * w.sum() * penalty / r.size + pull, aw.T @ r)
        res = np.abs(r - a @ c)
        if groups is not None:
            res = np.sqrt(np.bincount(groups, res * res))[groups]
        w = 1.0 / np.maximum(res, _IRLS_FLOOR)
    return c


def _bends(knots: tuple[float, ...]) -> np.ndarray:
    """Changes of slope between neighbouring knot intervals, as rows over the deltas at knots 1..:
    zero for an edit proportional or linear in the level."""
    k = np.asarray(knots)
    rows = np.zeros((k.size - 2, k.size))
    for j in range(k.size - 2):
        h0, h1 = k[j + 1] - k[j], k[j + 2] - k[j + 1]
        rows[j, j], rows[j, j + 1], rows[j, j + 2] = 1 / h0, -1 / h0 - 1 / h1, 1 / h1
    return rows[:, 1:] * np.sqrt(np.diff(k)[:-1].mean())


def _hats(x: np.ndarray, knots: tuple[float, ...]) -> np.ndarray:
    """Linear-interpolation weights [shape=(len(x), len(knots))] of each x between its two knots."""
    k = np.asarray(knots)
    j = np.clip(np.searchsorted(k, x, side="right") - 1, 0, k.size - 2)
    t = (x - k[j]) / (k[j + 1] - k[j])
    out = np.zeros((x.size, k.size))
    rows = np.arange(x.size)
    out[rows, j], out[rows, j + 1] = 1.0 - t, t
    return out


def _thin(x: np.ndarray, y: np.ndarray, blocks: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The fan levels (x, y [shape=(ticks, cells)]) flattened with each level's block, at most
    MAX_FAN_LEVELS of those where x > 0, evenly spaced (the rest add nothing)."""
    blocks = np.repeat(blocks, x.shape[1])
    x, y = x.reshape(-1), y.reshape(-1)
    on = np.flatnonzero(x > 0)
    if on.size > MAX_FAN_LEVELS:
        on = on[np.linspace(0, on.size - 1, MAX_FAN_LEVELS).astype(np.int64)]
    return x[on], y[on], blocks[on]
