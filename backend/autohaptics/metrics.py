"""Error metrics between two timelines of the same source (a reference and a test run).

Every metric is a pure function of arrays on the 100 ms tick grid; :func:`compare_timelines` gathers them into
one JSON-serialisable report. ``ref`` is the reference, ``test`` the run under test; where the two differ in
length only the common ticks ``0 .. min(n_ref, n_test) - 1`` are compared and the difference is reported.

- vibration: mean absolute error over ticks x actuators (0..1), per actuator too, of the chair's
  strongest actuator per tick (``chair_mae``: the timing and level, without the spatial spread), and onset
  agreement. An onset is a tick where an actuator goes from 0 to above 0 (the tick before
  tick 0 counts as 0); a test onset matches a reference onset of the same actuator within
  +-``tolerance`` ticks (default 1), each onset matched at most once. Precision = matched /
  test onsets, recall = matched / reference onsets, F1 their harmonic mean; with no onset on
  either side all three are 1 (the two agree that nothing starts). The same scores for the
  chair as a whole (``chair_onsets``: the strongest actuator per tick) separate the timing of
  events from their spatial distribution, which moves per-actuator onsets on its own.
- temperature: mean and largest absolute error, C.
- fans: a cell is on above ``on_level`` (default 0). Over the ticks where either side has any
  fan on, the IoU of the two sets of on-cells, averaged over those ticks (``iou``) and pooled
  (sum of intersections / sum of unions, ``iou_pooled``); 1 when neither side blows at all.
  Split into WHETHER and WHERE: precision/recall/F1 of the ticks that blow at all
  (``ticks_f1``...), and the mean IoU over the ticks where both blow (``iou_both_on``). The same
  IoUs with a one-cell tolerance (``iou_tolerant``...: an on-cell counts as matched when the other
  side has an on-cell within one cell, 8-neighbourhood; a person cannot tell two neighbouring
  cells apart). Also the mean absolute error of the fan levels over all ticks and cells.
- features: mean absolute error of every per-tick curve present in both.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from autohaptics.errors import ParameterError
from autohaptics.layout import ACTUATOR_IDS, FAN_COLS, FAN_ROWS, N_ACTUATORS

ONSET_TOLERANCE_TICKS = 1


# ----------------------------------------------------------------------- helpers
def common_length(n_ref: int, n_test: int) -> dict:
    """Tick counts of a comparison: {"ref", "test", "common", "difference" (test - ref)}."""
    n_ref, n_test = int(n_ref), int(n_test)
    if n_ref < 0 or n_test < 0:
        raise ParameterError(f"tick counts must be >= 0, got {n_ref} and {n_test}")
    return {"ref": n_ref, "test": n_test, "common": min(n_ref, n_test), "difference": n_test - n_ref}


def _pair(ref: np.ndarray, test: np.ndarray, name: str, trailing: tuple[int, ...] = ()) -> tuple[np.ndarray, np.ndarray]:
    """Both arrays as float64, cut to their common ticks; checks the per-tick shape and finiteness."""
    a = np.asarray(ref, dtype=np.float64)
    b = np.asarray(test, dtype=np.float64)
    for arr, side in ((a, "ref"), (b, "test")):
        if arr.ndim != 1 + len(trailing) or tuple(arr.shape[1:]) != trailing:
            raise ParameterError(f"{name} ({side}) has shape {arr.shape}, expected (n_ticks,) + {trailing}")
        if not np.isfinite(arr).all():
            raise ParameterError(f"{name} ({side}) holds {int((~np.isfinite(arr)).sum())} non-finite value(s)")
    n = min(a.shape[0], b.shape[0])
    return a[:n], b[:n]


def mae(ref: np.ndarray, test: np.ndarray) -> float:
    """Mean absolute error over the common ticks (and every trailing element).

    ref, test : arrays [shape=(n_ref, ...)] and [shape=(n_test, ...)] with the same trailing shape.
    Returns 0.0 when there is no common tick.
    """
    a = np.asarray(ref, dtype=np.float64)
    a, b = _pair(a, test, "values", tuple(a.shape[1:]))
    return float(np.abs(a - b).mean()) if a.size else 0.0


def max_abs_error(ref: np.ndarray, test: np.ndarray) -> float:
    """Largest absolute difference over the common ticks (0.0 without a common tick)."""
    a = np.asarray(ref, dtype=np.float64)
    a, b = _pair(a, test, "values", tuple(a.shape[1:]))
    return float(np.abs(a - b).max()) if a.size else 0.0


# ------------------------------------------------------------------------ onsets
def onsets(x: np.ndarray) -> np.ndarray:
    """Onset ticks of each column: where the value goes from 0 to > 0.

    x : array [shape=(n,)] or [shape=(n, k)], >= 0. The tick before tick 0 counts as 0, so a
    curve already on at tick 0 has an onset there. Returns bool, same shape as ``x``.
    """
    on = np.asarray(x, dtype=np.float64) > 0
    if on.ndim not in (1, 2):
        raise ParameterError(f"onsets expects shape (n,) or (n, k), got {on.shape}")
    before = np.zeros((1,) + on.shape[1:], bool)
    return on & ~np.concatenate([before, on[:-1]], axis=0)


def match_onsets(ref_ticks: np.ndarray, test_ticks: np.ndarray, *, tolerance: int = ONSET_TOLERANCE_TICKS) -> int:
    """Size of the largest one-to-one matching of test onsets to reference onsets within
    +-``tolerance`` ticks.

    ref_ticks, test_ticks : onset tick indices [shape=(m,)], any order. Greedy in time order is
    optimal for points on a line matched within a fixed window: every reference onset takes the
    earliest still-free test onset in its window.
    """
    if tolerance < 0:
        raise ParameterError(f"onset tolerance must be >= 0 ticks, got {tolerance}")
    r = np.sort(np.asarray(ref_ticks, dtype=np.int64))
    t = np.sort(np.asarray(test_ticks, dtype=np.int64))
    j = matched = 0
    for x in r.tolist():
        while j < t.size and t[j] < x - tolerance:
            j += 1
        if j < t.size and t[j] <= x + tolerance:
            matched += 1
            j += 1
    return matched


def prf(matched: int, n_ref: int, n_test: int) -> dict:
    """Precision, recall and F1 from match counts; all 1 when neither side has an event."""
    if n_ref == 0 and n_test == 0:
        return {"precision": 1.0, "recall": 1.0, "f1": 1.0}
    precision = matched / n_test if n_test else 0.0
    recall = matched / n_ref if n_ref else 0.0
    f1 = 2 * precision * recall / (precision + recall) if precision + recall > 0 else 0.0
    return {"precision": precision, "recall": recall, "f1": f1}


def onset_scores(ref: np.ndarray, test: np.ndarray, *, tolerance: int = ONSET_TOLERANCE_TICKS) -> dict:
    """Onset agreement per actuator, pooled over actuators.

    ref, test : vibration [shape=(n_ref, k)] and [shape=(n_test, k)], 0..1; compared on the common ticks.
    Returns {"precision", "recall", "f1", "matched", "ref_onsets", "test_onsets", "tolerance_ticks",
    "per_actuator": [{"precision", "recall", "f1", "matched", "ref_onsets", "test_onsets"}, ...]}.
    """
    a = np.asarray(ref, dtype=np.float64)
    if a.ndim == 1:
        a = a[:, None]
    b = np.asarray(test, dtype=np.float64)
    if b.ndim == 1:
        b = b[:, None]
    a, b = _pair(a, b, "vibration", tuple(a.shape[1:]))
    oa, ob = onsets(a), onsets(b)
    per, tot = [], [0, 0, 0]
    for col in range(a.shape[1]):
        ra, tb = np.flatnonzero(oa[:, col]), np.flatnonzero(ob[:, col])
        m = match_onsets(ra, tb, tolerance=tolerance)
        per.append({**prf(m, ra.size, tb.size), "matched": m, "ref_onsets": int(ra.size), "test_onsets": int(tb.size)})
        tot[0] += m
        tot[1] += int(ra.size)
        tot[2] += int(tb.size)
    return {**prf(*tot), "matched": tot[0], "ref_onsets": tot[1], "test_onsets": tot[2],
            "tolerance_ticks": int(tolerance), "per_actuator": per}


# -------------------------------------------------------------------------- fans
FAN_TOLERANCE_CELLS = 1


def _near(on: np.ndarray, cells: int) -> np.ndarray:
    """Cells within ``cells`` cells (8-neighbourhood, Chebyshev distance) of an on-cell, per tick.
    on : bool [shape=(n, rows, cols)] -> bool, same shape."""
    out = on.copy()
    rows, cols = on.shape[1:]
    for dy in range(-cells, cells + 1):
        for dx in range(-cells, cells + 1):
            if dy or dx:
                src = on[:, max(0, dy):rows + min(0, dy), max(0, dx):cols + min(0, dx)]
                out[:, max(0, -dy):rows + min(0, -dy), max(0, -dx):cols + min(0, -dx)] |= src
    return out


def _iou_scores(inter: np.ndarray, union: np.ndarray, both: np.ndarray) -> tuple[float, float, float]:
    """(mean per-tick IoU over the ticks where either side blows, pooled IoU, mean IoU where both
    blow), each 1.0 when there is no such tick."""
    active = union > 0
    if not active.any():
        return 1.0, 1.0, 1.0
    iou = float((inter[active] / union[active]).mean())
    pooled = float(inter[active].sum() / union[active].sum())
    where = float((inter[both] / union[both]).mean()) if both.any() else 1.0
    return iou, pooled, where


def fan_iou(ref: np.ndarray, test: np.ndarray, *, on_level: float = 0.0,
            tolerance: int = FAN_TOLERANCE_CELLS) -> dict:
    """IoU of the on-cells of two fan tracks over the ticks where either side has a fan on,
    exact and with a tolerance of ``tolerance`` cells.

    ref, test : fans [shape=(n_ref, 9, 17)] and [shape=(n_test, 9, 17)], 0..1; a cell is on above
    ``on_level``. Returns {"iou" (mean of the per-tick IoU), "iou_pooled" (sum of intersections /
    sum of unions), "ticks" (ticks where either side blows), "ref_ticks_on", "test_ticks_on",
    "ticks_precision" / "ticks_recall" / "ticks_f1" (agreement on which ticks blow at all),
    "ticks_both_on", "iou_both_on" (mean IoU where both blow), and "iou_tolerant",
    "iou_tolerant_pooled", "iou_tolerant_both_on", "tolerance_cells"}; IoUs are 1.0 when nothing blows.
    Tolerant: an on-cell of one side is matched when the other side has an on-cell within
    ``tolerance`` cells (8-neighbourhood); the IoU is the matched share of the union's cells
    (with ``tolerance`` 0 the exact IoU). Why: a person cannot tell which of two neighbouring cells
    of the grid blows on them.
    """
    if isinstance(tolerance, bool) or not isinstance(tolerance, (int, np.integer)) or not 0 <= tolerance <= FAN_COLS:
        raise ParameterError(f"fan tolerance must be a whole number of cells in 0..{FAN_COLS}, got {tolerance!r}")
    a, b = _pair(ref, test, "fans", (FAN_ROWS, FAN_COLS))
    on_a, on_b = a > on_level, b > on_level
    union = (on_a | on_b).reshape(a.shape[0], -1).sum(axis=1)
    inter = (on_a & on_b).reshape(a.shape[0], -1).sum(axis=1)
    matched = (on_a & _near(on_b, int(tolerance))) | (on_b & _near(on_a, int(tolerance)))
    tick_a, tick_b = on_a.reshape(a.shape[0], -1).any(axis=1), on_b.reshape(b.shape[0], -1).any(axis=1)
    both = tick_a & tick_b
    iou, pooled, where = _iou_scores(inter, union, both)
    tol, tol_pooled, tol_where = _iou_scores(matched.reshape(a.shape[0], -1).sum(axis=1), union, both)
    whether = prf(int(both.sum()), int(tick_a.sum()), int(tick_b.sum()))
    return {"iou": iou, "iou_pooled": pooled, "ticks": int((union > 0).sum()),
            "ref_ticks_on": int(tick_a.sum()), "test_ticks_on": int(tick_b.sum()),
            "ticks_precision": whether["precision"], "ticks_recall": whether["recall"], "ticks_f1": whether["f1"],
            "ticks_both_on": int(both.sum()), "iou_both_on": where, "iou_tolerant": tol,
            "iou_tolerant_pooled": tol_pooled, "iou_tolerant_both_on": tol_where, "tolerance_cells": int(tolerance)}


# ------------------------------------------------------------------------ report
def compare_tracks(ref_vibration: np.ndarray, test_vibration: np.ndarray, ref_temperature: np.ndarray,
                   test_temperature: np.ndarray, ref_fans: np.ndarray, test_fans: np.ndarray, *,
                   tolerance: int = ONSET_TOLERANCE_TICKS, on_level: float = 0.0,
                   fan_tolerance: int = FAN_TOLERANCE_CELLS) -> dict:
    """The track metrics (module docstring) from bare arrays.

    vibration [shape=(n, 9)] 0..1, temperature [shape=(n,)] C, fans [shape=(n, 9, 17)] 0..1, per side.
    """
    va, vb = _pair(ref_vibration, test_vibration, "vibration", (N_ACTUATORS,))
    ta, tb = _pair(ref_temperature, test_temperature, "temperature_c")
    per_act = np.abs(va - vb).mean(axis=0) if va.size else np.zeros(N_ACTUATORS)
    fa, fb = _pair(ref_fans, test_fans, "fans", (FAN_ROWS, FAN_COLS))
    return {
        "vibration": {"mae": mae(va, vb), "max_abs": max_abs_error(va, vb),
                      "chair_mae": mae(va.max(axis=1, initial=0.0), vb.max(axis=1, initial=0.0)),
                      "mae_per_actuator": {a: float(v) for a, v in zip(ACTUATOR_IDS, per_act)},
                      "onsets": onset_scores(va, vb, tolerance=tolerance),
                      "chair_onsets": _without_per_actuator(onset_scores(va.max(axis=1, initial=0.0),
                                                                         vb.max(axis=1, initial=0.0),
                                                                         tolerance=tolerance))},
        "temperature": {"mae_c": mae(ta, tb), "max_abs_c": max_abs_error(ta, tb)},
        "fans": {**fan_iou(fa, fb, on_level=on_level, tolerance=fan_tolerance), "mae": mae(fa, fb)},
    }


def _without_per_actuator(scores: dict) -> dict:
    scores.pop("per_actuator", None)
    return scores


def compare_features(ref: dict[str, np.ndarray], test: dict[str, np.ndarray]) -> dict:
    """{name: MAE} for every per-tick curve present in both (common ticks), in ``ref``'s order."""
    out = {}
    for name, values in ref.items():
        if name in test:
            a = np.asarray(values, dtype=np.float64)
            b = np.asarray(test[name], dtype=np.float64)
            if a.ndim == 1 and b.ndim == 1:
                out[name] = mae(a, b)
    return out


def compare_timelines(ref: Any, test: Any, *, tolerance: int = ONSET_TOLERANCE_TICKS,
                      on_level: float = 0.0, fan_tolerance: int = FAN_TOLERANCE_CELLS) -> dict:
    """Every metric between two :class:`autohaptics.timeline.Timeline` s (module docstring).

    Returns {"n_ticks": common_length(...), "same_source": bool | None, "vibration": {...},
    "temperature": {...}, "fans": {...}, "features": {name: mae}, "features_only_in": {"ref": [...],
    "test": [...]}}; ``same_source`` compares the sources' sha256 (None when either lacks one).
    """
    sha_a = (ref.source or {}).get("sha256")
    sha_b = (test.source or {}).get("sha256")
    report = {"n_ticks": common_length(ref.n_ticks, test.n_ticks),
              "same_source": None if not (sha_a and sha_b) else sha_a == sha_b}
    report.update(compare_tracks(ref.vibration, test.vibration, ref.temperature_c, test.temperature_c,
                                 ref.fans, test.fans, tolerance=tolerance, on_level=on_level,
                                 fan_tolerance=fan_tolerance))
    report["features"] = compare_features(ref.features, test.features)
    report["features_only_in"] = {"ref": sorted(set(ref.features) - set(test.features)),
                                  "test": sorted(set(test.features) - set(ref.features))}
    return report


def headline(report: dict) -> dict:
    """The few figures a benchmark table shows, from a :func:`compare_timelines` report."""
    return {
        "vibration_mae": report["vibration"]["mae"],
        "onset_f1": report["vibration"]["onsets"]["f1"],
        "onset_precision": report["vibration"]["onsets"]["precision"],
        "onset_recall": report["vibration"]["onsets"]["recall"],
        "chair_onset_f1": report["vibration"]["chair_onsets"]["f1"],
        "chair_mae": report["vibration"]["chair_mae"],
        "temperature_mae_c": report["temperature"]["mae_c"],
        "fan_iou": report["fans"]["iou"],
        "fan_iou_tolerant": report["fans"]["iou_tolerant"],
        "fan_ticks_f1": report["fans"]["ticks_f1"],
        "fan_iou_both_on": report["fans"]["iou_both_on"],
        "tick_difference": report["n_ticks"]["difference"],
    }


def format_report(report: dict) -> str:
    """A short human-readable text of a :func:`compare_timelines` report."""
    n = report["n_ticks"]
    v, t, f = report["vibration"], report["temperature"], report["fans"]
    o = v["onsets"]
    lines = [
        f"ticks: ref {n['ref']}, test {n['test']}, compared {n['common']} (difference {n['difference']:+d})",
        f"vibration: MAE {v['mae']:.4f}, max {v['max_abs']:.4f}, chair (strongest actuator) MAE "
        f"{v['chair_mae']:.4f}; onsets (+-{o['tolerance_ticks']} tick) "
        f"F1 {o['f1']:.3f}, precision {o['precision']:.3f}, recall {o['recall']:.3f} "
        f"({o['matched']} matched of {o['ref_onsets']} ref / {o['test_onsets']} test)",
        f"chair as a whole: onsets F1 {v['chair_onsets']['f1']:.3f}, precision {v['chair_onsets']['precision']:.3f}, "
        f"recall {v['chair_onsets']['recall']:.3f} ({v['chair_onsets']['matched']} matched of "
        f"{v['chair_onsets']['ref_onsets']} ref / {v['chair_onsets']['test_onsets']} test)",
        f"temperature: MAE {t['mae_c']:.3f} C, max {t['max_abs_c']:.3f} C",
        f"fans: IoU {f['iou']:.3f} (pooled {f['iou_pooled']:.3f}), within {f['tolerance_cells']} cell "
        f"{f['iou_tolerant']:.3f} (pooled {f['iou_tolerant_pooled']:.3f}) over {f['ticks']} ticks "
        f"(ref on {f['ref_ticks_on']}, test on {f['test_ticks_on']}), level MAE {f['mae']:.4f}; "
        f"which ticks blow: F1 {f['ticks_f1']:.3f}; which cells where both blow ({f['ticks_both_on']} ticks): "
        f"IoU {f['iou_both_on']:.3f}",
    ]
    if report["features"]:
        width = max(len(k) for k in report["features"])
        lines.append("features (MAE):")
        lines += [f"  {k.ljust(width)}  {_num(val)}" for k, val in report["features"].items()]
    only = report.get("features_only_in") or {}
    for side in ("ref", "test"):
        if only.get(side):
            lines.append(f"features only in {side}: {', '.join(only[side])}")
    if report.get("same_source") is False:
        lines.append("warning: the two timelines come from different sources (sha256 differs)")
    return "\n".join(lines)


def _num(v: float) -> str:
    if v == 0 or not math.isfinite(v):
        return str(v)
    return f"{v:.4g}"
