"""Importers: a timeline from our own files, the native JSON or the CSV of :mod:`autohaptics.formats.csv`.

- :func:`import_timeline` reads a file (format from the suffix, else sniffed); a CSV's metadata
  sidecar ``NAME.meta.json`` next to it is used when present.
- :func:`parse_timeline` takes the bytes or text of an upload (the web editor's entry point).
- :func:`read_csv` parses CSV lines from any iterable of strings, streaming.

CSV validation names the row and the column of every problem (row 1 is the first data row, the
line after the header; blank lines are skipped): a cell that is not a number or not finite, a
value outside its range (0..1 for motors and fans, the generator's temp_low..temp_high for
temperature_c), a time that is not on the 100 ms grid or not the next tick, a row with the
wrong number of fields, missing, unexpected or repeated columns. Up to ``MAX_PROBLEMS`` problems
are collected into one :class:`TimelineImportError`, whose ``problems`` list an editor can show.
"""

from __future__ import annotations

import csv
import io
import os
from collections.abc import Iterable, Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from autohaptics.errors import ParameterError
from autohaptics.formats.csv import CSV_COLUMNS, SIDECAR_FORMAT, TEMPERATURE_COLUMN, TIME_COLUMN
from autohaptics.layout import FAN_COLS, FAN_ROWS, N_ACTUATORS, TEMP_HIGH_C, TEMP_LOW_C, layout_dict
from autohaptics.timebase import TICK_S
from autohaptics.timeline import Timeline, default_generator
from autohaptics.timeline.model import read_json

MAX_PROBLEMS = 20
_BLOCK_ROWS = 2048
_VALUE_TOL = 5e-5  # the CSV holds 4 decimals
_TIME_TOL = 5e-5 + 1e-9
_TEMP_COL = CSV_COLUMNS.index(TEMPERATURE_COLUMN)
_LEVEL_COLS = np.array([i for i, c in enumerate(CSV_COLUMNS) if c not in (TIME_COLUMN, TEMPERATURE_COLUMN)])


@dataclass(frozen=True)
class ImportProblem:
    """One problem of an imported file: ``row`` is the 1-based data row (None: the file or its
    header), ``column`` the column name (None: the whole row)."""

    row: int | None
    column: str | None
    message: str

    def __str__(self) -> str:
        where = ", ".join(p for p in (f"row {self.row}" if self.row is not None else None,
                                      f"column {self.column}" if self.column else None) if p)
        return f"{where}: {self.message}" if where else self.message


class TimelineImportError(ParameterError):
    """An imported file is not a valid timeline; ``problems`` lists what is wrong where."""

    def __init__(self, name: str, problems: list[ImportProblem], *, truncated: bool = False):
        self.name = name
        self.problems = list(problems)
        if len(self.problems) == 1:
            text = str(self.problems[0])
        else:
            more = f" (stopped after the first {len(self.problems)})" if truncated else ""
            text = f"{len(self.problems)} problems{more}: " + "; ".join(str(p) for p in self.problems)
        super().__init__(f"{name}: {text}")


# ---------------------------------------------------------------------------- entry points
def import_timeline(path: str | os.PathLike, *, fmt: str | None = None,
                    meta: dict | str | os.PathLike | None = "auto") -> Timeline:
    """Read a timeline file: ``fmt`` "json" or "csv" (default: from the suffix, else sniffed).

    ``meta`` (CSV only): "auto" uses the sidecar ``<stem>.meta.json`` when it exists; a path or
    a dict gives it explicitly; None ignores it.
    """
    path = Path(path)
    if path.is_dir():
        raise ParameterError(f"{path}: is a folder; give a timeline JSON or CSV file")
    if not path.is_file():
        raise ParameterError(f"{path}: no such file")
    fmt = (fmt or _format_from_suffix(path) or _sniff_file(path)).lower()
    if fmt == "json":
        return Timeline.load(path)
    if fmt != "csv":
        raise ParameterError(f"{path}: cannot import format {fmt!r}; choose json or csv")
    meta_doc = _resolve_meta(path, meta)
    try:
        with open(path, encoding="utf-8-sig", newline="") as fh:
            return read_csv(fh, meta=meta_doc, name=str(path))
    except UnicodeDecodeError as exc:
        raise ParameterError(f"{path}: not UTF-8 text ({exc.reason} at byte {exc.start})") from None


def parse_timeline(data: bytes | str, *, fmt: str | None = None, meta: dict | None = None,
                   name: str = "upload") -> Timeline:
    """A timeline from the content of an uploaded file (bytes or text), JSON or CSV.

    ``fmt`` "json"/"csv" (default: JSON when the text starts with ``{``, else CSV); ``meta`` an
    optional CSV sidecar as a dict; ``name`` prefixes every error message.
    """
    if isinstance(data, (bytes, bytearray, memoryview)):
        try:
            text = bytes(data).decode("utf-8-sig")
        except UnicodeDecodeError as exc:
            raise ParameterError(f"{name}: not UTF-8 text ({exc.reason} at byte {exc.start})") from None
    elif isinstance(data, str):
        text = data[1:] if data.startswith("\ufeff") else data
    else:
        raise ParameterError(f"{name}: expected bytes or text, got {type(data).__name__}")
    fmt = (fmt or ("json" if text.lstrip()[:1] == "{" else "csv")).lower()
    if fmt == "json":
        try:
            return Timeline.from_json(text)
        except ParameterError as exc:
            raise ParameterError(f"{name}: {exc}") from None
    if fmt != "csv":
        raise ParameterError(f"{name}: cannot import format {fmt!r}; choose json or csv")
    return read_csv(io.StringIO(text, newline=""), meta=meta, name=name)


def read_csv(lines: Iterable[str], *, meta: dict | None = None, name: str = "CSV") -> Timeline:
    """Parse and validate a timeline CSV (the columns of :data:`CSV_COLUMNS`, in any order).

    lines : iterable of text lines (an open file, a StringIO). ``meta`` : the sidecar dict, which
    supplies source/generator/layout/stats and the temperature range; without it the temperature
    range is the default 30..55 C and the source records only the name and duration.
    """
    meta = _check_meta(meta, name)
    generator = meta.get("generator") or default_generator(mode="imported")
    lo_t, hi_t = _temp_range(generator)
    reader = csv.reader(lines)
    header = _read_header(reader, name)
    order = _column_order(header, name)
    problems: list[ImportProblem] = []
    blocks: list[np.ndarray] = []
    pending: list[list[str]] = []
    pending_rows: list[int] = []
    n_rows = 0
    for row in _rows(reader, name, problems):
        if not row:
            continue
        n_rows += 1
        if len(row) != len(header):
            problems.append(ImportProblem(n_rows, None, f"expected {len(header)} fields, got {len(row)}"))
        else:
            pending.append(row)
            pending_rows.append(n_rows)
        if len(pending) >= _BLOCK_ROWS:
            blocks.append(_convert(pending, pending_rows, header, order, (lo_t, hi_t), problems))
            pending, pending_rows = [], []
        if len(problems) >= MAX_PROBLEMS:
            problems = sorted(problems, key=_problem_key)
            raise TimelineImportError(name, problems[:MAX_PROBLEMS], truncated=True)
    if pending:
        blocks.append(_convert(pending, pending_rows, header, order, (lo_t, hi_t), problems))
    if n_rows == 0:
        problems.append(ImportProblem(None, None, "no data rows (expected one row per 100 ms tick "
                                                  "after the header)"))
    if "n_ticks" in meta and not problems and meta["n_ticks"] != n_rows:
        problems.append(ImportProblem(None, None, f"the metadata sidecar says n_ticks={meta['n_ticks']}"
                                                  f" but the file has {n_rows} data rows"))
    if problems:
        problems = sorted(problems, key=_problem_key)
        raise TimelineImportError(name, problems[:MAX_PROBLEMS], truncated=len(problems) > MAX_PROBLEMS)
    data = np.concatenate(blocks, axis=0)
    n = data.shape[0]
    source = meta.get("source") or {"name": Path(name).name, "duration_s": round(n * TICK_S, 4),
                                    "video": None, "audio": None}
    tl = Timeline(
        n_ticks=n,
        vibration=data[:, 1:1 + N_ACTUATORS],
        temperature_c=data[:, _TEMP_COL],
        fans=data[:, _TEMP_COL + 1:].reshape(n, FAN_ROWS, FAN_COLS),
        source=source,
        generator=generator,
        stats=meta.get("stats") or {},
        extra=meta.get("extra") or {},
        layout=meta.get("layout") or layout_dict(),
    )
    try:
        return tl.validate()
    except ParameterError as exc:
        raise ParameterError(f"{name}: {exc}") from None


def read_csv_meta(path: str | os.PathLike) -> dict:
    """Load a CSV metadata sidecar (written by ``autohaptics export --format csv --meta``)."""
    path = Path(path)
    return _check_meta(read_json(path, "JSON sidecar"), str(path))


def csv_meta_path(csv_path: str | os.PathLike) -> Path:
    """Where the metadata sidecar of a CSV lives: ``movie.csv`` -> ``movie.meta.json``."""
    return Path(csv_path).with_suffix(".meta.json")


# ---------------------------------------------------------------------------- private
def _format_from_suffix(path: Path) -> str | None:
    return {".csv": "csv", ".json": "json"}.get(path.suffix.lower())


def _sniff_file(path: Path) -> str:
    with open(path, "rb") as fh:
        head = fh.read(256).lstrip(b"\xef\xbb\xbf \t\r\n")
    return "json" if head[:1] == b"{" else "csv"


def _resolve_meta(path: Path, meta: Any) -> dict | None:
    if meta is None or isinstance(meta, dict):
        return meta
    if meta == "auto":
        side = csv_meta_path(path)
        return read_csv_meta(side) if side.is_file() else None
    return read_csv_meta(meta)


def _check_meta(meta: Any, name: str) -> dict:
    if meta is None:
        return {}
    if not isinstance(meta, dict):
        raise ParameterError(f"{name}: the metadata sidecar must be a JSON object")
    if meta.get("format") != SIDECAR_FORMAT:
        raise ParameterError(f"{name}: not an autohaptics CSV sidecar: format is {meta.get('format')!r}, "
                             f"expected {SIDECAR_FORMAT!r}")
    for key in ("source", "generator", "layout", "stats", "extra"):
        if key in meta and meta[key] is not None and not isinstance(meta[key], dict):
            raise ParameterError(f"{name}: sidecar key {key!r} must be a JSON object")
    return meta


def _temp_range(generator: dict) -> tuple[float, float]:
    params = generator.get("params") or {}
    return float(params.get("temp_low", TEMP_LOW_C)), float(params.get("temp_high", TEMP_HIGH_C))


def _rows(reader, name: str, problems: list[ImportProblem]) -> Iterator[list[str]]:
    while True:
        try:
            yield next(reader)
        except StopIteration:
            return
        except csv.Error as exc:
            problems.append(ImportProblem(None, None, f"line {reader.line_num}: malformed CSV ({exc})"))
            raise TimelineImportError(name, problems) from None


def _read_header(reader, name: str) -> list[str]:
    for header in reader:
        if header:
            return [h.strip() for h in header]
    raise TimelineImportError(name, [ImportProblem(None, None, "the file is empty (expected a header "
                                                               "row and one row per 100 ms tick)")])


def _column_order(header: list[str], name: str) -> np.ndarray:
    """Index in ``header`` of each of CSV_COLUMNS; TimelineImportError for a bad header."""
    problems = []
    seen: dict[str, int] = {}
    for i, h in enumerate(header):
        if h in seen:
            problems.append(ImportProblem(None, h, f"column appears twice (fields {seen[h] + 1} and {i + 1})"))
        else:
            seen[h] = i
    missing = [c for c in CSV_COLUMNS if c not in seen]
    extra = [h for h in seen if h not in CSV_COLUMNS]
    if missing:
        problems.append(ImportProblem(None, None, f"missing column{'s' if len(missing) > 1 else ''} "
                                                   f"{_name_list(missing)}"))
    if extra:
        problems.append(ImportProblem(None, None, f"unexpected column{'s' if len(extra) > 1 else ''} "
                                                   f"{_name_list(extra)} (expected: time_s, A1..A9, "
                                                   "temperature_c, fan_r0_c0..fan_r8_c16)"))
    if problems:
        raise TimelineImportError(name, problems)
    return np.array([seen[c] for c in CSV_COLUMNS], dtype=np.int64)


def _name_list(names: list[str], limit: int = 8) -> str:
    shown = ", ".join(names[:limit])
    return shown + (f" and {len(names) - limit} more" if len(names) > limit else "")


def _convert(rows: list[list[str]], row_numbers: list[int], header: list[str], order: np.ndarray,
             temp_range: tuple[float, float], problems: list[ImportProblem]) -> np.ndarray:
    """Rows of strings -> float32 [shape=(len(rows), 164)] in CSV_COLUMNS order, appending problems."""
    found: list[ImportProblem] = []
    try:
        raw = np.array(rows, dtype=np.float64)
    except ValueError:
        raw = np.empty((len(rows), len(header)), dtype=np.float64)
        for i, row in enumerate(rows):
            for j, cell in enumerate(row):
                try:
                    raw[i, j] = float(cell)
                except ValueError:
                    raw[i, j] = 0.0
                    found.append(ImportProblem(row_numbers[i], header[j], f"{cell!r} is not a number"))
    nonfinite = ~np.isfinite(raw)
    for i, j in np.argwhere(nonfinite)[:MAX_PROBLEMS]:
        found.append(ImportProblem(row_numbers[i], header[j], f"{rows[i][j].strip()!r} is not a finite number"))
    raw[nonfinite] = 0.0
    data = raw[:, order]
    rows_idx = np.asarray(row_numbers, dtype=np.int64)

    t = data[:, 0]
    ticks = np.rint(t / TICK_S)
    off_grid = np.abs(t - ticks * TICK_S) > _TIME_TOL
    wrong_tick = ~off_grid & (ticks != rows_idx - 1)
    for i in np.flatnonzero(off_grid)[:MAX_PROBLEMS]:
        found.append(ImportProblem(row_numbers[i], TIME_COLUMN, f"{t[i]:g} is not on the 100 ms grid"))
    for i in np.flatnonzero(wrong_tick)[:MAX_PROBLEMS]:
        found.append(ImportProblem(row_numbers[i], TIME_COLUMN,
                                   f"expected {(rows_idx[i] - 1) * TICK_S:.1f}, got {t[i]:g} (rows must be "
                                   "consecutive 100 ms ticks starting at 0)"))

    levels = data[:, _LEVEL_COLS]
    bad = np.argwhere((levels < -_VALUE_TOL) | (levels > 1 + _VALUE_TOL))
    for i, j in bad[:MAX_PROBLEMS]:
        found.append(ImportProblem(row_numbers[i], CSV_COLUMNS[_LEVEL_COLS[j]],
                                   f"{levels[i, j]:g} is outside 0..1"))
    lo, hi = temp_range
    temp = data[:, _TEMP_COL]
    for i in np.flatnonzero((temp < lo - _VALUE_TOL) | (temp > hi + _VALUE_TOL))[:MAX_PROBLEMS]:
        found.append(ImportProblem(row_numbers[i], TEMPERATURE_COLUMN,
                                   f"{temp[i]:g} is outside {lo:g}..{hi:g} (degrees C, the generator's "
                                   "temp_low..temp_high)"))
    problems.extend(found)
    return data.astype(np.float32)


def _problem_key(p: ImportProblem) -> tuple:
    col = CSV_COLUMNS.index(p.column) if p.column in CSV_COLUMNS else -1
    return (p.row if p.row is not None else -1, col, p.message)


__all__ = ["MAX_PROBLEMS", "ImportProblem", "TimelineImportError", "csv_meta_path", "import_timeline",
           "parse_timeline", "read_csv", "read_csv_meta"]
