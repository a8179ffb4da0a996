"""Learning a :class:`~autohaptics.style.model.Style` from films a designer edited: each pair is a
film's cached analysis and the designer's edited (composed) timeline of it; ``params`` are the
parameters the designer started from. Fitted on sampled ticks, without decoding:

1. the threshold scale (0.5..2 in sixth-octaves): stepping away from 1 while most of the ticks a
   step wakes (or silences) vibrate (or are silent) in the edited timelines (:data:`STEP_SHARE`);
2. a tone curve per actuator and one for the fans, on the ticks where the derive at that scale is
   on: the edit ``edited - derived`` as a piecewise-linear function of the derived level, fitted
   by least absolute deviations (iteratively reweighted), so one-off edits of a scene or two
   (a minority of the ticks at each level) do not move it;
3. the temperature: ``edited - derived = offset_c + (scale - 1) * (derived - neutral_c)``, the same
   robust fit (scale to 0.001, offset to 0.01 C).
Unedited films give the identity style exactly (every fitted edit is exactly 0).
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from autohaptics.errors import ParameterError
from autohaptics.params import GenerateParams
from autohaptics.pipeline.cache import Analysis
from autohaptics.pipeline.derive import derive
from autohaptics.style.model import KNOTS, TEMP_OFFSET_RANGE_C, TEMP_SCALE_RANGE, Style
from autohaptics.timeline import Timeline

SCALES: tuple[float, ...] = tuple(round(2.0 ** (e / 6), 4) for e in range(-6, 7))
STEP_SHARE = 2 / 3  # of the ticks a threshold step changes that must agree with the edits
MAX_TICKS = 6000  # ticks sampled per film (a 2-hour film has 72,000)
OFF_LEVEL = 1 / 255  # a fitted level below one step of the chair's 0..255 levels is off
MAX_FAN_LEVELS = 400_000  # fan levels above 0 fitted at most (sampled evenly)
_IRLS_STEPS, _IRLS_FLOOR, _RIDGE, _SMOOTH = 10, 0.01, 1e-6, 1e-3

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
    scale, f1 = _threshold_scale(pairs, params, picks)
    probe = Style(threshold_scale=scale)
    bases = [derive(a, probe.apply_params(params)) for a, _ in pairs]
    vib_x = np.concatenate([b.vibration[p] for b, p in zip(bases, picks)])
    vib_y = np.concatenate([e.vibration[p] for (_, e), p in zip(pairs, picks)])
    fan_x = np.concatenate([b.fans[p].reshape(-1) for b, p in zip(bases, picks)])
    fan_y = np.concatenate([e.fans[p].reshape(-1) for (_, e), p in zip(pairs, picks)])
    t_scale, t_offset = _fit_temperature(bases, [e for _, e in pairs], picks, params)
    learned = {"films": len(pairs), "ticks": int(sum(p.size for p in picks)), "vibration_f1": round(f1, 4),
               "mode": params.mode}
    return Style(name=name, threshold_scale=scale, knots=KNOTS,
                 vibration=tuple(fit_curve(vib_x[:, a], vib_y[:, a], KNOTS) for a in range(vib_x.shape[1])),
                 fans=fit_curve(*_thin(fan_x, fan_y), KNOTS), temperature_scale=t_scale,
                 temperature_offset_c=t_offset, learned=learned)


def fit_curve(x: np.ndarray, y: np.ndarray, knots: tuple[float, ...] = KNOTS) -> tuple[float, ...]:
    """The tone curve (levels at ``knots``, 0..1, starting at 0, never decreasing, 4 decimals, below
    :data:`OFF_LEVEL` off) that maps the derived levels ``x`` to the edited levels ``y`` (both 0..1,
    same shape), fitted where ``x > 0`` by least absolute deviations. No edit gives ``knots`` exactly."""
    keep = x > 0
    x, r = x[keep].astype(np.float64), (y[keep].astype(np.float64) - x[keep])
    if not np.any(r):
        return tuple(knots)
    delta = np.concatenate([[0.0], _robust_fit(_hats(x, knots)[:, 1:], r, _bends(knots))])
    curve = np.maximum.accumulate(np.clip(np.asarray(knots) + delta, 0.0, 1.0))
    curve[curve < OFF_LEVEL] = 0.0
    return tuple(round(float(v), 4) for v in curve)


# ----------------------------------------------------------------------- private
def _check_pair(analysis: Analysis, edited: Timeline) -> None:
    name = edited.source.get("name") or "the edited timeline"
    if edited.n_ticks != analysis.n_ticks:
        raise ParameterError(f"{name}: the edited timeline has {edited.n_ticks} ticks, its film "
                             f"{analysis.n_ticks}: not a timeline of this film")
    sha = edited.source.get("sha256")
    if sha and analysis.sha256 and sha != analysis.sha256:
        raise ParameterError(f"{name}: the edited timeline is of another film (source.sha256 differs)")


def _threshold_scale(pairs: list[Pair], params: GenerateParams, picks: list[np.ndarray]) -> tuple[float, float]:
    """(scale, its pooled vibrating-tick F1): from 1, each step down the candidates is taken while
    STEP_SHARE of the ticks it wakes vibrate in the edited timelines, else each step up while
    STEP_SHARE of the ticks it silences are silent there. A one-off edit (a scene set or cleared) covers a few
    of the ticks a step changes, a taste for more or fewer events most of them."""
    if params.intensity.density is not None or params.mode not in ("multimodal", "audio"):
        return 1.0, float("nan")  # the thresholds do not decide which ticks vibrate here
    wanted = np.concatenate([e.vibration[p].max(axis=1) > 0 for (_, e), p in zip(pairs, picks)])

    def active(scale: float) -> np.ndarray:
        params_k = Style(threshold_scale=scale).apply_params(params)
        return np.concatenate([derive(a, params_k).vibration[p].max(axis=1) > 0 for (a, _), p in zip(pairs, picks)])

    at_one = active(1.0)
    scale = 1.0
    for steps, agree in ((sorted((s for s in SCALES if s < 1.0), reverse=True), wanted),
                         (sorted(s for s in SCALES if s > 1.0), ~wanted)):
        previous = at_one
        for candidate in steps:
            now = active(candidate)
            changed = now != previous
            if changed.any():
                if np.count_nonzero(agree[changed]) < STEP_SHARE * np.count_nonzero(changed):
                    break
                scale, previous = candidate, now
        if scale != 1.0:
            break
    got = active(scale)
    tp, fp, fn = int(np.sum(got & wanted)), int(np.sum(got & ~wanted)), int(np.sum(~got & wanted))
    return scale, 1.0 if tp + fp + fn == 0 else 2 * tp / (2 * tp + fp + fn)


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


def _robust_fit(a: np.ndarray, r: np.ndarray, bends: np.ndarray | None = None) -> np.ndarray:
    """Coefficients c minimising sum |a @ c - r| (iteratively reweighted least squares) plus a light
    penalty on ``bends @ c`` (so knots without data follow their neighbours' line) and a tiny ridge."""
    w = np.ones(r.size)
    penalty = _RIDGE * np.eye(a.shape[1])
    if bends is not None:
        penalty = penalty + bends.T @ bends
    c = np.zeros(a.shape[1])
    for _ in range(_IRLS_STEPS):
        aw = a * w[:, None]
        c = np.linalg.solve(aw.T @ a + _SMOOTH * w.sum() * penalty / r.size, aw.T @ r)
        w = 1.0 / np.maximum(np.abs(r - a @ c), _IRLS_FLOOR)
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


def _thin(x: np.ndarray, y: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """At most MAX_FAN_LEVELS of the levels where x > 0, evenly spaced (the rest add nothing)."""
    on = np.flatnonzero(x > 0)
    if on.size > MAX_FAN_LEVELS:
        on = on[np.linspace(0, on.size - 1, MAX_FAN_LEVELS).astype(np.int64)]
    return x[on], y[on]
