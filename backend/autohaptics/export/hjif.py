"""MPEG-I Haptics (ISO/IEC 23090-31) interchange format export, ``.hjif`` (JSON).

Layout of the file (field names as written by the MPEG reference software's HJIF writer):

- ``version`` "2023", ``profile`` "Main", ``level`` 2 (the wind perception has 153 channels;
  level 1 allows at most 128 per perception), ``timescale`` 1000: every position is in ms.
- Three perceptions: ``Vibrotactile`` (9 channels, A1..A9), ``Temperature`` (1 channel) and
  ``Wind`` (153 channels, one per fan cell, row-major, row 0 = top).
- Every channel has one ``Curve`` band (``curve_type`` "Linear") whose ``Basis`` effects carry
  keyframes (``relative_position`` in ms, ``amplitude_modulation``). Keyframes sit on the 100 ms
  grid, only where the slope changes: linear interpolation between them gives back every tick
  exactly (4 decimals), so a piecewise-constant or piecewise-linear track costs two keyframes per
  segment whatever its length.
- Vibration and wind: one effect per stretch of non-zero ticks, opened and closed by a zero
  keyframe one tick outside the stretch; no effect at all where the channel is silent.
- Temperature: one effect over the whole timeline, amplitude = (T - temp_low) / (temp_high -
  temp_low) in 0..1; the perception description states the two bounds.
- The last tick's value is held to the end time n x 100 ms (one extra keyframe).
"""

from __future__ import annotations

import datetime as _dt
import json
from collections.abc import Callable, Iterator
from typing import IO

import numpy as np

from autohaptics.export._common import (
    MS_PER_TICK,
    QUANTUM,
    breakpoints,
    ensure_valid,
    fmt_q,
    quantise,
    runs,
    timeline_title,
    with_hold,
)
from autohaptics.layout import ACTUATORS, FAN_COLS, FAN_ROWS
from autohaptics.timeline import Timeline

HJIF_VERSION = "2023"
PROFILE = "Main"
LEVEL = 2
TIMESCALE = 1000  # ticks per second of every position: positions are in ms

# body_part_mask bits assigned by autohaptics (the ISO table was not available; docs/EXPORT.md).
BODY_UPPER_BACK = 1 << 0
BODY_LOWER_BACK = 1 << 1
BODY_LEFT_ARM = 1 << 2
BODY_RIGHT_ARM = 1 << 3
BODY_SEAT = 1 << 4
BODY_FRONT = 1 << 5
ACTUATOR_MASK = {
    "A1": BODY_UPPER_BACK, "A2": BODY_UPPER_BACK,
    "A3": BODY_LEFT_ARM,
    "A4": BODY_LOWER_BACK, "A5": BODY_LOWER_BACK, "A6": BODY_LOWER_BACK,
    "A7": BODY_RIGHT_ARM,
    "A8": BODY_SEAT, "A9": BODY_SEAT,
}
TEMPERATURE_MASK = BODY_UPPER_BACK | BODY_LOWER_BACK | BODY_SEAT
WIND_MASK = BODY_FRONT
CURVE_UPPER_HZ = 5  # a 10 Hz tick curve carries nothing above 5 Hz


def write_hjif(tl: Timeline, fh: IO[str], *, date: str | None = None) -> None:
    """Write ``tl`` as an HJIF document to the text stream ``fh``, channel by channel.

    ``date`` : the ``date`` field (default: today, ISO 8601).
    """
    tl = ensure_valid(tl)
    n = tl.n_ticks
    title = timeline_title(tl.source)
    head = {
        "version": HJIF_VERSION,
        "profile": PROFILE,
        "level": LEVEL,
        "date": date or _dt.date.today().isoformat(),
        "description": (f"autohaptics export of {title}: chair vibration A1..A9, temperature, "
                        f"{FAN_ROWS}x{FAN_COLS} fan grid; {n} ticks of 100 ms"),
        "timescale": TIMESCALE,
        "avatars": [],
    }
    fh.write("{" + ", ".join(f"{json.dumps(k)}: {json.dumps(v)}" for k, v in head.items()))
    fh.write(',\n"perceptions": [\n')

    _perception_open(fh, 0, "Vibrotactile",
                     "Chair vibration motors A1..A9; amplitude = motor intensity 0..1")
    for i, act in enumerate(ACTUATORS):
        qh = with_hold(quantise(tl.vibration[:, i]))  # (n + 1,)
        _channel(fh, i, f"{act.id}: {act.body}", ACTUATOR_MASK[act.id], _onoff_effects(qh), first=i == 0)
    fh.write("\n]},\n")

    lo, hi = tl.temp_range
    qt = with_hold(quantise(tl.temperature_c))  # (n + 1,)
    _perception_open(fh, 1, "Temperature",
                     f"Chair temperature element; amplitude 0..1 = {lo:g}..{hi:g} degrees Celsius "
                     "(linear)")
    _channel(fh, 0, "temperature element (back and seat)", TEMPERATURE_MASK,
             _temperature_effects(qt, lo, hi), first=True)
    fh.write("\n]},\n")

    _perception_open(fh, 2, "Wind",
                     f"Fan grid {FAN_ROWS} rows x {FAN_COLS} columns facing the viewer; channel id = "
                     f"row * {FAN_COLS} + column (row 0 top, column 0 left); amplitude = fan level 0..1")
    for r in range(FAN_ROWS):
        for c in range(FAN_COLS):
            cid = r * FAN_COLS + c
            qh = with_hold(quantise(tl.fans[:, r, c]))  # (n + 1,), one channel at a time
            _channel(fh, cid, f"fan r{r} c{c}", WIND_MASK, _onoff_effects(qh), first=cid == 0)
    fh.write("\n]}\n],\n")
    fh.write('"syncs": []\n}\n')


def _perception_open(fh: IO[str], pid: int, modality: str, description: str) -> None:
    fh.write("{" + f'"id": {pid}, "avatar_id": 0, "description": {json.dumps(description)}, '
             f'"perception_modality": "{modality}", "reference_devices": [], "effect_library": [], '
             '"channels": [')


def _channel(fh: IO[str], cid: int, description: str, mask: int, effects: Iterator[str], *,
             first: bool) -> None:
    fh.write(("\n" if first else ",\n")
             + "{" + f'"id": {cid}, "description": {json.dumps(description)}, "gain": 1.0, '
             f'"mixing_coefficient": 1.0, "body_part_mask": {mask}, "bands": [{{"band_type": "Curve", '
             f'"curve_type": "Linear", "lower_frequency_limit": 0, "upper_frequency_limit": {CURVE_UPPER_HZ}, '
             '"effects": [')
    buf = []
    for i, effect in enumerate(effects):
        buf.append(("\n" if i == 0 else ",\n") + effect)
        if len(buf) >= 256:
            fh.write("".join(buf))
            buf = []
    fh.write("".join(buf) + "]}]}")


def _effect(start_tick: int, seg: np.ndarray, amp: Callable[[int], str]) -> str:
    idx = breakpoints(seg)
    keys = ",".join(
        f'{{"relative_position": {int(p) * MS_PER_TICK}, "amplitude_modulation": {amp(seg[p])}}}'
        for p in idx)
    return ('{"effect_type": "Basis", "position": ' + str(start_tick * MS_PER_TICK)
            + ', "phase": 0.0, "base_signal": "Sine", "keyframes": [' + keys + "]}")


def _onoff_effects(qh: np.ndarray) -> Iterator[str]:
    """Effects of a 0-means-off channel. qh : [shape=(n_ticks + 1,)], last entry = held value."""
    n = qh.shape[0] - 1
    for s, e in runs(qh[:n] != 0):
        lo = max(s - 1, 0)
        yield _effect(lo, qh[lo:e + 1], fmt_q)


def _temperature_effects(qh: np.ndarray, lo: float, hi: float) -> Iterator[str]:
    span = hi - lo if hi > lo else 1.0

    def amp(q: int) -> str:
        a = (int(q) / QUANTUM - lo) / span
        return f"{a:.8f}".rstrip("0").rstrip(".") if a else "0"

    yield _effect(0, qh, amp)
