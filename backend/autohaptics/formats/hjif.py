"""MPEG-I Haptics (ISO/IEC 23090-31) interchange format export, ``.hjif`` (JSON).

Layout of the file (field names as written by the MPEG reference software's HJIF writer):

- ``version`` "2023", ``profile`` "Main", ``timescale`` 1000: every position is in ms. ``level``
  is the lowest that holds the largest perception: 1 up to 127 channels, else 2 (the wind
  perception has 153 channels, so 2).
- Three perceptions: ``Vibrotactile`` (9 channels, A1..A9), ``Temperature`` (1 channel) and
  ``Wind`` (153 channels, one per fan cell, row-major, row 0 = top). Channel ids are unique across
  the whole file: 0..8 = A1..A9, 9 = temperature, 10 + row * 17 + column = fans.
- Every perception states ``unit_exponent`` -3 and ``perception_unit_exponent`` 0 (what the
  reference writer fills in); the temperature's unit, degrees Celsius, is in its description.
- ``body_part_mask``: bits of the MPEG reference body-part table (``BODY_PART_BITS``).
- Every channel has one ``Curve`` band (``curve_type`` "Linear") whose ``Basis`` effects carry
  keyframes (``relative_position`` in ms, ``amplitude_modulation``) on the 100 ms grid, only where
  the slope changes: linear interpolation between them gives back every tick exactly (4 decimals).
- Vibration and wind: one stretch of effects per run of non-zero ticks, opened and closed by a
  zero keyframe one tick outside the run; no effect at all where the channel is silent.
- Temperature: effects over the whole timeline, amplitude = (T - temp_low) / (temp_high -
  temp_low) in 0..1; the perception description states the two bounds.
- No effect spans more than ``MAX_EFFECT_MS`` or holds more than ``MAX_EFFECT_KEYFRAMES``
  keyframes (the binary form stores both in 16 bits): a longer stretch is consecutive effects
  that share their joint keyframe (same time, same value).
- The last tick's value is held to the end time n x 100 ms (one extra keyframe).
"""

from __future__ import annotations

import json
from collections.abc import Callable, Iterator
from typing import IO

import numpy as np

from autohaptics.errors import ParameterError
from autohaptics.formats.common import (
    MS_PER_TICK,
    QUANTUM,
    breakpoints,
    ensure_valid,
    export_time,
    fmt_q,
    quantise,
    runs,
    timeline_title,
    with_hold,
)
from autohaptics.layout import ACTUATORS, FAN_COLS, FAN_ROWS, N_ACTUATORS
from autohaptics.timeline import Timeline

HJIF_VERSION = "2023"
PROFILE = "Main"
TIMESCALE = 1000  # ticks per second of every position: positions are in ms
MAX_CHANNELS = {1: 127, 2: 65_535}  # channels per perception allowed at each level
UNIT_EXPONENT = -3
PERCEPTION_UNIT_EXPONENT = 0
MAX_EFFECT_MS = 65_535  # an effect's relative positions are 16 bits in the binary form
MAX_EFFECT_KEYFRAMES = 65_535  # so is its keyframe count
_EFFECT_SPAN_TICKS = min(MAX_EFFECT_MS // MS_PER_TICK, MAX_EFFECT_KEYFRAMES - 1)  # 655 ticks

# The MPEG haptics body-part table, bit i = 1 << i, in the order of the reference software's
# enum (MPEGGroup/HapticReferenceSoftware, source/Tools/include/OHMData.h, ``enum class Body``).
BODY_PART_BITS: dict[str, int] = {name: 1 << i for i, name in enumerate((
    "HEAD_FRONT", "HEAD_BACK", "HEAD_RIGHT", "HEAD_LEFT",
    "RIGHT_UPPER_CHEST", "LEFT_UPPER_CHEST", "ABDOMEN", "WAIST", "UPPER_BACK", "LOWER_BACK",
    "RIGHT_UPPERARM", "LEFT_UPPERARM", "RIGHT_FOREARM", "LEFT_FOREARM", "RIGHT_WRIST", "LEFT_WRIST",
    "RIGHT_HAND_PALM", "LEFT_HAND_PALM", "RIGHT_HAND_DORSUM", "LEFT_HAND_DORSUM",
    "RIGHT_HAND_FINGERS", "LEFT_HAND_FINGERS",
    "RIGHT_THIGH", "LEFT_THIGH", "RIGHT_CALF", "LEFT_CALF",
    "RIGHT_FOOT_PALM", "LEFT_FOOT_PALM", "RIGHT_FOOT_DORSUM", "LEFT_FOOT_DORSUM",
    "RIGHT_FOOT_FINGERS", "LEFT_FOOT_FINGERS",
))}

# What each output touches, as body parts of that table (left/right = the sitter's, who faces the
# screen: layout's x = 0 is the sitter's left).
ACTUATOR_BODY_PARTS: dict[str, tuple[str, ...]] = {
    "A1": ("UPPER_BACK",), "A2": ("UPPER_BACK",),
    "A3": ("LEFT_UPPERARM", "LEFT_FOREARM"),
    "A4": ("LOWER_BACK",), "A5": ("LOWER_BACK",), "A6": ("LOWER_BACK",),
    "A7": ("RIGHT_UPPERARM", "RIGHT_FOREARM"),
    "A8": ("LEFT_THIGH",), "A9": ("RIGHT_THIGH",),
}
TEMPERATURE_BODY_PARTS = ("UPPER_BACK", "LOWER_BACK", "RIGHT_THIGH", "LEFT_THIGH")  # back and seat
WIND_BODY_PARTS = ("HEAD_FRONT", "RIGHT_UPPER_CHEST", "LEFT_UPPER_CHEST", "ABDOMEN")  # faces the sitter


def body_part_mask(parts: tuple[str, ...]) -> int:
    """The ``body_part_mask`` of the named body parts (keys of ``BODY_PART_BITS``)."""
    mask = 0
    for part in parts:
        mask |= BODY_PART_BITS[part]
    return mask


ACTUATOR_MASK = {aid: body_part_mask(parts) for aid, parts in ACTUATOR_BODY_PARTS.items()}
TEMPERATURE_MASK = body_part_mask(TEMPERATURE_BODY_PARTS)
WIND_MASK = body_part_mask(WIND_BODY_PARTS)

TEMPERATURE_CHANNEL_ID = N_ACTUATORS  # vibration channels are 0..8
FAN_CHANNEL_BASE = TEMPERATURE_CHANNEL_ID + 1
PERCEPTION_CHANNELS = (N_ACTUATORS, 1, FAN_ROWS * FAN_COLS)
CURVE_UPPER_HZ = 5  # a 10 Hz tick curve carries nothing above 5 Hz


def level_for(channel_counts: tuple[int, ...]) -> int:
    """The lowest HJIF level whose per-perception channel limit holds every count given."""
    most = max(channel_counts, default=0)
    for level, limit in MAX_CHANNELS.items():
        if most <= limit:
            return level
    raise ParameterError(f"{most} channels in one perception exceed the HJIF limit of "
                         f"{MAX_CHANNELS[max(MAX_CHANNELS)]}")


LEVEL = level_for(PERCEPTION_CHANNELS)


def write_hjif(tl: Timeline, fh: IO[str], *, date: str | None = None) -> None:
    """Write ``tl`` as an HJIF document to the text stream ``fh``, channel by channel.

    ``date`` : the ``date`` field, ISO 8601 (default: :func:`~autohaptics.formats.common.export_time`).
    """
    tl = ensure_valid(tl)
    n = tl.n_ticks
    title = timeline_title(tl.source)
    head = {
        "version": HJIF_VERSION,
        "profile": PROFILE,
        "level": LEVEL,
        "date": export_time(date).date().isoformat(),
        "description": (f"autohaptics export of {title}: chair vibration A1..A9, temperature, "
                        f"{FAN_ROWS}x{FAN_COLS} fan grid; {n} ticks of 100 ms"),
        "timescale": TIMESCALE,
        "avatars": [],
    }
    fh.write("{" + ", ".join(f"{json.dumps(k)}: {json.dumps(v)}" for k, v in head.items()))
    fh.write(',\n"perceptions": [\n')

    _perception_open(fh, 0, "Vibrotactile",
                     "Chair vibration motors A1..A9; amplitude = motor intensity 0..1 (unitless)")
    for i, act in enumerate(ACTUATORS):
        qh = with_hold(quantise(tl.vibration[:, i]))  # (n + 1,)
        _channel(fh, i, f"{act.id}: {act.body}", ACTUATOR_MASK[act.id], _onoff_effects(qh), first=i == 0)
    fh.write("\n]},\n")

    lo, hi = tl.temp_range
    qt = with_hold(quantise(tl.temperature_c))  # (n + 1,)
    _perception_open(fh, 1, "Temperature",
                     f"Chair temperature element; unit degrees Celsius: amplitude 0..1 = {lo:g}..{hi:g} "
                     "degrees Celsius (linear)")
    _channel(fh, TEMPERATURE_CHANNEL_ID, "temperature element (back and seat)", TEMPERATURE_MASK,
             _temperature_effects(qt, lo, hi), first=True)
    fh.write("\n]},\n")

    _perception_open(fh, 2, "Wind",
                     f"Fan grid {FAN_ROWS} rows x {FAN_COLS} columns facing the viewer; channel id = "
                     f"{FAN_CHANNEL_BASE} + row * {FAN_COLS} + column (row 0 top, column 0 left); "
                     "amplitude = fan level 0..1 (unitless)")
    for r in range(FAN_ROWS):
        for c in range(FAN_COLS):
            cid = FAN_CHANNEL_BASE + r * FAN_COLS + c
            qh = with_hold(quantise(tl.fans[:, r, c]))  # (n + 1,), one channel at a time
            _channel(fh, cid, f"fan r{r} c{c}", WIND_MASK, _onoff_effects(qh), first=r == c == 0)
    fh.write("\n]}\n],\n")
    fh.write('"syncs": []\n}\n')


def _perception_open(fh: IO[str], pid: int, modality: str, description: str) -> None:
    fh.write("{" + f'"id": {pid}, "avatar_id": 0, "description": {json.dumps(description)}, '
             f'"perception_modality": "{modality}", "unit_exponent": {UNIT_EXPONENT}, '
             f'"perception_unit_exponent": {PERCEPTION_UNIT_EXPONENT}, "reference_devices": [], '
             '"effect_library": [], "channels": [')


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


def _effects(start_tick: int, seg: np.ndarray, amp: Callable[[int], str]) -> Iterator[str]:
    """Effects carrying the samples ``seg`` (one per tick from ``start_tick``), split so that none
    spans more than ``_EFFECT_SPAN_TICKS`` ticks; consecutive pieces share their joint sample."""
    last = max(seg.shape[0] - 1, 1)
    for a in range(0, last, _EFFECT_SPAN_TICKS):
        piece = seg[a:a + _EFFECT_SPAN_TICKS + 1]
        keys = ",".join(
            f'{{"relative_position": {int(p) * MS_PER_TICK}, "amplitude_modulation": {amp(piece[p])}}}'
            for p in breakpoints(piece))
        yield ('{"effect_type": "Basis", "position": ' + str((start_tick + a) * MS_PER_TICK)
               + ', "phase": 0.0, "base_signal": "Sine", "keyframes": [' + keys + "]}")


def _onoff_effects(qh: np.ndarray) -> Iterator[str]:
    """Effects of a 0-means-off channel. qh : [shape=(n_ticks + 1,)], last entry = held value."""
    n = qh.shape[0] - 1
    for s, e in runs(qh[:n] != 0):
        lo = max(s - 1, 0)
        yield from _effects(lo, qh[lo:e + 1], fmt_q)


def _temperature_effects(qh: np.ndarray, lo: float, hi: float) -> Iterator[str]:
    span = hi - lo if hi > lo else 1.0

    def amp(q: int) -> str:
        a = (int(q) / QUANTUM - lo) / span
        return f"{a:.8f}".rstrip("0").rstrip(".") if a else "0"

    yield from _effects(0, qh, amp)
