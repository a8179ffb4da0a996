"""Apple Haptic and Audio Pattern (AHAP) export: a zip of nine patterns, one per actuator.

A Core Haptics pattern drives one haptic engine, so each actuator A1..A9 gets its own file
``A{i}.ahap``; ``manifest.json`` and ``README.txt`` in the zip say which body location each file
belongs to. Mapping (docs/EXPORT.md has the full table):

- Every maximal run of non-zero ticks becomes ``HapticContinuous`` events with
  ``HapticIntensity`` 1.0 and a constant ``HapticSharpness``; silent ticks produce no event.
- A continuous event lasts at most 30 s (Core Haptics' documented limit), so a longer run is
  chained into consecutive events of at most 300 ticks.
- The per-tick level rides on ``HapticIntensityControl`` parameter curves (a multiplier of the
  event intensity), starting with each event. Control points sit on the 100 ms grid and only where
  the slope changes, so linear interpolation reproduces every tick exactly (4 decimals). A curve
  holds at most ``CURVE_MAX_POINTS`` points; longer ones are chained, sharing the joint point.
- No two curves give one instant different values: where a chained event ends, its last curve
  ends on the level the next event starts with (a run's last event ends on its held last tick,
  and the next run starts at least one tick later).
- AHAP requires at least one event per pattern: an actuator silent for the whole film gets one
  continuous event at intensity 0 (it plays nothing).
- Zip entries carry mode 0644 and the export's time (the ``date`` given: that day at 00:00).
"""

from __future__ import annotations

import datetime as _dt
import json
import stat
import zipfile
from collections.abc import Iterator
from typing import IO

import numpy as np

from autohaptics.formats.common import (
    breakpoints,
    ensure_valid,
    export_time,
    fmt_q,
    fmt_ticks_s,
    quantise,
    runs,
    timeline_title,
)
from autohaptics.errors import ParameterError
from autohaptics.layout import ACTUATORS
from autohaptics.timeline import Timeline

EVENT_MAX_S = 30.0  # Core Haptics: "The maximum duration of a continuous haptic event is 30 seconds."
EVENT_MAX_TICKS = 300
CURVE_MAX_POINTS = 16  # conservative cap per parameter curve, see docs/EXPORT.md
DEFAULT_SHARPNESS = 0.5
MANIFEST_FORMAT = "autohaptics.ahap-set"
MANIFEST_VERSION = 1
_FLUSH_CHARS = 1 << 16


def write_ahap_zip(tl: Timeline, fh: IO[bytes], *, sharpness: float = DEFAULT_SHARPNESS,
                   date: str | None = None) -> None:
    """Write the nine per-actuator AHAP patterns, ``manifest.json`` and ``README.txt`` as a zip.

    fh : binary stream (seekable or not). ``sharpness`` : HapticSharpness of every event, 0..1.
    ``date`` : the Metadata "Created" date and the manifest's ``created``, ISO 8601; the zip
    entries are stamped with that day at 00:00 (default: :func:`~autohaptics.formats.common.export_time`).
    """
    tl = ensure_valid(tl)
    sharpness = float(sharpness)
    if not 0.0 <= sharpness <= 1.0:
        raise ParameterError(f"AHAP sharpness must lie in [0, 1], got {sharpness!r}")
    now = export_time(date)
    created = now.date().isoformat()
    title = timeline_title(tl.source)
    q = quantise(tl.vibration)  # (n, 9) int
    files = []
    with zipfile.ZipFile(fh, "w", compression=zipfile.ZIP_DEFLATED) as zf:
        for i, act in enumerate(ACTUATORS):
            counts = {"events": 0, "curves": 0, "control_points": 0}
            name = f"{act.id}.ahap"
            with zf.open(_zip_entry(name, now), "w") as entry:
                _write_buffered(entry, pattern_chunks(q[:, i], actuator=act.id, title=title,
                                                      created=created, sharpness=sharpness,
                                                      counts=counts))
            files.append({
                "file": name, "actuator": act.id, "zone": act.zone, "body": act.body,
                "x": round(act.x, 4), "y": round(act.y, 4),
                "active_ticks": int(np.count_nonzero(q[:, i])), **counts,
            })
        manifest = {
            "format": MANIFEST_FORMAT, "version": MANIFEST_VERSION, "title": title,
            "created": created, "tick_s": tl.tick_s, "n_ticks": int(tl.n_ticks),
            "duration_s": round(tl.duration_s, 4), "sharpness": sharpness,
            "event_intensity": 1.0, "event_max_s": EVENT_MAX_S,
            "curve_parameter": "HapticIntensityControl", "curve_max_points": CURVE_MAX_POINTS,
            "files": files,
        }
        zf.writestr(_zip_entry("manifest.json", now), json.dumps(manifest, indent=1) + "\n")
        zf.writestr(_zip_entry("README.txt", now), _readme(title, tl.n_ticks, sharpness))


def _zip_entry(name: str, when: _dt.datetime) -> zipfile.ZipInfo:
    """A zip member stamped with ``when`` (local time) and mode 0644, so it unpacks readable."""
    info = zipfile.ZipInfo(name, date_time=when.timetuple()[:6])
    info.compress_type = zipfile.ZIP_DEFLATED
    info.create_system = 3  # Unix: unzip tools apply the mode bits below
    info.external_attr = (stat.S_IFREG | 0o644) << 16
    return info


def pattern_chunks(q: np.ndarray, *, actuator: str, title: str, created: str,
                   sharpness: float = DEFAULT_SHARPNESS, counts: dict | None = None) -> Iterator[str]:
    """The AHAP JSON text of one actuator, in pieces.

    q : np.ndarray [shape=(n_ticks,)], int, intensities quantised to 1e-4 (see ``quantise``).
    ``counts`` (optional) is updated with the numbers of events, curves and control points.
    """
    q = np.asarray(q, dtype=np.int64)
    counts = counts if counts is not None else {}
    for key in ("events", "curves", "control_points"):
        counts.setdefault(key, 0)
    body = next((a.body for a in ACTUATORS if a.id == actuator), actuator)
    meta = {
        "Project": "autohaptics",
        "Created": created,
        "Description": (f"{title}: actuator {actuator} ({body}); one continuous event per active "
                        f"stretch of at most {EVENT_MAX_S:g} s, level on HapticIntensityControl "
                        "curves at 100 ms ticks"),
        "Actuator": actuator,
        "TickSeconds": 0.1,
        "Ticks": int(q.shape[0]),
    }
    yield '{\n"Version": 1.0,\n"Metadata": ' + json.dumps(meta) + ',\n"Pattern": ['
    first = True
    sharp = _num(sharpness)
    for start, stop in runs(q != 0):
        for a in range(start, stop, EVENT_MAX_TICKS):
            b = min(stop, a + EVENT_MAX_TICKS)
            yield ("\n" if first else ",\n") + _event(a, b - a, "1.0", sharp)
            first = False
            counts["events"] += 1
            # ticks a..b-1, then at the event's end the level the chained next event starts with
            # (tick b), or at a run's end the last tick held
            seg = np.concatenate([q[a:b], q[b:b + 1] if b < stop else q[b - 1:b]])
            idx = breakpoints(seg)
            for c in range(0, idx.shape[0] - 1, CURVE_MAX_POINTS - 1):
                pts = idx[c:c + CURVE_MAX_POINTS]
                p0 = int(pts[0])
                points = ", ".join(
                    f'{{"Time": {fmt_ticks_s(int(p) - p0)}, "ParameterValue": {fmt_q(seg[p])}}}'
                    for p in pts)
                yield (f',\n{{"ParameterCurve": {{"ParameterID": "HapticIntensityControl", '
                       f'"Time": {fmt_ticks_s(a + p0)}, "ParameterCurveControlPoints": [{points}]}}}}')
                counts["curves"] += 1
                counts["control_points"] += int(pts.shape[0])
    if first:  # silent throughout: one event that plays nothing keeps the pattern valid
        yield "\n" + _event(0, min(int(q.shape[0]), EVENT_MAX_TICKS), "0.0", sharp)
        counts["events"] += 1
    yield "\n]\n}\n"


def _event(start: int, ticks: int, intensity: str, sharp: str) -> str:
    """One ``HapticContinuous`` event from tick ``start`` lasting ``ticks`` ticks (values as JSON text)."""
    return (f'{{"Event": {{"Time": {fmt_ticks_s(start)}, "EventType": "HapticContinuous", '
            f'"EventDuration": {fmt_ticks_s(ticks)}, "EventParameters": ['
            f'{{"ParameterID": "HapticIntensity", "ParameterValue": {intensity}}}, '
            f'{{"ParameterID": "HapticSharpness", "ParameterValue": {sharp}}}]}}}}')


def _num(v: float) -> str:
    return f"{v:.4f}".rstrip("0").rstrip(".") if v else "0"


def _write_buffered(entry: IO[bytes], chunks: Iterator[str]) -> None:
    buf: list[str] = []
    size = 0
    for chunk in chunks:
        buf.append(chunk)
        size += len(chunk)
        if size >= _FLUSH_CHARS:
            entry.write("".join(buf).encode("utf-8"))
            buf, size = [], 0
    if buf:
        entry.write("".join(buf).encode("utf-8"))


def _readme(title: str, n_ticks: int, sharpness: float) -> str:
    lines = [
        f"autohaptics AHAP export of {title}",
        "",
        f"{n_ticks} ticks of 100 ms. One Core Haptics pattern per chair actuator:",
    ]
    lines += [f"  {a.id}.ahap  {a.body} ({a.zone})" for a in ACTUATORS]
    lines += [
        "",
        "Each active stretch is HapticContinuous events (at most 30 s each, chained), intensity 1.0,",
        f"sharpness {sharpness:g}. The level per 100 ms tick is on HapticIntensityControl parameter",
        "curves (linear between control points, at most 16 points per curve). Silence has no events;",
        "an actuator silent for the whole film has one continuous event at intensity 0 (plays nothing).",
        "manifest.json lists the files with their actuator, zone and event counts.",
        "",
    ]
    return "\n".join(lines)
