"""The chair protocol's messages and constants, mirrored from the C core (``firmware/PROTOCOL.md``
has the specification): what each message holds, with every field range checked on construction
(ParameterError). :mod:`autohaptics.chair.protocol` puts them on the wire.
"""

from __future__ import annotations

import enum
from dataclasses import asdict, dataclass
from typing import Union

from autohaptics.errors import DeviceError, ParameterError

PROTOCOL_VERSION = 1

MSG_HELLO_REQ = 0x01
MSG_HELLO = 0x02
MSG_STATUS_REQ = 0x03
MSG_STATUS = 0x04
MSG_FRAME = 0x10
MSG_STOP = 0x11

N_MOTORS = 9
FAN_ROWS = 9
FAN_COLS = 17
N_FANS = FAN_ROWS * FAN_COLS
NAME_LEN = 16

HEADER_LEN = 4
CRC_LEN = 2
PAYLOAD_LEN = {MSG_HELLO_REQ: 0, MSG_STATUS_REQ: 0, MSG_STOP: 0, MSG_HELLO: 37, MSG_STATUS: 64,
               MSG_FRAME: 4 + 2 + N_MOTORS + 2 + N_FANS}
MAX_PACKET = HEADER_LEN + max(PAYLOAD_LEN.values()) + CRC_LEN  # 176
MAX_ENCODED = MAX_PACKET + (MAX_PACKET + 253) // 254  # 177: longest valid frame before its delimiter

# STATUS flags and safe-state reasons (PROTOCOL.md).
FLAG_SAFE = 0x01
FLAG_STOPPED = 0x02
FLAG_RAMPING = 0x04
FLAG_HAS_TICK = 0x08
SAFE_REASONS = {0: "none", 1: "boot", 2: "watchdog", 3: "stop"}


class Status(enum.IntEnum):
    """Result of decoding a frame; the same numbers as ``ah_status_t`` in the C core."""

    OK = 0
    CRC_ERROR = -1
    LENGTH_ERROR = -2
    OVERFLOW = -3
    VERSION_ERROR = -4
    TYPE_ERROR = -5
    STALE = -6

    @property
    def label(self) -> str:
        return self.name.lower()


class ProtocolError(DeviceError):
    """A frame that cannot be decoded; ``status`` says why."""

    def __init__(self, status: Status, message: str):
        super().__init__(message)
        self.status = status


# ------------------------------------------------------------------------------- messages
@dataclass(frozen=True)
class HelloRequest:
    """Host -> chair: who are you? Also restarts the chair's sequence tracking."""

    type = MSG_HELLO_REQ


@dataclass(frozen=True)
class StatusRequest:
    """Host -> chair: send a STATUS."""

    type = MSG_STATUS_REQ


@dataclass(frozen=True)
class Stop:
    """Host -> chair: every output off now (motors, fans; temperature back to neutral)."""

    type = MSG_STOP


@dataclass(frozen=True)
class Hello:
    """Chair -> host: capabilities. Temperatures in centi-degrees C (``*_cc``)."""

    protocol_version: int = PROTOCOL_VERSION
    firmware_version: tuple[int, int, int] = (0, 1, 0)
    n_actuators: int = N_MOTORS
    fan_rows: int = FAN_ROWS
    fan_cols: int = FAN_COLS
    temp_min_cc: int = 1800
    temp_max_cc: int = 4000
    temp_neutral_cc: int = 3300
    temp_rate_cc_per_s: int = 100
    watchdog_ms: int = 300
    tick_ms: int = 100
    max_packet: int = MAX_PACKET
    name: str = "autohaptics"

    type = MSG_HELLO

    def __post_init__(self) -> None:
        for key in ("protocol_version", "n_actuators", "fan_rows", "fan_cols"):
            check_int(key, getattr(self, key), 0, 0xFF)
        if len(self.firmware_version) != 3:
            raise ParameterError(f"firmware_version needs 3 numbers, got {self.firmware_version!r}")
        for v in self.firmware_version:
            check_int("firmware_version", v, 0, 0xFF)
        for key in ("temp_min_cc", "temp_max_cc", "temp_neutral_cc"):
            check_int(key, getattr(self, key), -0x8000, 0x7FFF)
        for key in ("temp_rate_cc_per_s", "watchdog_ms", "tick_ms", "max_packet"):
            check_int(key, getattr(self, key), 0, 0xFFFF)
        raw = self.name.encode("ascii", "replace")
        if len(raw) > NAME_LEN or b"\x00" in raw:
            raise ParameterError(f"device name {self.name!r} must be at most {NAME_LEN} ASCII bytes")

    temp_min_c = property(lambda self: self.temp_min_cc / 100.0)
    temp_max_c = property(lambda self: self.temp_max_cc / 100.0)
    temp_neutral_c = property(lambda self: self.temp_neutral_cc / 100.0)
    temp_rate_c_per_s = property(lambda self: self.temp_rate_cc_per_s / 100.0)

    def to_dict(self) -> dict:
        d = asdict(self)
        d["firmware_version"] = ".".join(str(v) for v in self.firmware_version)
        d.update(temp_min_c=self.temp_min_c, temp_max_c=self.temp_max_c, temp_neutral_c=self.temp_neutral_c,
                 temp_rate_c_per_s=self.temp_rate_c_per_s)
        return d


@dataclass
class RxCounts:
    """What a protocol parser counts, on either side of the link: packets taken, and those dropped
    by cause (the C core's counters of the same names)."""

    packets_ok: int = 0
    crc_errors: int = 0
    length_errors: int = 0
    overflows: int = 0
    version_errors: int = 0
    type_errors: int = 0


@dataclass
class ChairStatus(RxCounts):
    """Chair -> host: counters and state (the STATUS message); the chair's own receive counters
    are its :class:`RxCounts`."""

    uptime_ms: int = 0
    frames_ok: int = 0
    stale_frames: int = 0
    seq_gaps: int = 0
    late_frames: int = 0
    watchdog_trips: int = 0
    tx_dropped: int = 0
    last_tick: int = 0
    last_seq: int = 0
    flags: int = 0
    safe_reason: int = 0
    temp_target_cc: int = 3300
    temp_setpoint_cc: int = 3300

    type = MSG_STATUS

    def __post_init__(self) -> None:
        for key in STATUS_U32:
            check_int(key, getattr(self, key), 0, 0xFFFFFFFF)
        check_int("last_seq", self.last_seq, 0, 0xFFFF)
        check_int("flags", self.flags, 0, 0xFF)
        check_int("safe_reason", self.safe_reason, 0, 0xFF)
        check_int("temp_target_cc", self.temp_target_cc, -0x8000, 0x7FFF)
        check_int("temp_setpoint_cc", self.temp_setpoint_cc, -0x8000, 0x7FFF)

    @property
    def safe(self) -> bool:
        return bool(self.flags & FLAG_SAFE)

    @property
    def stopped(self) -> bool:
        return bool(self.flags & FLAG_STOPPED)

    def to_dict(self) -> dict:
        d = asdict(self)
        d.update(safe=self.safe, stopped=self.stopped, ramping=bool(self.flags & FLAG_RAMPING),
                 has_tick=bool(self.flags & FLAG_HAS_TICK), safe_reason=SAFE_REASONS.get(self.safe_reason, "unknown"),
                 temp_target_c=self.temp_target_cc / 100.0, temp_setpoint_c=self.temp_setpoint_cc / 100.0)
        return d


STATUS_U32 = ("uptime_ms", "frames_ok", "packets_ok", "crc_errors", "length_errors", "overflows",
               "version_errors", "type_errors", "stale_frames", "seq_gaps", "late_frames", "watchdog_trips",
               "tx_dropped", "last_tick")


@dataclass(frozen=True)
class Frame:
    """Host -> chair: the outputs for one 100 ms tick.

    motors : bytes [9]     A1..A9 intensity, 0..255
    temp_cc: int           temperature target, centi-degrees C (int16)
    fans   : bytes [153]   fan levels 0..255, row-major 9 x 17, row 0 = top, column 0 = left
    seq    : int           per-frame sequence number (u16, wraps); ChairLink assigns it
    """

    tick: int
    motors: bytes = bytes(N_MOTORS)
    temp_cc: int = 3300
    fans: bytes = bytes(N_FANS)
    seq: int = 0

    type = MSG_FRAME

    def __post_init__(self) -> None:
        check_int("tick", self.tick, 0, 0xFFFFFFFF)
        check_int("seq", self.seq, 0, 0xFFFF)
        check_int("temp_cc", self.temp_cc, -0x8000, 0x7FFF)
        object.__setattr__(self, "motors", bytes(self.motors))
        object.__setattr__(self, "fans", bytes(self.fans))
        if len(self.motors) != N_MOTORS:
            raise ParameterError(f"a frame has {N_MOTORS} motor values, got {len(self.motors)}")
        if len(self.fans) != N_FANS:
            raise ParameterError(f"a frame has {N_FANS} fan values (9 x 17), got {len(self.fans)}")


Message = Union[HelloRequest, Hello, StatusRequest, ChairStatus, Frame, Stop]


def check_int(name: str, v: object, lo: int, hi: int) -> None:
    if not isinstance(v, int) or isinstance(v, bool) or not lo <= v <= hi:
        raise ParameterError(f"field {name}={v!r} does not fit its wire type ({lo}..{hi})")
