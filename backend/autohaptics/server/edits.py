"""Manual edits: validated operations and their composition over a generated timeline.

The editor never changes the generated tracks; it records operations (docs/API.md, "Edit
operations") and the composed timeline is always ``apply_ops(generated, ops[0:cursor])``. So a
regeneration with other thresholds keeps every manual edit.

An operation is a JSON object ``{"op": NAME, ...fields}``. Lanes are ``"A1"``..``"A9"``
(vibration), ``"temperature"`` and ``"fans"`` (the whole 9 x 17 grid); ranges are half-open tick
ranges ``[t0, t1)``. Ranges reaching past the end of the timeline are cut at the end. Values are
clamped to each track's range: vibration and fans 0..1, temperature to the generator's
``[temp_low, temp_high]``; the temperature "neutral" (33 C) is clamped into that range too.

Ramps (``fade_in`` / ``fade_out``) over a range of n ticks multiply tick k (0-based inside the
range) by k / (n - 1) or (n - 1 - k) / (n - 1): the first tick of a fade-in and the last tick of
a fade-out are 0 (temperature: neutral), the opposite ends keep their value. A one-tick fade
gives 0.

An ``import`` op arrives with its document (``timeline``); the service stores the document in a
file and keeps the op as ``{"op": "import", "ref": ID, "name", "n_ticks"}`` (the stored form), so
the edit list stays light. :func:`apply_ops` reads a stored import through ``imports(ref)``.

Everything here is a pure function: Timeline in, new Timeline out; the input is never modified.
"""

from __future__ import annotations

import dataclasses
import json
import math
import re
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from autohaptics.errors import ParameterError
from autohaptics.layout import ACTUATOR_IDS, FAN_COLS, FAN_ROWS, TEMP_NEUTRAL_C
from autohaptics.timebase import fit_length
from autohaptics.timeline import Timeline

VIBRATION_LANES: tuple[str, ...] = ACTUATOR_IDS
LANES: tuple[str, ...] = (*ACTUATOR_IDS, "temperature", "fans")
MAX_TICK = 10**8  # ~115 days of 100 ms ticks: a structural bound, not the timeline's length
MAX_MARKER_ID = 64
MAX_MARKER_LABEL = 200

_REQUIRED: dict[str, tuple[str, ...]] = {
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
}
OPS: tuple[str, ...] = tuple(_REQUIRED)
IMPORT_STORED_FIELDS = ("ref", "name", "n_ticks")  # an import op as stored: its document lives in a file
MARKER_OPS = ("marker_add", "marker_update", "marker_delete")
TRACKS = ("vibration", "temperature_c", "fans")
_REF = re.compile(r"^[0-9a-f]{32}$")
ImportResolver = Callable[[str], Timeline]


# ------------------------------------------------------------------------- public
def validate_op(op: Any) -> dict:
    """Check one operation and return its normalised form (ints for ticks, floats for values).

    Raises ParameterError naming the operation and the field: unknown op or field, a missing
    field, a wrong type, a non-finite number, an empty or reversed range, an unknown lane.
    """
    return _normalise(op)[0]


def apply_ops(generated: Timeline, ops: Sequence[dict], *, strict: bool = False,
              markers: Sequence[dict] = (), imports: ImportResolver | None = None,
              reuse: Mapping[str, np.ndarray] | None = None) -> tuple[Timeline, list[dict]]:
    """Compose ``ops`` in order over a copy of ``generated``, starting from ``markers``.

    Returns (composed timeline, markers sorted by time). ``strict`` (used when an operation is
    submitted) also rejects a range starting past the end of the timeline and marker operations
    naming a marker that does not exist (update/delete) or already exists (add); without it
    (recomposing stored history) such operations are no-ops or replacements, so stored history
    always composes. ``imports`` returns the document of a stored ``import`` op by its ``ref``.

    Tracks no operation changes are shared with ``generated`` (read-only), not copied. ``reuse``
    maps a track (``vibration``, ``temperature_c``, ``fans``) to its composed values from an
    earlier composition with the same :func:`track_keys` over an equal generated track: it is
    taken as it is and the operations' effects on it are skipped.
    """
    reuse = dict(reuse or {})
    skip = frozenset(reuse)
    normalised = [_normalise(raw) for raw in ops]
    written = set().union(*(_tracks_written(op) for op, _ in normalised)) - skip
    tl = _copy_tracks(generated, written)
    for track, values in reuse.items():
        setattr(tl, track, values)
    by_id: dict[str, dict] = {m["id"]: dict(m) for m in markers}
    for index, (op, parsed) in enumerate(normalised):
        try:
            if op["op"] == "import":
                if parsed is None:
                    if imports is None:
                        raise ParameterError(f"stored import {op['ref']} cannot be read here (no import store)")
                    parsed = imports(op["ref"])
                _import_tracks(tl, parsed, skip)
                continue
            op, parsed = _restrict(op, parsed, skip)
            if op is not None:
                _APPLY[op["op"]](tl, by_id, op, parsed, strict)
        except ParameterError as exc:
            where = f"operation {index} ({op['op']})" if len(ops) > 1 else f"op '{op['op']}'"
            raise ParameterError(f"{where}: {exc}") from None
    _check_tracks(tl, set().union(*(tracks_of(op) for op, _ in normalised)) - skip)
    return tl, _sorted_markers(by_id)


def tracks_of(op: dict) -> frozenset[str]:
    """The tracks (``vibration``, ``temperature_c``, ``fans``) a normalised operation changes."""
    if op["op"] == "import":
        return frozenset(TRACKS)
    return frozenset(_tracks_written(op))


def track_keys(ops: Sequence[dict]) -> dict[str, tuple[str, ...]]:
    """Per track, the operations that change it, in order (as canonical JSON): two compositions
    with equal keys over equal generated tracks have equal composed tracks."""
    keys: dict[str, list[str]] = {t: [] for t in TRACKS}
    for raw in ops:
        if isinstance(raw, dict) and raw.get("op") in MARKER_OPS:
            continue
        op, _ = _normalise(raw) if not (isinstance(raw, dict) and raw.get("op") == "import") else (raw, None)
        text = json.dumps(op, sort_keys=True, separators=(",", ":"))
        for track in tracks_of(op):
            keys[track].append(text)
    return {t: tuple(v) for t, v in keys.items()}


def _track_of_lane(lane: str) -> str:
    return "temperature_c" if lane == "temperature" else "fans" if lane == "fans" else "vibration"


def _tracks_written(op: dict) -> set[str]:
    """The tracks an operation writes into in place (an import replaces them by new arrays)."""
    if op["op"] == "import":
        return set()
    lanes = list(op.get("lanes", ())) + ([op["lane"]] if "lane" in op else [])
    if op["op"] == "paste":
        lanes += list(op["values"])
    if op["op"] == "temp_points":
        lanes.append("temperature")
    return {_track_of_lane(lane) for lane in lanes}


def _restrict(op: dict, parsed: Any, skip: frozenset[str]) -> tuple[dict | None, Any]:
    """``op`` without its effects on the tracks in ``skip`` (None when nothing is left)."""
    if not skip or op["op"] in MARKER_OPS:
        return op, parsed
    if "lanes" in op:
        lanes = [lane for lane in op["lanes"] if _track_of_lane(lane) not in skip]
        return ({**op, "lanes": lanes}, parsed) if lanes else (None, None)
    if op["op"] == "pencil":
        return (op, parsed) if _track_of_lane(op["lane"]) not in skip else (None, None)
    if op["op"] == "temp_points":
        return (op, parsed) if "temperature_c" not in skip else (None, None)
    if op["op"] == "paste":
        kept = {lane: v for lane, v in parsed.items() if _track_of_lane(lane) not in skip}
        return ({**op, "values": {lane: op["values"][lane] for lane in kept}}, kept) if kept else (None, None)
    return op, parsed


def _copy_tracks(generated: Timeline, tracks: set[str]) -> Timeline:
    """A copy of ``generated`` whose arrays are copied only for ``tracks``; the others (and the
    features) are shared, read-only, so composing an edit of one lane of a long film does not copy
    the fans' 44 MB."""
    if tracks >= set(TRACKS):
        return generated.copy()
    shell = dataclasses.replace(generated, vibration=generated.vibration[:0], temperature_c=generated.temperature_c[:0],
                                fans=generated.fans[:0], features={}).copy()  # the metadata, deep-copied
    for track in TRACKS:
        values = getattr(generated, track)
        setattr(shell, track, values.copy() if track in tracks else values)
    shell.features = dict(generated.features)
    return shell


def _check_tracks(tl: Timeline, tracks: set[str]) -> None:
    """The composed tracks in ``tracks`` are float32, finite and in range (the others are the
    generated, already checked)."""
    lo, hi = tl.temp_range
    for track in tracks:
        values = np.asarray(getattr(tl, track), dtype=np.float32)
        low, high = (lo, hi) if track == "temperature_c" else (0.0, 1.0)
        if values.size and not (np.isfinite(values).all() and low <= float(values.min())
                                and float(values.max()) <= high):
            raise ParameterError(f"the composed track '{track}' left its range [{low:g}, {high:g}]")
        setattr(tl, track, values)


def _import_tracks(tl: Timeline, parsed: Timeline, skip: frozenset[str]) -> None:
    n = tl.n_ticks
    if "vibration" not in skip:
        tl.vibration = fit_length(parsed.vibration, n, fill=0.0).astype(np.float32)
    if "temperature_c" not in skip:
        temp = fit_length(parsed.temperature_c.astype(np.float64), n, fill=_neutral(tl))
        tl.temperature_c = _clamp(tl, "temperature", temp).astype(np.float32)
    if "fans" not in skip:
        tl.fans = fit_length(parsed.fans, n, fill=0.0).astype(np.float32)


def fold_markers(ops: Sequence[dict], duration_s: float) -> list[dict]:
    """The markers after ``ops`` on a timeline of ``duration_s`` seconds, exactly as
    :func:`apply_ops` composes them, without touching any track (other ops are skipped)."""
    span = _Duration(float(duration_s))
    by_id: dict[str, dict] = {}
    for raw in ops:
        if isinstance(raw, dict) and raw.get("op") in MARKER_OPS:
            op, parsed = _normalise(raw)
            _APPLY[op["op"]](span, by_id, op, parsed, False)
    return _sorted_markers(by_id)


def is_stored_import(op: dict) -> bool:
    """An ``import`` op in its stored form (its document in a file)."""
    return op.get("op") == "import" and "ref" in op


@dataclass(frozen=True)
class _Duration:
    """What the marker operations read of a timeline."""

    duration_s: float


def _sorted_markers(by_id: dict[str, dict]) -> list[dict]:
    return sorted(by_id.values(), key=lambda m: (m["t_s"], m["id"]))


# -------------------------------------------------------------------- validation
def _normalise(op: Any) -> tuple[dict, Any]:
    if not isinstance(op, dict):
        raise ParameterError(f"an operation must be a JSON object, got {type(op).__name__}")
    name = op.get("op")
    if name not in _REQUIRED:
        raise ParameterError(f"field 'op' must be one of {', '.join(OPS)}; got {name!r}")
    if name == "import" and "ref" in op:
        return _stored_import(op), None
    required = _REQUIRED[name]
    unknown = sorted(set(op) - set(required) - {"op"})
    if unknown:
        raise ParameterError(f"op '{name}': unknown field '{unknown[0]}' (fields: {', '.join(required)})")
    missing = [f for f in required if f not in op]
    if missing:
        raise ParameterError(f"op '{name}': field '{missing[0]}' is required")
    out: dict[str, Any] = {"op": name}
    parsed: Any = None
    if "lanes" in required:
        out["lanes"] = _lanes(name, op["lanes"])
    if "lane" in required:
        out["lane"] = _lane(name, "lane", op["lane"])
    if "t0" in required:
        out["t0"] = _tick(name, "t0", op["t0"])
    if "t1" in required:
        out["t1"] = _tick(name, "t1", op["t1"])
        if out["t1"] <= out["t0"]:
            raise ParameterError(f"op '{name}': field 't1' ({out['t1']}) must be greater than t0 ({out['t0']})")
    if name == "set":
        out["value"] = _number(name, "value", op["value"])
    elif name == "scale":
        out["factor"] = _number(name, "factor", op["factor"])
        if out["factor"] < 0:
            raise ParameterError(f"op 'scale': field 'factor' must be >= 0, got {out['factor']}")
    elif name == "paste":
        out["values"], parsed = _paste_values(op["values"])
    elif name == "pencil":
        arr = _array(name, "values", op["values"], ndim=1)
        out["values"] = arr.tolist()
        parsed = arr
    elif name == "temp_points":
        out["points"], parsed = _points(op["points"])
    elif name == "marker_add":
        out["marker"] = _marker(name, op["marker"], full=True)
    elif name == "marker_update":
        out["marker"] = _marker(name, op["marker"], full=False)
    elif name == "marker_delete":
        out["id"] = _marker_id(name, "id", op["id"])
    elif name == "import":
        doc = op["timeline"]
        if not isinstance(doc, dict):
            raise ParameterError("op 'import': field 'timeline' must be a timeline JSON object")
        try:
            parsed = Timeline.from_dict(doc)
        except ParameterError as exc:
            raise ParameterError(f"op 'import': field 'timeline': {exc}") from None
        out["timeline"] = doc
    return out, parsed


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


def _lane(name: str, field: str, value: Any) -> str:
    if value not in LANES:
        raise ParameterError(f"op '{name}': field '{field}' has unknown lane {value!r}; "
                             f"expected one of {', '.join(LANES)}")
    return value


def _lanes(name: str, value: Any) -> list[str]:
    if not isinstance(value, list) or not value:
        raise ParameterError(f"op '{name}': field 'lanes' must be a non-empty list of lane ids")
    lanes = [_lane(name, "lanes", v) for v in value]
    return list(dict.fromkeys(lanes))  # duplicates would apply twice (scale, fade)


def _is_number(value: Any) -> bool:
    return isinstance(value, (int, float)) and not isinstance(value, bool)


def _number(name: str, field: str, value: Any) -> float:
    if not _is_number(value) or not math.isfinite(value):
        raise ParameterError(f"op '{name}': field '{field}' must be a finite number, got {value!r}")
    return float(value)


def _tick(name: str, field: str, value: Any) -> int:
    if not _is_number(value) or not math.isfinite(value) or float(value) != int(value):
        raise ParameterError(f"op '{name}': field '{field}' must be an integer tick index, got {value!r}")
    tick = int(value)
    if not 0 <= tick <= MAX_TICK:
        raise ParameterError(f"op '{name}': field '{field}' must lie in 0..{MAX_TICK}, got {tick}")
    return tick


def _array(name: str, field: str, value: Any, *, ndim: int, inner: tuple[int, ...] = ()) -> np.ndarray:
    if not isinstance(value, list) or not value:
        raise ParameterError(f"op '{name}': field '{field}' must be a non-empty list")
    try:
        arr = np.asarray(value, dtype=np.float64)
    except (TypeError, ValueError):
        raise ParameterError(f"op '{name}': field '{field}' must be a rectangular array of numbers") from None
    if arr.ndim != ndim or arr.shape[1:] != inner:
        want = "[n]" + "".join(f"[{d}]" for d in inner)
        raise ParameterError(f"op '{name}': field '{field}' has shape {list(arr.shape)}, expected {want}")
    if not np.isfinite(arr).all():
        raise ParameterError(f"op '{name}': field '{field}' holds a non-finite value")
    if arr.shape[0] > MAX_TICK:
        raise ParameterError(f"op '{name}': field '{field}' is longer than {MAX_TICK} ticks")
    return arr


def _paste_values(value: Any) -> tuple[dict, dict[str, np.ndarray]]:
    if not isinstance(value, dict) or not value:
        raise ParameterError("op 'paste': field 'values' must be a non-empty object {lane: per-tick values}")
    out, parsed = {}, {}
    for lane, vals in value.items():
        _lane("paste", "values", lane)
        if lane == "fans":
            arr = _array("paste", "values.fans", vals, ndim=3, inner=(FAN_ROWS, FAN_COLS))
        else:
            arr = _array("paste", f"values.{lane}", vals, ndim=1)
        out[lane] = arr.tolist()
        parsed[lane] = arr
    return out, parsed


def _points(value: Any) -> tuple[list, tuple[np.ndarray, np.ndarray]]:
    arr = _array("temp_points", "points", value, ndim=2, inner=(2,))
    order = np.argsort(arr[:, 0], kind="stable")
    arr = arr[order]
    return arr.tolist(), (arr[:, 0], arr[:, 1])


def _marker_id(name: str, field: str, value: Any) -> str:
    if not isinstance(value, str) or not value or len(value) > MAX_MARKER_ID:
        raise ParameterError(f"op '{name}': field '{field}' must be a string of 1..{MAX_MARKER_ID} characters")
    return value


def _marker(name: str, value: Any, *, full: bool) -> dict:
    if not isinstance(value, dict):
        raise ParameterError(f"op '{name}': field 'marker' must be an object {{id, t_s, label}}")
    unknown = sorted(set(value) - {"id", "t_s", "label"})
    if unknown:
        raise ParameterError(f"op '{name}': field 'marker.{unknown[0]}' is unknown (fields: id, t_s, label)")
    out = {"id": _marker_id(name, "marker.id", value.get("id"))}
    if "t_s" in value or full:
        if "t_s" not in value:
            raise ParameterError(f"op '{name}': field 'marker.t_s' is required")
        t = _number(name, "marker.t_s", value["t_s"])
        if t < 0:
            raise ParameterError(f"op '{name}': field 'marker.t_s' must be >= 0, got {t}")
        out["t_s"] = t
    if "label" in value or full:
        label = value.get("label", "")
        if not isinstance(label, str) or len(label) > MAX_MARKER_LABEL:
            raise ParameterError(f"op '{name}': field 'marker.label' must be a string of at most "
                                 f"{MAX_MARKER_LABEL} characters")
        out["label"] = label
    if not full and len(out) == 1:
        raise ParameterError(f"op '{name}': give 'marker.t_s' or 'marker.label' to change")
    return out


# ------------------------------------------------------------------- application
def _neutral(tl: Timeline) -> float:
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


def _clamp(tl: Timeline, lane: str, values: np.ndarray) -> np.ndarray:
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
        n0 = _neutral(tl)
        view[...] = _clamp(tl, lane, n0 + (view - n0) * r)
    else:
        view[...] = _clamp(tl, lane, view * r)


def _op_set(tl, markers, op, parsed, strict) -> None:
    a, b = _span(tl, op["t0"], op["t1"], strict)
    for lane in op["lanes"]:
        _lane_view(tl, lane, a, b)[...] = _clamp(tl, lane, np.float64(op["value"]))


def _op_scale(tl, markers, op, parsed, strict) -> None:
    a, b = _span(tl, op["t0"], op["t1"], strict)
    for lane in op["lanes"]:
        _apply_ramp(tl, lane, a, b, np.full(b - a, op["factor"]))


def _op_clear(tl, markers, op, parsed, strict) -> None:
    a, b = _span(tl, op["t0"], op["t1"], strict)
    for lane in op["lanes"]:
        _lane_view(tl, lane, a, b)[...] = _neutral(tl) if lane == "temperature" else 0.0


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
        view[...] = _clamp(tl, lane, values[: b - a])[:, None, None]
    else:
        view[...] = _clamp(tl, lane, values[: b - a])


def _op_paste(tl, markers, op, parsed, strict) -> None:
    for lane, values in parsed.items():
        _write(tl, lane, op["t0"], values, strict)


def _op_pencil(tl, markers, op, parsed, strict) -> None:
    _write(tl, op["lane"], op["t0"], parsed, strict)


def _op_temp_points(tl, markers, op, parsed, strict) -> None:
    a, b = _span(tl, op["t0"], op["t1"], strict)
    px, py = parsed
    ticks = np.arange(a, b, dtype=np.float64)
    tl.temperature_c[a:b] = _clamp(tl, "temperature", np.interp(ticks, px, py))


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


_APPLY: dict[str, Callable] = {
    "set": _op_set,
    "scale": _op_scale,
    "clear": _op_clear,
    "fade_in": _fade("in"),
    "fade_out": _fade("out"),
    "paste": _op_paste,
    "pencil": _op_pencil,
    "temp_points": _op_temp_points,
    "marker_add": _op_marker_add,
    "marker_update": _op_marker_update,
    "marker_delete": _op_marker_delete,
}
