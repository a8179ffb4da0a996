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
from collections.abc import Callable, Mapping, Sequence
from typing import Any

import numpy as np

from autohaptics.errors import ParameterError
from autohaptics.timebase import fit_length
from autohaptics.timeline.edit_ops import (
    APPLY,
    MARKER_OPS,
    TRACKS,
    Duration,
    clamp,
    neutral,
    normalise,
    sorted_markers,
    track_of_lane,
)
from autohaptics.timeline.model import Timeline

ImportResolver = Callable[[str], Timeline]


# ------------------------------------------------------------------------- public
def validate_op(op: Any) -> dict:
    """Check one operation and return its normalised form (ints for ticks, floats for values).

    Raises ParameterError naming the operation and the field: unknown op or field, a missing
    field, a wrong type, a non-finite number, an empty or reversed range, an unknown lane.
    """
    return normalise(op)[0]


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
    normalised = [normalise(raw) for raw in ops]
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
                APPLY[op["op"]](tl, by_id, op, parsed, strict)
        except ParameterError as exc:
            where = f"operation {index} ({op['op']})" if len(ops) > 1 else f"op '{op['op']}'"
            raise ParameterError(f"{where}: {exc}") from None
    _check_tracks(tl, set().union(*(tracks_of(op) for op, _ in normalised)) - skip)
    return tl, sorted_markers(by_id)


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
        op, _ = normalise(raw) if not (isinstance(raw, dict) and raw.get("op") == "import") else (raw, None)
        text = json.dumps(op, sort_keys=True, separators=(",", ":"))
        for track in tracks_of(op):
            keys[track].append(text)
    return {t: tuple(v) for t, v in keys.items()}


def _tracks_written(op: dict) -> set[str]:
    """The tracks an operation writes into in place (an import replaces them by new arrays)."""
    if op["op"] == "import":
        return set()
    if op["op"] == "group":
        return set().union(*(_tracks_written(sub) for sub in op["ops"]))
    lanes = list(op.get("lanes", ())) + ([op["lane"]] if "lane" in op else [])
    if op["op"] == "paste":
        lanes += list(op["values"])
    if op["op"] == "temp_points":
        lanes.append("temperature")
    return {track_of_lane(lane) for lane in lanes}


def _restrict(op: dict, parsed: Any, skip: frozenset[str]) -> tuple[dict | None, Any]:
    """``op`` without its effects on the tracks in ``skip`` (None when nothing is left)."""
    if not skip or op["op"] in MARKER_OPS:
        return op, parsed
    if op["op"] == "group":
        kept = [r for r in (_restrict(sub, p, skip) for sub, p in parsed) if r[0] is not None]
        return ({**op, "ops": [sub for sub, _ in kept]}, kept) if kept else (None, None)
    if "lanes" in op:
        lanes = [lane for lane in op["lanes"] if track_of_lane(lane) not in skip]
        return ({**op, "lanes": lanes}, parsed) if lanes else (None, None)
    if op["op"] == "pencil":
        return (op, parsed) if track_of_lane(op["lane"]) not in skip else (None, None)
    if op["op"] == "temp_points":
        return (op, parsed) if "temperature_c" not in skip else (None, None)
    if op["op"] == "paste":
        kept = {lane: v for lane, v in parsed.items() if track_of_lane(lane) not in skip}
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
        temp = fit_length(parsed.temperature_c.astype(np.float64), n, fill=neutral(tl))
        tl.temperature_c = clamp(tl, "temperature", temp).astype(np.float32)
    if "fans" not in skip:
        tl.fans = fit_length(parsed.fans, n, fill=0.0).astype(np.float32)


def fold_markers(ops: Sequence[dict], duration_s: float) -> list[dict]:
    """The markers after ``ops`` on a timeline of ``duration_s`` seconds, exactly as
    :func:`apply_ops` composes them, without touching any track (other ops are skipped)."""
    span = Duration(float(duration_s))
    by_id: dict[str, dict] = {}
    for raw in ops:
        if isinstance(raw, dict) and raw.get("op") in MARKER_OPS:
            op, parsed = normalise(raw)
            APPLY[op["op"]](span, by_id, op, parsed, False)
    return sorted_markers(by_id)


def is_stored_import(op: dict) -> bool:
    """An ``import`` op in its stored form (its document in a file)."""
    return op.get("op") == "import" and "ref" in op


