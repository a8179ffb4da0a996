"""Edit operations one by one: each checked and normalised at the edge (:func:`normalise`), and
applied in place to a copy of the composed tracks (:data:`APPLY`). :mod:`autohaptics.timeline.edits`
composes them; docs/API.md ("Edit operations") lists every operation and its fields.
"""

from __future__ import annotations

import re
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np

from autohaptics.errors import ParameterError
from autohaptics.layout import ACTUATOR_IDS, FAN_COLS, FAN_ROWS, TEMP_NEUTRAL_C
from autohaptics.timeline import op_fields as fields
from autohaptics.timeline.model import Timeline



REQUIRED: dict[str, tuple[str, ...]] = {
    "set": ("lanes", "t0", "t1", "value"),
    "scale": ("lanes", "t0", "t1", "factor"),
    "clear": ("lanes", "t0", "t1"),
    "fade_in": ("lanes", "t0", "t1"),
    "fade_out": ("lanes", "t0", "t1"),
    "paste": ("t0", "values"),
    "pencil": ("lane", "t0", "values"),
    "temp_points": ("t0", "t1", "points"),
    "marker_add": ("marker",),
    "marker_update": ("marker",),
    "marker_delete": ("id",),
    "import": ("timeline",),
    "params": ("from", "to"),
    "shot_split": ("t",),
    "shot_merge": ("shots",),
    "group": ("ops",),
}
OPTIONAL: dict[str, tuple[str, ...]] = {name: ("cells",) for name in ("set", "scale", "clear", "fade_in", "fade_out")}
OPTIONAL["paste"] = ("t1",)
GROUP_OPS = ("set", "scale", "clear", "fade_in", "fade_out", "paste", "pencil", "temp_points")  # what a group holds
MAX_GROUP = 10_000  # sub-operations in one group
OPS: tuple[str, ...] = tuple(REQUIRED)
IMPORT_STORED_FIELDS = ("ref", "name", "n_ticks")  # an import op as stored: its document lives in a file
MARKER_OPS = ("marker_add", "marker_update", "marker_delete")
PARAMS_FIELDS = ("preset", "mode", "thresholds", "overrides")  # a stored parameter document
TRACKS = ("vibration", "temperature_c", "fans")
_REF = re.compile(r"^[0-9a-f]{32}$")


def track_of_lane(lane: str) -> str:
    """The track a lane edits: ``vibration`` (A1..A9), ``temperature_c`` or ``fans``."""
    return "temperature_c" if lane == "temperature" else "fans" if lane == "fans" else "vibration"


@dataclass(frozen=True)
class Duration:
    """What the marker operations read of a timeline."""

    duration_s: float


def sorted_markers(by_id: dict[str, dict]) -> list[dict]:
    """Markers by time, then id."""
    return sorted(by_id.values(), key=lambda m: (m["t_s"], m["id"]))


# -------------------------------------------------------------------- validation
def normalise(op: Any) -> tuple[dict, Any]:
    if not isinstance(op, dict):
        raise ParameterError(f"an operation must be a JSON object, got {type(op).__name__}")
    name = op.get("op")
    if not isinstance(name, str) or name not in REQUIRED:
        raise ParameterError(f"field 'op' must be one of {', '.join(OPS)}; got {name!r}")
    if name == "import" and "ref" in op:
        return _stored_import(op), None
    required, optional = REQUIRED[name], OPTIONAL.get(name, ())
    unknown = sorted(set(op) - set(required) - set(optional) - {"op"})
    if unknown:
        raise ParameterError(f"op '{name}': unknown field '{unknown[0]}' (fields: {', '.join(required + optional)})")
    missing = [f for f in required if f not in op]
    if missing:
        raise ParameterError(f"op '{name}': field '{missing[0]}' is required")
    out: dict[str, Any] = {"op": name}
    parsed: Any = None
    if "lanes" in required:
        out["lanes"] = fields.lanes(name, op["lanes"])
    if "lane" in required:
        out["lane"] = fields.lane(name, "lane", op["lane"])
    if "t0" in required:
        out["t0"] = fields.tick(name, "t0", op["t0"])
    if "t1" in required:
        out["t1"] = fields.tick(name, "t1", op["t1"])
        if out["t1"] <= out["t0"]:
            raise ParameterError(f"op '{name}': field 't1' ({out['t1']}) must be greater than t0 ({out['t0']})")
    if "cells" in op:
        out["cells"] = fields.cells(name, op["cells"], out["lanes"])
    if name == "set":
        out["value"] = fields.number(name, "value", op["value"])
    elif name == "scale":
        out["factor"] = fields.number(name, "factor", op["factor"])
        if out["factor"] < 0:
            raise ParameterError(f"op 'scale': field 'factor' must be >= 0, got {out['factor']}")
    elif name == "paste":
        out["values"], parsed = fields.paste_values(op["values"])
        if "t1" in op:
            out["t1"] = fields.tick(name, "t1", op["t1"])
            if out["t1"] <= out["t0"]:
                raise ParameterError(f"op 'paste': field 't1' ({out['t1']}) must be greater than t0 ({out['t0']})")
    elif name == "pencil":
        arr = fields.array(name, "values", op["values"], ndim=1)
        out["values"] = arr.tolist()
        parsed = arr
    elif name == "temp_points":
        out["points"], parsed = fields.points(op["points"])
    elif name == "marker_add":
        out["marker"] = fields.marker(name, op["marker"], full=True)
    elif name == "marker_update":
        out["marker"] = fields.marker(name, op["marker"], full=False)
    elif name == "marker_delete":
        out["id"] = fields.marker_id(name, "id", op["id"])
    elif name == "import":
        doc = op["timeline"]
        if not isinstance(doc, dict):
            raise ParameterError("op 'import': field 'timeline' must be a timeline JSON object")
        try:
            parsed = Timeline.from_dict(doc)
        except ParameterError as exc:
            raise ParameterError(f"op 'import': field 'timeline': {exc}") from None
        out["timeline"] = doc
    elif name == "params":
        out["from"], out["to"] = _params_doc(op["from"], "from"), _params_doc(op["to"], "to")
    elif name == "shot_split":
        out["t"] = fields.tick(name, "t", op["t"])
    elif name == "shot_merge":
        ids = op["shots"]
        if not isinstance(ids, list) or len(ids) != 2:
            raise ParameterError("op 'shot_merge': field 'shots' must be a list of two shot ids")
        out["shots"] = sorted(fields.tick(name, "shots", s) for s in ids)
        if out["shots"][0] == out["shots"][1]:
            raise ParameterError("op 'shot_merge': field 'shots' must name two different shots")
    elif name == "group":
        out["ops"], parsed = _group(op["ops"])
    return out, parsed


def _group(ops: Any) -> tuple[list[dict], list[tuple[dict, Any]]]:
    """A group's sub-operations, each normalised; a bad one is named by its index (``ops[i]``)."""
    if not isinstance(ops, list) or not 1 <= len(ops) <= MAX_GROUP:
        raise ParameterError(f"op 'group': field 'ops' must be a list of 1..{MAX_GROUP} operations")
    subs = []
    for i, sub in enumerate(ops):
        name = sub.get("op") if isinstance(sub, dict) else None
        if name not in GROUP_OPS:
            raise ParameterError(f"op 'group': ops[{i}] must be one of {', '.join(GROUP_OPS)}; got {fields.brief(name)}")
        try:
            subs.append(normalise(sub))
        except ParameterError as exc:
            why = str(exc).removeprefix(f"op '{name}': ")
            raise ParameterError(f"op 'group': ops[{i}] ({name}): {why}") from None
    return [op for op, _ in subs], subs


def _params_doc(value: Any, field: str) -> dict:
    """A stored parameter document ``{preset, mode, thresholds, overrides}`` and optionally ``style``
    (a learned style: ``{id, name, document}``); its values are checked where it is applied, by
    :func:`autohaptics.params.resolve_doc` and the style's own check."""
    if not isinstance(value, dict) or sorted(set(value) - {"style"}) != sorted(PARAMS_FIELDS):
        raise ParameterError(f"op 'params': field '{field}' must be an object with exactly the fields "
                             f"{', '.join(PARAMS_FIELDS)} (and optionally style)")
    if not isinstance(value["thresholds"], dict) or not isinstance(value["overrides"], dict):
        raise ParameterError(f"op 'params': field '{field}': 'thresholds' and 'overrides' must be objects")
    style = value.get("style")
    if "style" in value and (not isinstance(style, dict) or sorted(style) != ["document", "id", "name"]):
        raise ParameterError(f"op 'params': field '{field}.style' must be an object with id, name and document")
    return {k: value[k] for k in (*PARAMS_FIELDS, *(("style",) if "style" in value else ()))}


def _stored_import(op: dict) -> dict:
    unknown = sorted(set(op) - set(IMPORT_STORED_FIELDS) - {"op"})
    if unknown:
        raise ParameterError(f"op 'import': unknown field '{unknown[0]}' (a stored import has "
                             f"{', '.join(IMPORT_STORED_FIELDS)})")
    ref, name, n = op.get("ref"), op.get("name", ""), op.get("n_ticks")
    if not isinstance(ref, str) or not _REF.match(ref):
        raise ParameterError(f"op 'import': field 'ref' must be a stored import id, got {ref!r}")
    if not isinstance(name, str):
        raise ParameterError(f"op 'import': field 'name' must be a string, got {name!r}")
    if not isinstance(n, int) or isinstance(n, bool) or n < 1:
        raise ParameterError(f"op 'import': field 'n_ticks' must be a positive integer, got {n!r}")
    return {"op": "import", "ref": ref, "name": name, "n_ticks": n}


# ------------------------------------------------------------------- application
def neutral(tl: Timeline) -> float:
    lo, hi = tl.temp_range
    return float(min(max(TEMP_NEUTRAL_C, lo), hi))


def _span(tl: Timeline, t0: int, t1: int, strict: bool) -> tuple[int, int]:
    """The part of [t0, t1) inside the timeline (possibly empty)."""
    if strict and t0 >= tl.n_ticks:
        raise ParameterError(f"field 't0' ({t0}) lies past the end of the timeline ({tl.n_ticks} ticks)")
    return min(t0, tl.n_ticks), min(t1, tl.n_ticks)


def _lane_view(tl: Timeline, lane: str, a: int, b: int) -> np.ndarray:
    """A writable view of one lane over ticks [a, b): (m,) vibration/temperature, (m, 9, 17) fans."""
    if lane == "temperature":
        return tl.temperature_c[a:b]
    if lane == "fans":
        return tl.fans[a:b]
    return tl.vibration[a:b, ACTUATOR_IDS.index(lane)]


def lane_values(tl: Timeline, lanes: list[str], t0: int, t1: int) -> dict[str, list]:
    """Per-tick values of lanes over [t0, t1) at full precision, in the shape ``paste`` takes (what
    the editor's Copy holds): vibration 0..1 and temperature C as (m,), fans as (m, 9, 17)."""
    for lane in lanes:
        fields.lane("copy", "lanes", lane)
    if not 0 <= t0 < t1 <= tl.n_ticks:
        raise ParameterError(f"the range must satisfy 0 <= t0 < t1 <= {tl.n_ticks} ticks, got {t0}..{t1}")
    return {lane: _lane_view(tl, lane, t0, t1).tolist() for lane in dict.fromkeys(lanes)}


def clamp(tl: Timeline, lane: str, values: np.ndarray) -> np.ndarray:
    if lane == "temperature":
        lo, hi = tl.temp_range
        return np.clip(values, lo, hi)
    return np.clip(values, 0.0, 1.0)


def _broadcast(view: np.ndarray, factors: np.ndarray) -> np.ndarray:
    """Per-tick factors shaped to multiply a lane view ((m,) or (m, 9, 17))."""
    return factors.reshape((-1,) + (1,) * (view.ndim - 1))


def _apply_ramp(tl: Timeline, lane: str, a: int, b: int, ramp: np.ndarray) -> None:
    view = _lane_view(tl, lane, a, b)
    r = _broadcast(view, ramp)
    if lane == "temperature":
        n0 = neutral(tl)
        view[...] = clamp(tl, lane, n0 + (view - n0) * r)
    else:
        view[...] = clamp(tl, lane, view * r)


def _op_set(tl, markers, op, parsed, strict) -> None:
    a, b = _span(tl, op["t0"], op["t1"], strict)
    for lane in op["lanes"]:
        _lane_view(tl, lane, a, b)[...] = clamp(tl, lane, np.float64(op["value"]))


def _op_scale(tl, markers, op, parsed, strict) -> None:
    a, b = _span(tl, op["t0"], op["t1"], strict)
    for lane in op["lanes"]:
        _apply_ramp(tl, lane, a, b, np.full(b - a, op["factor"]))


def _op_clear(tl, markers, op, parsed, strict) -> None:
    a, b = _span(tl, op["t0"], op["t1"], strict)
    for lane in op["lanes"]:
        _lane_view(tl, lane, a, b)[...] = neutral(tl) if lane == "temperature" else 0.0


def _fade(kind: str) -> Callable:
    def apply(tl, markers, op, parsed, strict) -> None:
        t0, t1 = op["t0"], op["t1"]
        a, b = _span(tl, t0, t1, strict)
        n = t1 - t0
        k = np.arange(a - t0, b - t0, dtype=np.float64)
        ramp = (k if kind == "in" else (n - 1 - k)) / (n - 1) if n > 1 else np.zeros(b - a)
        for lane in op["lanes"]:
            _apply_ramp(tl, lane, a, b, ramp)
    return apply


def _write(tl: Timeline, lane: str, t0: int, values: np.ndarray, strict: bool) -> None:
    a, b = _span(tl, t0, t0 + values.shape[0], strict)
    view = _lane_view(tl, lane, a, b)
    if lane == "fans" and values.ndim == 1:  # one level for every fan
        view[...] = clamp(tl, lane, values[: b - a])[:, None, None]
    else:
        view[...] = clamp(tl, lane, values[: b - a])


def fitted(values: np.ndarray, length: int, count: int | None = None) -> np.ndarray:
    """``values`` (m ticks along axis 0) fitted to ``length`` ticks: target tick k is the mean of
    the source over ``[k m / length, (k + 1) m / length)``, each source tick held over its own
    tick (area resampling: the mean level is kept, values stay within the source's range, a peak
    shorter than the stretch factor is spread). Only the first ``count`` ticks are made."""
    m = values.shape[0]
    count = length if count is None else min(count, length)
    if m == length:
        return values[:count]
    src = np.asarray(values, np.float64)
    total = np.concatenate([np.zeros((1,) + src.shape[1:]), np.cumsum(src, axis=0)])
    edges = np.arange(count + 1, dtype=np.float64) * (m / length)
    i = np.minimum(np.floor(edges).astype(np.int64), m - 1)
    frac = (edges - i).reshape((-1,) + (1,) * (src.ndim - 1))
    area = total[i] + frac * src[i]  # the integral of the held source up to each edge
    return (area[1:] - area[:-1]) / (m / length)


def _op_paste(tl, markers, op, parsed, strict) -> None:
    for lane, values in parsed.items():
        if "t1" in op:
            values = fitted(values, op["t1"] - op["t0"], max(0, tl.n_ticks - op["t0"]))
        _write(tl, lane, op["t0"], values, strict)


def _op_pencil(tl, markers, op, parsed, strict) -> None:
    _write(tl, op["lane"], op["t0"], parsed, strict)


def _op_temp_points(tl, markers, op, parsed, strict) -> None:
    a, b = _span(tl, op["t0"], op["t1"], strict)
    px, py = parsed
    ticks = np.arange(a, b, dtype=np.float64)
    tl.temperature_c[a:b] = clamp(tl, "temperature", np.interp(ticks, px, py))


def _op_marker_add(tl, markers, op, parsed, strict) -> None:
    m = dict(op["marker"])
    if strict and m["id"] in markers:
        raise ParameterError(f"a marker with id {m['id']!r} already exists")
    m["t_s"] = min(m["t_s"], tl.duration_s)
    markers[m["id"]] = m


def _op_marker_update(tl, markers, op, parsed, strict) -> None:
    change = op["marker"]
    if change["id"] not in markers:
        if strict:
            raise ParameterError(f"no marker with id {change['id']!r}")
        return
    m = markers[change["id"]]
    if "t_s" in change:
        m["t_s"] = min(change["t_s"], tl.duration_s)
    if "label" in change:
        m["label"] = change["label"]


def _op_marker_delete(tl, markers, op, parsed, strict) -> None:
    if op["id"] not in markers:
        if strict:
            raise ParameterError(f"no marker with id {op['id']!r}")
        return
    del markers[op["id"]]


def _op_params(tl, markers, op, parsed, strict) -> None:
    """A parameter change changes the generated layer (the service re-derives it), no composed track."""


def _op_shots(tl, markers, op, parsed, strict) -> None:
    """A shot boundary operation changes the shot list (``autohaptics.shots.model``), no track."""


def _op_group(tl, markers, op, parsed, strict) -> None:
    """The sub-operations in order; one that fails is named by its index."""
    for i, (sub, sub_parsed) in enumerate(parsed):
        try:
            APPLY[sub["op"]](tl, markers, sub, sub_parsed, strict)
        except ParameterError as exc:
            raise ParameterError(f"ops[{i}] ({sub['op']}): {exc}") from None


def _in_cells(apply: Callable) -> Callable:
    """A range op that, given ``cells``, changes only those fans (the others keep their values)."""
    def region(tl, markers, op, parsed, strict) -> None:
        if "cells" not in op:
            apply(tl, markers, op, parsed, strict)
            return
        a, b = _span(tl, op["t0"], op["t1"], strict)
        keep = np.ones((FAN_ROWS, FAN_COLS), dtype=bool)
        for r, c in op["cells"]:
            keep[r, c] = False
        before = tl.fans[a:b][:, keep].copy()
        apply(tl, markers, op, parsed, strict)
        tl.fans[a:b, keep] = before
    return region


APPLY: dict[str, Callable] = {
    "set": _in_cells(_op_set),
    "scale": _in_cells(_op_scale),
    "clear": _in_cells(_op_clear),
    "fade_in": _in_cells(_fade("in")),
    "fade_out": _in_cells(_fade("out")),
    "paste": _op_paste,
    "pencil": _op_pencil,
    "temp_points": _op_temp_points,
    "marker_add": _op_marker_add,
    "marker_update": _op_marker_update,
    "marker_delete": _op_marker_delete,
    "params": _op_params,
    "shot_split": _op_shots,
    "shot_merge": _op_shots,
    "group": _op_group,
}
