"""How much of each film's edits a style explains: the plain derive and the styled one, each
compared with the designer's edited timeline (the metrics of ``autohaptics compare``), and the
share of the plain derive's distance the style removes (vibration MAE + temperature MAE / 5 C + fan
MAE, as ``autohaptics bench style`` sums them). Pure functions over analyses and timelines.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

from autohaptics.metrics import compare_tracks
from autohaptics.params import GenerateParams
from autohaptics.pipeline.cache import Analysis
from autohaptics.pipeline.derive import derive
from autohaptics.timeline import Timeline

TEMPERATURE_WEIGHT_C = 5.0  # a temperature error of this many degrees weighs as a full level's
METRICS = ("vibration_mae", "onset_f1", "temperature_mae_c", "fan_mae", "fan_iou_tolerant")


def explain(pairs: Sequence[tuple[Analysis, Timeline]], params: GenerateParams, style) -> list[dict]:
    """One entry per (analysis, edited timeline) pair: ``{plain: {metric: value}, styled: {...},
    explained}`` with the metrics of :data:`METRICS` against the edited timeline and ``explained``
    the share (at most 1, negative when the style moves away) of the plain derive's distance the
    styled derive removes; None when the film was not edited (nothing to explain)."""
    out = []
    for analysis, edited in pairs:
        plain = _errors(derive(analysis, params), edited)
        styled = _errors(derive(analysis, params, style=style), edited)
        before, after = _distance(plain), _distance(styled)
        explained = None if before <= 0.0 else round(1.0 - after / before, 4)
        out.append({"plain": plain, "styled": styled, "explained": explained})
    return out


def _errors(test: Timeline, ref: Timeline) -> dict:
    r = compare_tracks(ref.vibration, test.vibration, ref.temperature_c, test.temperature_c, ref.fans, test.fans)
    values = {"vibration_mae": r["vibration"]["mae"], "onset_f1": r["vibration"]["onsets"]["f1"],
              "temperature_mae_c": r["temperature"]["mae_c"], "fan_mae": r["fans"]["mae"],
              "fan_iou_tolerant": r["fans"]["iou_tolerant"]}
    return {k: round(float(v), 4) if math.isfinite(v) else None for k, v in values.items()}


def _distance(errors: dict) -> float:
    return sum(errors[k] or 0.0 for k in ("vibration_mae", "fan_mae")) + (errors["temperature_mae_c"] or 0.0) / TEMPERATURE_WEIGHT_C
