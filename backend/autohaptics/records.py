"""Frozen parameter records: which fields the analysis depends on, dotted overrides, and the JSON
round trip.

Tags: a record's ``STAGE`` class attribute says whether changing its fields needs the film analysed
again (ANALYSIS) or only a re-derive from the cached analysis (DERIVE); a field's
``metadata=stage(...)`` overrides it. Overrides have one meaning across the CLI, the API and the
editor: ``"flow.method": "dis"`` replaces that field of a copy; string values (from the command
line) are converted to the field's type; an unknown name is a ParameterError naming the known ones.
"""

from __future__ import annotations

import dataclasses
import json
import math
import types
import typing
from typing import Any

from autohaptics.errors import ParameterError

ANALYSIS, DERIVE = "analysis", "derive"


def stage(name: str) -> dict:
    """Field metadata tagging one field ANALYSIS or DERIVE against its record's ``STAGE``."""
    return {"stage": name}


def param(default: Any, lo: float | None = None, hi: float | None = None, *, unit: str = "",
          gt: float | None = None, choices: tuple | None = None, whole: bool = False,
          stage: str | None = None) -> Any:
    """A record field with its default and what it accepts, checked by :class:`Record`: a number in
    ``lo..hi`` (inclusive, either may be open) or above ``gt``, in ``unit`` for the message; a
    whole number if ``whole``; one of ``choices``; None always passes (optional fields)."""
    meta: dict[str, Any] = {"lo": lo, "hi": hi, "gt": gt, "unit": unit, "choices": choices, "whole": whole}
    if stage is not None:
        meta["stage"] = stage
    return dataclasses.field(default=default, metadata=meta)


def _bound_error(group: str, f: dataclasses.Field, value: Any) -> str | None:
    m = f.metadata
    name, unit = f"{group}.{f.name}" if group else f.name, (" " + m["unit"]) if m.get("unit") else ""
    if m.get("choices") is not None:
        return None if value in m["choices"] else f"{name} must be one of {tuple(m['choices'])}, got {value!r}"
    if all(m.get(k) is None for k in ("lo", "hi", "gt")) and not m.get("whole"):
        return None
    numeric = isinstance(value, (int, float)) and not isinstance(value, bool)
    if m.get("whole") and not isinstance(value, int) or not numeric or not math.isfinite(value):
        kind = "a whole number" if m.get("whole") else "a finite number"
        return f"{name} must be {kind}{unit and ' of' + unit}, got {value!r}"
    lo, hi, gt = m.get("lo"), m.get("hi"), m.get("gt")
    if gt is not None and not value > gt:
        return f"{name} must be above {gt:g}{unit}, got {value!r}"
    if (lo is not None and value < lo) or (hi is not None and value > hi):
        span = f"{'' if lo is None else f'{lo:g}'}..{'' if hi is None else f'{hi:g}'}"
        return f"{name} must lie in {span}{unit}, got {value!r}"
    return None


class Record:
    """Base of a stage's frozen parameter dataclass: after construction every field declared with
    :func:`param` is checked (a ParameterError naming ``GROUP.field``), then :meth:`check` runs the
    record's own rules that tie fields together."""

    GROUP: typing.ClassVar[str] = ""

    def __post_init__(self) -> None:
        for f in dataclasses.fields(self):
            value = getattr(self, f.name)
            error = None if value is None else _bound_error(self.GROUP, f, value)
            if error:
                raise ParameterError(error)
        self.check()

    def check(self) -> None:
        """Rules across fields (none by default)."""


def stage_of(record: Any, name: str) -> str:
    """ANALYSIS or DERIVE: what a change of ``record``'s field ``name`` needs."""
    f = {f.name: f for f in dataclasses.fields(record)}[name]
    return f.metadata.get("stage", getattr(record, "STAGE", DERIVE))


def stage_of_key(params: Any, key: str) -> str:
    """ANALYSIS or DERIVE for a dotted name (``"intensity.thresholds.loudness"``: a key inside a
    dict field has the dict field's stage); an unknown name or a group is a ParameterError."""
    obj, path = params, key.split(".")
    for i, name in enumerate(path):
        if not dataclasses.is_dataclass(obj) or name not in {f.name for f in dataclasses.fields(obj)}:
            raise ParameterError(f"unknown parameter {key!r}")
        value = getattr(obj, name)
        if not dataclasses.is_dataclass(value):
            return stage_of(obj, name)
        if i == len(path) - 1:
            raise ParameterError(f"{key!r} is a group of parameters: name one of its fields")
        obj = value
    return DERIVE


def apply_overrides(params: Any, overrides: dict[str, Any]) -> Any:
    """Return a copy of a (nested, frozen) params dataclass with dotted ``overrides`` applied.

    Values may be strings (from the command line); they are converted to the field's type.
    Unknown names raise ParameterError naming the key and the known fields.
    """
    for key, value in overrides.items():
        params = _set_path(params, key.split("."), value, key)
    return params


def parse_assignments(items: list[str] | None) -> dict[str, str]:
    """``["flow.method=dis", "video.proxy_width=128"]`` -> {"flow.method": "dis", ...}."""
    out: dict[str, str] = {}
    for item in items or []:
        if "=" not in item:
            raise ParameterError(f"expected NAME=VALUE, got {item!r}")
        name, value = item.split("=", 1)
        name = name.strip()
        if not name:
            raise ParameterError(f"expected NAME=VALUE, got {item!r}")
        out[name] = value.strip()
    return out


def params_to_dict(params: Any) -> dict:
    """A JSON-serialisable nested dict of a params dataclass."""
    return json.loads(json.dumps(dataclasses.asdict(params), default=_default))


def params_from_dict(cls: type, doc: dict) -> Any:
    """Inverse of :func:`params_to_dict` for a params dataclass (unknown keys are errors)."""
    base = cls()
    flat: dict[str, Any] = {}

    def walk(prefix: str, d: dict, obj: Any):
        for k, v in d.items():
            child = getattr(obj, k, None) if obj is not None else None
            if isinstance(v, dict) and dataclasses.is_dataclass(child):
                walk(f"{prefix}{k}.", v, child)
            else:
                flat[f"{prefix}{k}"] = v

    walk("", doc, base)
    return apply_overrides(base, flat)


# ----------------------------------------------------------------------- private
def _set_path(obj: Any, path: list[str], value: Any, key: str) -> Any:
    if not dataclasses.is_dataclass(obj):
        raise ParameterError(f"cannot set {key!r}: {type(obj).__name__} has no fields")
    names = {f.name: f for f in dataclasses.fields(obj)}
    head = path[0]
    if head not in names:
        raise ParameterError(f"unknown parameter {key!r}; {type(obj).__name__} has {sorted(names)}")
    current = getattr(obj, head)
    if len(path) == 1 and dataclasses.is_dataclass(current):
        if not isinstance(value, dict):
            raise ParameterError(f"{key!r} is a group of parameters: set one of its fields "
                                 f"({key}.{dataclasses.fields(current)[0].name}=...) or give an object")
        nested = dict(value)
        try:
            return dataclasses.replace(obj, **{head: apply_overrides(current, nested)})
        except RecursionError:
            raise ParameterError(f"{key!r} is nested too deeply") from None
    if len(path) > 1:
        if isinstance(current, dict):
            new = dict(current)
            new[path[1]] = _convert(value, type(current.get(path[1], 0.0)) if path[1] in current else float, key)
            return dataclasses.replace(obj, **{head: new})
        return dataclasses.replace(obj, **{head: _set_path(current, path[1:], value, key)})
    hints = typing.get_type_hints(type(obj))
    converted = _convert_hint(value, hints.get(head, type(current)), current, key)
    try:
        return dataclasses.replace(obj, **{head: converted})
    except (TypeError, ValueError) as exc:
        raise ParameterError(f"invalid value for {key!r}: {exc}") from None


def _convert_hint(value: Any, hint: Any, current: Any, key: str) -> Any:
    origin = typing.get_origin(hint)
    args = typing.get_args(hint)
    if origin in (typing.Union, types.UnionType):
        if isinstance(value, str) and value.lower() in ("none", "null", "") and type(None) in args:
            return None
        if value is None and type(None) in args:
            return None
        last: Exception | None = None
        for a in args:
            if a is type(None):
                continue
            try:
                return _convert_hint(value, a, current, key)
            except ParameterError as exc:
                last = exc
        raise last or ParameterError(f"invalid value for {key!r}: {value!r}")
    if hint is typing.Any:
        return value
    if origin in (tuple, list):
        if isinstance(value, str):
            value = [v for v in value.replace("x", ",").split(",") if v.strip()]
        if not isinstance(value, (list, tuple)):
            raise ParameterError(f"{key!r} expects a list, got {value!r}"[:300])
        inner = args[0] if args else float
        return (tuple if origin is tuple else list)(_convert(v, inner, key) for v in value)
    if origin is dict or hint is dict:
        if isinstance(value, str):
            try:
                value = json.loads(value)
            except json.JSONDecodeError:
                raise ParameterError(f"{key!r} expects a JSON object, got {value!r}") from None
        if not isinstance(value, dict):
            raise ParameterError(f"{key!r} expects an object, got {value!r}")
        return dict(value)
    if isinstance(hint, type):
        return _convert(value, hint, key)
    return value


def _convert(value: Any, typ: type, key: str) -> Any:
    if typ is bool:
        if isinstance(value, bool):
            return value
        s = str(value).strip().lower()
        if s in ("1", "true", "yes", "on"):
            return True
        if s in ("0", "false", "no", "off"):
            return False
        raise ParameterError(f"{key!r} expects true/false, got {value!r}")
    if typ is int:  # "2", 2, "2.0" and 2.0 are 2; 1.5 is refused rather than cut to 1
        try:
            f = float(value)
        except (TypeError, ValueError, OverflowError):
            raise ParameterError(f"{key!r} expects a whole number, got {value!r}") from None
        if not (math.isfinite(f) and f.is_integer()):
            raise ParameterError(f"{key!r} expects a whole number, got {value!r}")
        return int(value) if isinstance(value, int) else int(f)
    if typ is float:
        try:
            v = float(value)
        except (TypeError, ValueError, OverflowError):
            raise ParameterError(f"{key!r} expects a number, got {value!r}") from None
        if not math.isfinite(v):
            raise ParameterError(f"{key!r} must be finite, got {value!r}")
        return v
    if typ is str:
        return str(value)
    return value


def _default(obj: Any) -> Any:
    if isinstance(obj, (set, frozenset, tuple)):
        return list(obj)
    return str(obj)
