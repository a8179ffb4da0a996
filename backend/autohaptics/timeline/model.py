"""The central data type: a per-100-ms haptic timeline (format "autohaptics.timeline", version 1).

Schema (see ../shared/docs/TIMELINE.md, the contract between generator, API, editor, exporters
and chair link):

- ``vibration``     float32 [shape=(n_ticks, 9)], intensity per actuator A1..A9, 0..1
- ``temperature_c`` float32 [shape=(n_ticks,)], target temperature, degrees Celsius, within
  ``generator.params.temp_low`` .. ``temp_high`` (defaults 30..55 C)
- ``fans``          float32 [shape=(n_ticks, 9, 17)], fan level 0..1; row 0 = top, column 0 = left
- ``features``      per-tick curves [shape=(n_ticks,)]; the normalised ones (``NORMALISED_FEATURES``)
  lie in 0..1, any other curve only needs to be finite
- ``source``, ``generator``, ``stats``: JSON objects; ``extra`` keeps unknown top-level keys
  (additions are allowed by the format) so load -> save round-trips them.

Every number is finite; a track a mode does not produce is still present (zeros, neutral
temperature) so readers never special-case.
"""

from __future__ import annotations

import io
import json
import math
import os
from dataclasses import dataclass, field
from pathlib import Path
from collections.abc import Callable
from typing import IO, Any

import numpy as np

from autohaptics import __version__
from autohaptics.errors import ParameterError
from autohaptics.layout import (
    FAN_COLS,
    FAN_ROWS,
    N_ACTUATORS,
    TEMP_HIGH_C,
    TEMP_LOW_C,
    TEMP_NEUTRAL_C,
    layout_dict,
)
from autohaptics.outputs import atomic_output
from autohaptics.timeline import numeric_json
from autohaptics.timebase import TICK_S

FORMAT = "autohaptics.timeline"
VERSION = 1
NORMALISED_FEATURES = frozenset(
    {"loudness", "sharpness", "booming", "low_energy", "intensity", "motion", "saliency_mass"}
)
_DECIMALS = 4
_KNOWN_KEYS = {"format", "version", "tick_s", "n_ticks", "source", "generator", "layout", "tracks",
               "features", "stats"}


@dataclass
class Timeline:
    """A haptic timeline. Build with :meth:`empty` or the constructor, then :meth:`validate`."""

    n_ticks: int
    vibration: np.ndarray
    temperature_c: np.ndarray
    fans: np.ndarray
    source: dict = field(default_factory=dict)
    generator: dict = field(default_factory=dict)
    features: dict[str, np.ndarray] = field(default_factory=dict)
    stats: dict = field(default_factory=dict)
    extra: dict = field(default_factory=dict)
    layout: dict = field(default_factory=layout_dict)
    tick_s: float = TICK_S

    # ------------------------------------------------------------------ build
    @classmethod
    def empty(cls, n_ticks: int, *, source: dict | None = None, generator: dict | None = None,
              neutral_c: float = TEMP_NEUTRAL_C) -> "Timeline":
        """All-off timeline of ``n_ticks`` ticks: no vibration, no fans, temperature at ``neutral_c``."""
        if int(n_ticks) < 1:
            raise ParameterError(f"a timeline needs at least 1 tick, got n_ticks={n_ticks}")
        n = int(n_ticks)
        return cls(
            n_ticks=n,
            vibration=np.zeros((n, N_ACTUATORS), np.float32),
            temperature_c=np.full(n, neutral_c, np.float32),
            fans=np.zeros((n, FAN_ROWS, FAN_COLS), np.float32),
            source=dict(source or {}),
            generator=default_generator(**(generator or {})),
        )

    @property
    def temp_range(self) -> tuple[float, float]:
        """(temp_low, temp_high) in C from ``generator.params``, defaults 30..55 C."""
        params = self.generator.get("params") or {}
        lo = params.get("temp_low", TEMP_LOW_C)
        hi = params.get("temp_high", TEMP_HIGH_C)
        return float(lo), float(hi)

    @property
    def duration_s(self) -> float:
        return self.n_ticks * self.tick_s

    # --------------------------------------------------------------- validate
    def validate(self) -> "Timeline":
        """Check shapes, finiteness and ranges; raise ParameterError naming the track and shape.

        Converts the tracks to float32 in place and returns ``self``.
        """
        n = self.n_ticks
        if not isinstance(n, (int, np.integer)) or n < 1:
            raise ParameterError(f"n_ticks must be a positive integer, got {n!r}")
        if not math.isclose(float(self.tick_s), TICK_S):
            raise ParameterError(f"tick_s must be {TICK_S}, got {self.tick_s!r}")
        self.vibration = _check_track("vibration", self.vibration, (n, N_ACTUATORS), 0.0, 1.0)
        lo, hi = self.temp_range
        if not (math.isfinite(lo) and math.isfinite(hi) and lo <= hi):
            raise ParameterError(f"generator.params temp_low/temp_high must be finite with low <= high, got {lo}, {hi}")
        self.temperature_c = _check_track("temperature_c", self.temperature_c, (n,), lo, hi)
        self.fans = _check_track("fans", self.fans, (n, FAN_ROWS, FAN_COLS), 0.0, 1.0)
        for name, values in list(self.features.items()):
            lo_f, hi_f = (0.0, 1.0) if name in NORMALISED_FEATURES else (-math.inf, math.inf)
            self.features[name] = _check_track(f"features.{name}", values, (n,), lo_f, hi_f)
        for key in ("source", "generator", "stats"):
            if not isinstance(getattr(self, key), dict):
                raise ParameterError(f"{key} must be a JSON object, got {type(getattr(self, key)).__name__}")
        return self

    # ------------------------------------------------------------- serialise
    def to_dict(self) -> dict:
        """The JSON document as Python objects (lists of floats rounded to 4 decimals)."""
        return json.loads(self.to_json())

    def to_json(self) -> str:
        buf = io.StringIO()
        self.write(buf)
        return buf.getvalue()

    def write(self, fh: IO[str]) -> None:
        """Write the JSON document to a text stream, tick by tick (memory does not grow with length)."""
        self.validate()
        head = {
            "format": FORMAT, "version": VERSION, "tick_s": self.tick_s, "n_ticks": int(self.n_ticks),
            "source": self.source, "generator": self.generator, "layout": self.layout,
        }
        fh.write("{\n")
        for key, value in head.items():
            fh.write(f"{json.dumps(key)}: {json.dumps(value, default=json_default)},\n")
        fh.write('"tracks": {\n"vibration": ')
        _write_rows(fh, self.vibration)
        fh.write(',\n"temperature_c": ')
        _write_rows(fh, self.temperature_c.reshape(-1, 1), flat=True)
        fh.write(',\n"fans": ')
        _write_rows(fh, self.fans)
        fh.write("\n},\n\"features\": {")
        for i, (name, values) in enumerate(self.features.items()):
            fh.write(("," if i else "") + f"\n{json.dumps(name)}: ")
            _write_rows(fh, np.asarray(values).reshape(-1, 1), flat=True)
        fh.write("\n},\n")
        fh.write(f'"stats": {json.dumps(self.stats, default=json_default)}')
        for key, value in self.extra.items():
            fh.write(f",\n{json.dumps(key)}: {json.dumps(value, default=json_default)}")
        fh.write("\n}\n")

    def save(self, path: str | os.PathLike) -> Path:
        """Validate and write to ``path`` atomically (a temporary file renamed into place)."""
        with atomic_output(path, binary=False) as fh:
            self.write(fh)
        return Path(path)

    @classmethod
    def from_dict(cls, doc: dict) -> "Timeline":
        """Build from a parsed JSON document and validate it."""
        if not isinstance(doc, dict):
            raise ParameterError("a timeline document must be a JSON object")
        if doc.get("format") != FORMAT:
            raise ParameterError(f"not an autohaptics timeline: format is {doc.get('format')!r}, expected {FORMAT!r}")
        if doc.get("version") != VERSION:
            raise ParameterError(f"unsupported timeline version {doc.get('version')!r}; this build reads version {VERSION}")
        tracks = doc.get("tracks")
        if not isinstance(tracks, dict):
            raise ParameterError("timeline has no 'tracks' object")
        for name in ("vibration", "temperature_c", "fans"):
            if name not in tracks:
                raise ParameterError(f"timeline is missing track '{name}'")
        n = doc.get("n_ticks")
        if not isinstance(n, int) or isinstance(n, bool):
            raise ParameterError(f"n_ticks must be an integer, got {n!r}")
        tl = cls(
            n_ticks=n,
            vibration=_as_array("vibration", tracks["vibration"]),
            temperature_c=_as_array("temperature_c", tracks["temperature_c"]),
            fans=_as_array("fans", tracks["fans"]),
            source=doc.get("source") or {},
            generator=doc.get("generator") or {},
            features={k: _as_array(f"features.{k}", v) for k, v in (doc.get("features") or {}).items()},
            stats=doc.get("stats") or {},
            extra={k: v for k, v in doc.items() if k not in _KNOWN_KEYS},
            layout=doc.get("layout") or layout_dict(),
            tick_s=float(doc.get("tick_s", TICK_S)),
        )
        return tl.validate()

    @classmethod
    def from_json(cls, text: str) -> "Timeline":
        try:
            doc = json.loads(text)
        except json.JSONDecodeError as exc:
            raise ParameterError(f"timeline is not valid JSON: {exc}") from None
        return cls.from_dict(doc)

    @classmethod
    def load(cls, path: str | os.PathLike) -> "Timeline":
        """Read and validate a timeline file; errors name the file."""
        path = Path(path)
        doc = read_json(path, "timeline JSON file", arrays_at=_numeric_place)
        try:
            return cls.from_dict(doc)
        except ParameterError as exc:
            raise ParameterError(f"{path}: {exc}") from None

    def copy(self) -> "Timeline":
        return Timeline(
            n_ticks=self.n_ticks, vibration=self.vibration.copy(), temperature_c=self.temperature_c.copy(),
            fans=self.fans.copy(), source=json.loads(json.dumps(self.source, default=json_default)),
            generator=json.loads(json.dumps(self.generator, default=json_default)),
            features={k: np.array(v, copy=True) for k, v in self.features.items()},
            stats=json.loads(json.dumps(self.stats, default=json_default)),
            extra=json.loads(json.dumps(self.extra, default=json_default)),
            layout=json.loads(json.dumps(self.layout)), tick_s=self.tick_s,
        )


def default_generator(**overrides: Any) -> dict:
    """The ``generator`` block: name, version, mode, preset, params (every parameter that shaped it)."""
    gen = {"name": "autohaptics", "version": __version__, "mode": "audio", "preset": "balanced", "params": {}}
    gen.update(overrides)
    return gen


# ---------------------------------------------------------------------- private
def _numeric_place(path: tuple) -> bool:
    """Where a timeline document holds its big numeric arrays: a track or a feature curve."""
    return len(path) == 2 and path[0] in ("tracks", "features")


def _as_array(name: str, value: Any) -> np.ndarray:
    if isinstance(value, np.ndarray) and value.dtype in (np.float32, np.float64):
        return value  # no copy: a 2-hour fan track is 44 MB
    try:
        arr = np.asarray(value, dtype=np.float64)
    except (TypeError, ValueError):
        raise ParameterError(f"track '{name}' is not a rectangular array of numbers") from None
    return arr


def _check_track(name: str, values: Any, shape: tuple[int, ...], lo: float, hi: float) -> np.ndarray:
    arr = _as_array(name, values)
    if arr.shape != shape:
        raise ParameterError(f"track '{name}' has shape {arr.shape}, expected {shape}")
    if arr.size:
        amin, amax = float(arr.min()), float(arr.max())  # NaN propagates; inf is an extreme
        if not (math.isfinite(amin) and math.isfinite(amax)):  # no full-size mask unless there is one
            idx = tuple(int(i) for i in np.argwhere(~np.isfinite(arr))[0])
            raise ParameterError(f"track '{name}' holds a non-finite value at index {idx} (shape {shape})")
        # Tracks are stored rounded to 4 decimals; allow that much slack at the range ends.
        tol = 0.5 * 10.0 ** -_DECIMALS
        if amin < lo - tol or amax > hi + tol:
            bad = amin if amin < lo - tol else amax
            idx = tuple(int(i) for i in np.argwhere(arr == bad)[0])
            raise ParameterError(
                f"track '{name}' value {bad:g} at index {idx} is outside [{lo:g}, {hi:g}] (shape {shape})")
        if amin < lo or amax > hi:
            arr = np.clip(arr, lo, hi)
    return arr.astype(np.float32, copy=False)


def _fmt(v: float) -> str:
    if v == 0.0:
        return "0"
    s = f"{v:.{_DECIMALS}f}".rstrip("0").rstrip(".")
    return "0" if s in ("-0", "") else s


def _write_rows(fh: IO[str], arr: np.ndarray, *, flat: bool = False) -> None:
    """Write ``arr`` as nested JSON lists, one tick per line, rounded to 4 decimals."""
    fh.write("[")
    zero_cache: dict[tuple, str] = {}
    block = 512  # rounded in blocks: a 2-hour fan track in one piece would be 88 MB of float64
    for k in range(arr.shape[0]):
        if k % block == 0:
            rounded = np.round(np.asarray(arr[k:k + block], dtype=np.float64), _DECIMALS)
        row = rounded[k % block]
        if flat:
            text = _fmt(float(row[0]))
        elif not row.any():
            key = row.shape
            if key not in zero_cache:
                zero_cache[key] = json.dumps(np.zeros(row.shape, dtype=np.int8).tolist()).replace(" ", "")
            text = zero_cache[key]
        else:
            text = _nested(row)
        fh.write(("," if k else "") + ("\n" if not flat and k else "") + text)
    fh.write("]")


def _nested(row: np.ndarray) -> str:
    if row.ndim == 1:
        return "[" + ",".join(_fmt(float(v)) for v in row) + "]"
    return "[" + ",".join(_nested(r) for r in row) + "]"


def json_default(obj: Any) -> Any:
    """``json.dumps(default=...)`` for the numpy scalars and arrays, tuples, sets and paths in metadata."""
    if isinstance(obj, np.generic):
        return obj.item()
    if isinstance(obj, np.ndarray):
        return obj.tolist()
    if isinstance(obj, (set, tuple)):
        return list(obj)
    if isinstance(obj, Path):
        return str(obj)
    raise TypeError(f"{type(obj).__name__} is not JSON serialisable")


def read_json(path: Path, what: str, arrays_at: Callable[[tuple], bool] | None = None) -> Any:
    """The JSON document in ``path``; ParameterError naming the file when it is missing or not
    JSON (``what`` says what it should have been). ``arrays_at``: the paths (tuples of keys) whose
    big numeric arrays come back as float64 arrays (:func:`.numeric_json.loads`)."""
    try:
        if arrays_at is not None:
            return numeric_json.loads(Path(path).read_bytes(), arrays_at)
        with open(path, encoding="utf-8") as fh:
            return json.load(fh)
    except FileNotFoundError:
        raise ParameterError(f"{path}: no such file") from None
    except (json.JSONDecodeError, UnicodeDecodeError) as exc:
        raise ParameterError(f"{path}: not a {what} ({exc})") from None
