"""Helpers shared by the exporters: value quantisation, slope breakpoints, runs, atomic output.

Every exporter works on the timeline's own precision: tracks are stored with 4 decimals
(``Timeline.write``), so values are quantised to integers of 1e-4 first. Breakpoint detection on
those integers is exact, which is what makes the keyframe/curve exports lossless at the tick
sample points (see docs/EXPORT.md, "Keyframes only where the slope changes").
"""

from __future__ import annotations

import dataclasses
import datetime as _dt
import math
import os
import re

import numpy as np

from autohaptics.errors import ParameterError
from autohaptics.layout import ACTUATORS, FAN_COLS, FAN_ROWS, N_ACTUATORS
from autohaptics.temperature.device import played_curve, profile_of
from autohaptics.timebase import TICK_S
from autohaptics.timeline import NORMALISED_FEATURES, Timeline

VALUE_DECIMALS = 4
QUANTUM = 10 ** VALUE_DECIMALS  # values are integers of 1 / QUANTUM
MS_PER_TICK = 100


def quantise(values: np.ndarray) -> np.ndarray:
    """Round ``values`` to 4 decimals and return them as int64 multiples of 1e-4 (same shape)."""
    return np.rint(np.asarray(values, dtype=np.float64) * QUANTUM).astype(np.int64)


def with_hold(q: np.ndarray) -> np.ndarray:
    """Append a copy of the last row: the value of tick n-1 held until the end time n * tick.

    q : np.ndarray [shape=(n_ticks, ...)] -> [shape=(n_ticks + 1, ...)]
    """
    return np.concatenate([q, q[-1:]], axis=0)


def breakpoints(q: np.ndarray) -> np.ndarray:
    """Indices of the samples where a piecewise-linear curve through ``q`` changes slope.

    q : np.ndarray [shape=(n,)], int, samples on an evenly spaced grid.
    Returns int64 indices, first and last always included. Linear interpolation between the
    kept samples reproduces every sample of ``q`` exactly (integer arithmetic, no tolerance).
    """
    q = np.asarray(q, dtype=np.int64)
    n = q.shape[0]
    if n <= 2:
        return np.arange(n, dtype=np.int64)
    bend = q[:-2] - 2 * q[1:-1] + q[2:]
    inner = np.flatnonzero(bend) + 1
    return np.concatenate(([0], inner, [n - 1])).astype(np.int64)


def runs(mask: np.ndarray) -> list[tuple[int, int]]:
    """Maximal runs of True in a 1-D boolean array as half-open ``(start, stop)`` index pairs."""
    m = np.asarray(mask, dtype=bool)
    if not m.any():
        return []
    edges = np.diff(np.concatenate(([0], m.astype(np.int8), [0])))
    starts = np.flatnonzero(edges == 1)
    stops = np.flatnonzero(edges == -1)
    return [(int(a), int(b)) for a, b in zip(starts, stops)]


def fmt_q(q: int) -> str:
    """A quantised value as a short decimal string: 5000 -> '0.5', 0 -> '0', 12345 -> '1.2345'."""
    q = int(q)
    sign = "-" if q < 0 else ""
    whole, frac = divmod(abs(q), QUANTUM)
    if frac == 0:
        return f"{sign}{whole}"
    return f"{sign}{whole}.{frac:0{VALUE_DECIMALS}d}".rstrip("0")


def fmt_ticks_s(ticks: int) -> str:
    """A tick count as seconds with one decimal, exact: 123 -> '12.3'."""
    whole, frac = divmod(int(ticks), 10)
    return f"{whole}.{frac}"


DATE_ENV = "SOURCE_DATE_EPOCH"  # the reproducible-builds convention: seconds since 1970, UTC
_ISO_DATE = re.compile(r"\d{4}-\d{2}-\d{2}")


def export_time(date: str | None = None) -> _dt.datetime:
    """The date and time an export carries (a file's date field, its zip entries' stamps).

    ``date`` (ISO 8601 ``YYYY-MM-DD``) gives that day at 00:00; without it, the instant in
    ``$SOURCE_DATE_EPOCH`` (UTC) where that is set, else now (local time). The one place an
    exporter reads the clock, so an export is reproducible whenever either is given.
    """
    if date is not None:
        text = str(date).strip()
        try:
            if not _ISO_DATE.fullmatch(text):
                raise ValueError
            return _dt.datetime.combine(_dt.date.fromisoformat(text), _dt.time())
        except ValueError:
            raise ParameterError(f"the export date must be an ISO 8601 date YYYY-MM-DD, got {date!r}") from None
    epoch = os.environ.get(DATE_ENV, "").strip()
    if epoch:
        try:
            return _dt.datetime.fromtimestamp(int(epoch), _dt.timezone.utc).replace(tzinfo=None)
        except (ValueError, OverflowError, OSError):
            raise ParameterError(f"{DATE_ENV} must be whole seconds since 1970, got {epoch!r}") from None
    return _dt.datetime.now()


def fan_name(row: int, col: int) -> str:
    """Column name of one fan cell, e.g. ``fan_r3_c4`` (row 0 top, column 0 left)."""
    return f"fan_r{row}_c{col}"


FAN_NAMES: tuple[str, ...] = tuple(fan_name(r, c) for r in range(FAN_ROWS) for c in range(FAN_COLS))
ACTUATOR_BODY = {a.id: a.body for a in ACTUATORS}


def ensure_valid(tl: Timeline) -> Timeline:
    """``tl``, checked for export without copying its tracks.

    A timeline whose tracks are already float32 arrays of the right shapes, finite and inside
    their ranges passes with a few reductions (no float64 copies: a 2-hour fan track is 44 MB).
    Anything else goes through ``Timeline.validate``, which converts, clips the rounding slack
    and raises ParameterError naming the track and index.
    """
    n = tl.n_ticks
    lo, hi = tl.temp_range
    checks = [(tl.vibration, (n, N_ACTUATORS), 0.0, 1.0), (tl.temperature_c, (n,), lo, hi),
              (tl.fans, (n, FAN_ROWS, FAN_COLS), 0.0, 1.0)]
    for name, values in tl.features.items():
        f_lo, f_hi = (0.0, 1.0) if name in NORMALISED_FEATURES else (-np.inf, np.inf)
        checks.append((values, (n,), f_lo, f_hi))
    fast = (isinstance(n, (int, np.integer)) and n >= 1 and math.isclose(float(tl.tick_s), TICK_S)
            and math.isfinite(lo) and math.isfinite(hi) and lo <= hi
            and all(isinstance(d, dict) for d in (tl.source, tl.generator, tl.stats))) and all(
        isinstance(a, np.ndarray) and a.dtype == np.float32 and a.shape == shape
        and bool(np.isfinite(a).all()) and (a.size == 0 or (float(a.min()) >= a_lo and float(a.max()) <= a_hi))
        for a, shape, a_lo, a_hi in checks)
    return tl if fast else tl.validate()


def as_played(tl: Timeline) -> Timeline:
    """``tl`` with its temperature as the chair plays it: clamped to the device's range and
    slew-limited from its neutral point (:func:`~autohaptics.temperature.played_curve`, with the
    profile in ``generator.params.thermal``), kept inside the timeline's own range. A timeline of the
    default mapping already is that curve and comes back as it is; the other tracks are shared."""
    played = played_curve(tl.temperature_c, profile_of(tl.generator.get("params") or {}), tick_s=tl.tick_s)
    lo, hi = tl.temp_range
    played = np.clip(played, lo, hi).astype(np.float32)
    if np.array_equal(played, tl.temperature_c):
        return tl
    return dataclasses.replace(tl, temperature_c=played)


def timeline_title(source: dict) -> str:
    """A short human title for file metadata: the source file name, or 'untitled timeline'."""
    name = source.get("name") if isinstance(source, dict) else None
    return str(name) if name else "untitled timeline"


