"""The style document (format "autohaptics.style", version 2, reads 1; docs/STYLE_FORMAT.md): a designer's
taste as a few derive-time numbers, checked field by field at the edge.

A style changes a timeline in two places, both at derive time (no decoding):
- parameters: every intensity threshold below 1 times ``threshold_scale`` (fewer or more
  vibrating ticks), then the dotted derive-time ``overrides``;
- tracks: a floor and a tone curve per actuator and for the fans (levels below the floor off, then
  piecewise linear over ``knots``, 0 stays 0, never decreasing) and the temperature's distance from the neutral point times ``scale`` plus
  ``offset_c``.
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
from autohaptics.errors import ParameterError
from autohaptics.layout import ACTUATOR_IDS
from autohaptics.params import GenerateParams
from autohaptics.records import DERIVE, apply_overrides, stage_of_key
from autohaptics.style.apply import scaled_params, shape_levels, shape_temperature, shape_vibration

FORMAT, VERSION = "autohaptics.style", 2
VERSIONS = (1, 2)  # read; version 2 added ``floors``
KNOTS: tuple[float, ...] = (0.0, 0.05, 0.1, 0.2, 0.3, 0.4, 0.5, 0.6, 0.7, 0.8, 0.9, 1.0)
THRESHOLD_SCALE_RANGE = (0.25, 4.0)
TEMP_SCALE_RANGE = (0.0, 4.0)
TEMP_OFFSET_RANGE_C = (-20.0, 20.0)
MAX_KNOTS = 101
_KEYS = ("format", "version", "name", "threshold_scale", "overrides", "knots", "vibration", "fans",
         "temperature", "floors", "learned")


@dataclass(frozen=True)
class Style:
    """A checked style. Curves are tuples of output levels 0..1 at ``knots`` (input levels 0..1);
    ``vibration`` holds one per actuator A1..A9, ``vibration_floor`` a floor per actuator (levels
    below it off, 0..1) and ``fans_floor`` the fans'. ``learned`` records what it was fitted on."""

    name: str = ""
    threshold_scale: float = 1.0
    overrides: dict = field(default_factory=dict)
    knots: tuple[float, ...] = KNOTS
    vibration: tuple[tuple[float, ...], ...] = tuple(KNOTS for _ in ACTUATOR_IDS)
    fans: tuple[float, ...] = KNOTS
    temperature_scale: float = 1.0
    temperature_offset_c: float = 0.0
    vibration_floor: tuple[float, ...] = (0.0,) * len(ACTUATOR_IDS)
    fans_floor: float = 0.0
    learned: dict = field(default_factory=dict)

    def __post_init__(self) -> None:
        check(to_dict(self))

    def apply_params(self, params: GenerateParams) -> GenerateParams:
        """The parameters a derive in this style uses (:func:`~.apply.scaled_params`)."""
        return scaled_params(params, threshold_scale=self.threshold_scale, overrides=self.overrides)

    def shape(self, vibration: np.ndarray, temperature_c: np.ndarray, fans: np.ndarray, *, neutral_c: float,
              range_c: tuple[float, float]) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Derived tracks (vibration (n, 9) and fans (n, 9, 17) 0..1, temperature (n,) C within
        ``range_c``) in this style: new arrays, the inputs untouched."""
        return (shape_vibration(vibration, self.knots, self.vibration, self.vibration_floor),
                shape_temperature(temperature_c, scale=self.temperature_scale, offset_c=self.temperature_offset_c,
                                  neutral_c=neutral_c, range_c=range_c),
                shape_levels(fans, self.knots, self.fans, self.fans_floor))

    def to_dict(self) -> dict:
        """The JSON document (:func:`to_dict`)."""
        return to_dict(self)

    @property
    def is_identity(self) -> bool:
        """True when applying the style changes nothing."""
        return (self.threshold_scale == 1.0 and not self.overrides and self.fans == self.knots
                and all(c == self.knots for c in self.vibration)
                and self.temperature_scale == 1.0 and self.temperature_offset_c == 0.0
                and self.fans_floor == 0.0 and not any(self.vibration_floor))


def to_dict(style: Style) -> dict:
    """The JSON document of a style."""
    return {"format": FORMAT, "version": VERSION, "name": style.name, "threshold_scale": style.threshold_scale,
            "overrides": dict(style.overrides), "knots": list(style.knots),
            "vibration": {a: list(c) for a, c in zip(ACTUATOR_IDS, style.vibration)}, "fans": list(style.fans),
            "temperature": {"scale": style.temperature_scale, "offset_c": style.temperature_offset_c},
            "floors": {**dict(zip(ACTUATOR_IDS, style.vibration_floor)), "fans": style.fans_floor},
            "learned": json.loads(json.dumps(style.learned))}


def from_dict(doc: Any) -> Style:
    """A :class:`Style` from its JSON document; ParameterError naming the field otherwise. Missing
    optional fields mean "unchanged" (identity curves, scale 1, no overrides)."""
    check(doc)
    knots = tuple(float(k) for k in doc.get("knots", KNOTS))
    vib = doc.get("vibration") or {}
    temp = doc.get("temperature") or {}
    floors = doc.get("floors") or {}
    return Style(name=str(doc.get("name", "")), threshold_scale=float(doc.get("threshold_scale", 1.0)),
                 overrides=dict(doc.get("overrides") or {}), knots=knots,
                 vibration=tuple(tuple(float(v) for v in vib.get(a, knots)) for a in ACTUATOR_IDS),
                 fans=tuple(float(v) for v in doc.get("fans", knots)),
                 temperature_scale=float(temp.get("scale", 1.0)),
                 temperature_offset_c=float(temp.get("offset_c", 0.0)),
                 vibration_floor=tuple(float(floors.get(a, 0.0)) for a in ACTUATOR_IDS),
                 fans_floor=float(floors.get("fans", 0.0)), learned=dict(doc.get("learned") or {}))


def load(path: str | Path) -> Style:
    """Read a style file; a missing, unreadable or malformed file is a ParameterError naming it."""
    path = Path(path)
    try:
        doc = json.loads(path.read_text(encoding="utf-8"))
    except OSError as exc:
        raise ParameterError(f"{path}: cannot read the style ({exc.strerror or exc})") from None
    except (UnicodeDecodeError, json.JSONDecodeError) as exc:
        raise ParameterError(f"{path}: not a style file (not JSON: {exc})") from None
    try:
        return from_dict(doc)
    except ParameterError as exc:
        raise ParameterError(f"{path}: {exc}") from None


def save(style: Style, path: str | Path) -> Path:
    """Write the style's JSON document; returns the path."""
    path = Path(path)
    path.write_text(json.dumps(to_dict(style), indent=1) + "\n", encoding="utf-8")
    return path


def check(doc: Any) -> None:
    """Raise ParameterError naming the first field of ``doc`` that is not a valid style document."""
    if not isinstance(doc, dict):
        raise ParameterError(f"a style must be a JSON object, got {type(doc).__name__}")
    version = doc.get("version")
    if doc.get("format") != FORMAT or isinstance(version, bool) or version not in VERSIONS:
        raise ParameterError(f"not a style document: format must be {FORMAT!r} and version "
                             f"{' or '.join(map(str, VERSIONS))}, "
                             f"got {doc.get('format')!r}, {doc.get('version')!r}")
    unknown = sorted(set(doc) - set(_KEYS))
    if unknown:
        raise ParameterError(f"style: unknown field {unknown[0]!r} (fields: {', '.join(_KEYS)})")
    if not isinstance(doc.get("name", ""), str):
        raise ParameterError("style: name must be a string")
    _number(doc.get("threshold_scale", 1.0), "threshold_scale", *THRESHOLD_SCALE_RANGE)
    _check_overrides(doc.get("overrides", {}))
    knots = _knots(doc.get("knots", KNOTS))
    vib = doc.get("vibration", {})
    if not isinstance(vib, dict) or set(vib) - set(ACTUATOR_IDS):
        raise ParameterError(f"style: vibration must be an object with curves for {', '.join(ACTUATOR_IDS)}")
    for name, curve in vib.items():
        _curve(curve, f"vibration.{name}", len(knots))
    _curve(doc.get("fans", knots), "fans", len(knots))
    temp = doc.get("temperature", {})
    if not isinstance(temp, dict) or set(temp) - {"scale", "offset_c"}:
        raise ParameterError("style: temperature must be an object with 'scale' and 'offset_c'")
    _number(temp.get("scale", 1.0), "temperature.scale", *TEMP_SCALE_RANGE)
    _number(temp.get("offset_c", 0.0), "temperature.offset_c", *TEMP_OFFSET_RANGE_C, unit=" C")
    floors = doc.get("floors", {})
    if version == 1 and "floors" in doc:
        raise ParameterError("style: floors needs version 2")
    if not isinstance(floors, dict) or set(floors) - {*ACTUATOR_IDS, "fans"}:
        raise ParameterError(f"style: floors must be an object with levels for {', '.join(ACTUATOR_IDS)}, fans")
    for name, value in floors.items():
        _number(value, f"floors.{name}", 0.0, 1.0)
    if not isinstance(doc.get("learned", {}), dict):
        raise ParameterError("style: learned must be an object")


# ----------------------------------------------------------------------- private
def _number(value: Any, name: str, lo: float, hi: float, unit: str = "") -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
        raise ParameterError(f"style: {name} must be a finite number, got {value!r}"[:200])
    if not lo <= value <= hi:
        raise ParameterError(f"style: {name} must lie in {lo:g}..{hi:g}{unit}, got {value!r}")
    return float(value)


def _knots(value: Any) -> list[float]:
    if not isinstance(value, (list, tuple)) or not 2 <= len(value) <= MAX_KNOTS:
        raise ParameterError(f"style: knots must be a list of 2..{MAX_KNOTS} input levels")
    knots = [_number(v, "knots", 0.0, 1.0) for v in value]
    if knots[0] != 0.0 or knots[-1] != 1.0 or any(b <= a for a, b in zip(knots, knots[1:])):
        raise ParameterError(f"style: knots must rise strictly from 0 to 1, got {knots}"[:200])
    return knots


def _curve(value: Any, name: str, n: int) -> None:
    if not isinstance(value, (list, tuple)) or len(value) != n:
        raise ParameterError(f"style: {name} must be a list of {n} levels (one per knot)")
    levels = [_number(v, name, 0.0, 1.0) for v in value]
    if levels[0] != 0.0:
        raise ParameterError(f"style: {name} must start at 0 (off stays off), got {levels[0]!r}")
    if any(b < a for a, b in zip(levels, levels[1:])):
        raise ParameterError(f"style: {name} must never decrease (a stronger effect stays stronger)")


def _check_overrides(value: Any) -> None:
    if not isinstance(value, dict):
        raise ParameterError("style: overrides must be an object of dotted parameter names")
    base = GenerateParams()
    for key in value:
        if stage_of_key(base, key) != DERIVE:
            raise ParameterError(f"style: override {key!r} needs the film analysed again; a style holds "
                                 "derive-time parameters only")
    apply_overrides(base, value)
