"""The fields of an edit operation, each checked at the edge: lanes, numbers, tick indices, arrays,
fan cells and markers; every failure one ParameterError naming the operation and the field."""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from autohaptics.errors import ParameterError
from autohaptics.layout import ACTUATOR_IDS, FAN_COLS, FAN_ROWS

VIBRATION_LANES: tuple[str, ...] = ACTUATOR_IDS
LANES: tuple[str, ...] = (*ACTUATOR_IDS, "temperature", "fans")
MAX_TICK = 10**8  # ~115 days of 100 ms ticks: a structural bound, not the timeline's length
MAX_MARKER_ID = 64
MAX_MARKER_LABEL = 200


def lane(name: str, field: str, value: Any) -> str:
    if value not in LANES:
        raise ParameterError(f"op '{name}': field '{field}' has unknown lane {value!r}; "
                             f"expected one of {', '.join(LANES)}")
    return value


def lanes(name: str, value: Any) -> list[str]:
    if not isinstance(value, list) or not value:
        raise ParameterError(f"op '{name}': field 'lanes' must be a non-empty list of lane ids")
    lanes = [lane(name, "lanes", v) for v in value]
    return list(dict.fromkeys(lanes))  # duplicates would apply twice (scale, fade)


def is_number(value: Any) -> bool:
    return isinstance(value, (int, float)) and not isinstance(value, bool)


def finite(value: Any) -> bool:
    """A JSON number a float holds (an integer like 10**400 is not)."""
    try:
        return is_number(value) and math.isfinite(value)
    except OverflowError:
        return False


def brief(value: Any) -> str:
    text = repr(value)
    return text if len(text) <= 40 else text[:37] + "..."


def number(name: str, field: str, value: Any) -> float:
    if not finite(value):
        raise ParameterError(f"op '{name}': field '{field}' must be a finite number, got {brief(value)}")
    return float(value)


def tick(name: str, field: str, value: Any) -> int:
    if not finite(value) or float(value) != int(value):
        raise ParameterError(f"op '{name}': field '{field}' must be an integer tick index, got {brief(value)}")
    tick = int(value)
    if not 0 <= tick <= MAX_TICK:
        raise ParameterError(f"op '{name}': field '{field}' must lie in 0..{MAX_TICK}, got {tick}")
    return tick


def array(name: str, field: str, value: Any, *, ndim: int, inner: tuple[int, ...] = ()) -> np.ndarray:
    if not isinstance(value, list) or not value:
        raise ParameterError(f"op '{name}': field '{field}' must be a non-empty list")
    try:
        arr = np.asarray(value, dtype=np.float64)
    except (TypeError, ValueError, OverflowError):
        raise ParameterError(f"op '{name}': field '{field}' must be a rectangular array of numbers") from None
    if arr.ndim != ndim or arr.shape[1:] != inner:
        want = "[n]" + "".join(f"[{d}]" for d in inner)
        raise ParameterError(f"op '{name}': field '{field}' has shape {list(arr.shape)}, expected {want}")
    if not np.isfinite(arr).all():
        raise ParameterError(f"op '{name}': field '{field}' holds a non-finite value")
    if arr.shape[0] > MAX_TICK:
        raise ParameterError(f"op '{name}': field '{field}' is longer than {MAX_TICK} ticks")
    return arr


def paste_values(value: Any) -> tuple[dict, dict[str, np.ndarray]]:
    if not isinstance(value, dict) or not value:
        raise ParameterError("op 'paste': field 'values' must be a non-empty object {lane: per-tick values}")
    out, parsed = {}, {}
    for name, vals in value.items():
        lane("paste", "values", name)
        if name == "fans":
            arr = array("paste", "values.fans", vals, ndim=3, inner=(FAN_ROWS, FAN_COLS))
        else:
            arr = array("paste", f"values.{name}", vals, ndim=1)
        out[name] = arr.tolist()
        parsed[name] = arr
    return out, parsed


def points(value: Any) -> tuple[list, tuple[np.ndarray, np.ndarray]]:
    arr = array("temp_points", "points", value, ndim=2, inner=(2,))
    order = np.argsort(arr[:, 0], kind="stable")
    arr = arr[order]
    return arr.tolist(), (arr[:, 0], arr[:, 1])


def cells(name: str, value: Any, lanes: list[str]) -> list[list[int]]:
    """A region of the fan grid: distinct [row, col] pairs, sorted; only for the lanes ["fans"]."""
    if lanes != ["fans"]:
        raise ParameterError(f"op '{name}': field 'cells' picks fans, so 'lanes' must be [\"fans\"] alone")
    if not isinstance(value, list) or not value:
        raise ParameterError(f"op '{name}': field 'cells' must be a non-empty list of [row, col] pairs")
    cells = set()
    for cell in value:
        if (not isinstance(cell, list) or len(cell) != 2 or not all(isinstance(v, int) and not isinstance(v, bool)
                                                                    for v in cell)
                or not (0 <= cell[0] < FAN_ROWS and 0 <= cell[1] < FAN_COLS)):
            raise ParameterError(f"op '{name}': field 'cells' holds {cell!r}; each cell is [row 0..{FAN_ROWS - 1}, "
                                 f"col 0..{FAN_COLS - 1}]")
        cells.add((cell[0], cell[1]))
    return [list(c) for c in sorted(cells)]


def marker_id(name: str, field: str, value: Any) -> str:
    if not isinstance(value, str) or not value or len(value) > MAX_MARKER_ID:
        raise ParameterError(f"op '{name}': field '{field}' must be a string of 1..{MAX_MARKER_ID} characters")
    return value


def marker(name: str, value: Any, *, full: bool) -> dict:
    if not isinstance(value, dict):
        raise ParameterError(f"op '{name}': field 'marker' must be an object {{id, t_s, label}}")
    unknown = sorted(set(value) - {"id", "t_s", "label"})
    if unknown:
        raise ParameterError(f"op '{name}': field 'marker.{unknown[0]}' is unknown (fields: id, t_s, label)")
    out = {"id": marker_id(name, "marker.id", value.get("id"))}
    if "t_s" in value or full:
        if "t_s" not in value:
            raise ParameterError(f"op '{name}': field 'marker.t_s' is required")
        t = number(name, "marker.t_s", value["t_s"])
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
