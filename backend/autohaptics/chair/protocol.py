"""The chair wire protocol, mirrored from the C core (``firmware/src/proto_wire.c``).

The specification and the frame diagram live in ONE place: ``firmware/PROTOCOL.md``. In short::

    wire   = COBS(packet) 0x00
    packet = version u8 | type u8 | payload length u16 | payload | CRC-16/CCITT-FALSE u16

Every field is little-endian and written one at a time. Both sides check the same byte-level
vectors (``firmware/test/vectors.txt``).

Public pieces: the message dataclasses (:class:`HelloRequest`, :class:`Hello`,
:class:`StatusRequest`, :class:`ChairStatus`, :class:`Frame`, :class:`Stop`), :func:`encode`
(message -> wire bytes), :func:`decode` (one wire frame -> message, raising
:class:`ProtocolError`; building a message with a value its field cannot hold raises
ParameterError), the incremental :class:`Parser`, and :func:`crc16` / :func:`cobs_encode` /
:func:`cobs_decode`.
"""

from __future__ import annotations

from dataclasses import dataclass, field

from autohaptics.chair.messages import (  # noqa: F401  the messages are part of the protocol's API
    CRC_LEN,
    ChairStatus,
    FAN_COLS,
    FAN_ROWS,
    Frame,
    HEADER_LEN,
    Hello,
    HelloRequest,
    MAX_ENCODED,
    MSG_FRAME,
    MSG_HELLO,
    MSG_HELLO_REQ,
    MSG_STATUS,
    MSG_STATUS_REQ,
    MSG_STOP,
    Message,
    NAME_LEN,
    N_FANS,
    N_MOTORS,
    PAYLOAD_LEN,
    PROTOCOL_VERSION,
    ProtocolError,
    STATUS_U32,
    RxCounts,
    Status,
    StatusRequest,
    Stop,
)


# ------------------------------------------------------------------------- field access
class _Writer:
    """Little-endian fields, appended one at a time."""

    def __init__(self) -> None:
        self.buf = bytearray()

    def u8(self, v: int) -> None:
        self.buf.append(v & 0xFF)

    def u16(self, v: int) -> None:
        self.buf += (v & 0xFFFF).to_bytes(2, "little")

    def i16(self, v: int) -> None:
        self.buf += int(v).to_bytes(2, "little", signed=True)

    def u32(self, v: int) -> None:
        self.buf += (v & 0xFFFFFFFF).to_bytes(4, "little")

    def raw(self, b: bytes) -> None:
        self.buf += b


class _Reader:
    def __init__(self, data: bytes) -> None:
        self.data = data
        self.pos = 0

    def _take(self, n: int) -> bytes:
        chunk = self.data[self.pos:self.pos + n]
        if len(chunk) != n:  # payload sizes are checked before reading; this is a guard
            raise ProtocolError(Status.LENGTH_ERROR, "payload shorter than its type needs")
        self.pos += n
        return chunk

    def u8(self) -> int:
        return self._take(1)[0]

    def u16(self) -> int:
        return int.from_bytes(self._take(2), "little")

    def i16(self) -> int:
        return int.from_bytes(self._take(2), "little", signed=True)

    def u32(self) -> int:
        return int.from_bytes(self._take(4), "little")

    def raw(self, n: int) -> bytes:
        return bytes(self._take(n))


# ----------------------------------------------------------------------------- CRC, COBS
def _crc_table() -> tuple[int, ...]:
    table = []
    for i in range(16):
        c = i << 12
        for _ in range(4):
            c = ((c << 1) ^ 0x1021) if c & 0x8000 else (c << 1)
        table.append(c & 0xFFFF)
    return tuple(table)


_CRC_NIBBLE = _crc_table()


def crc16(data: bytes) -> int:
    """CRC-16/CCITT-FALSE (poly 0x1021, init 0xFFFF, no reflection, xorout 0); b"123456789" -> 0x29B1."""
    crc = 0xFFFF
    t = _CRC_NIBBLE
    for b in data:
        crc = ((crc << 4) & 0xFFFF) ^ t[((crc >> 12) ^ (b >> 4)) & 0xF]
        crc = ((crc << 4) & 0xFFFF) ^ t[((crc >> 12) ^ (b & 0xF)) & 0xF]
    return crc


def cobs_encode(data: bytes) -> bytes:
    """COBS-encode ``data`` (no delimiter appended). A full 254-byte run at the very end gets no
    extra code byte (the canonical encoding)."""
    out = bytearray([0])
    code_pos, code = 0, 1
    n = len(data)
    for i, b in enumerate(data):
        if b == 0:
            out[code_pos] = code
            code_pos, code = len(out), 1
            out.append(0)
        else:
            out.append(b)
            code += 1
            if code == 0xFF and i + 1 < n:
                out[code_pos] = code
                code_pos, code = len(out), 1
                out.append(0)
    out[code_pos] = code
    return bytes(out)


def cobs_decode(data: bytes) -> bytes:
    """Decode one COBS frame (without its delimiter); ProtocolError(LENGTH_ERROR) when malformed."""
    out = bytearray()
    i, n = 0, len(data)
    while i < n:
        code = data[i]
        i += 1
        if code == 0:
            raise ProtocolError(Status.LENGTH_ERROR, "zero byte inside a COBS frame")
        run = data[i:i + code - 1]
        if len(run) != code - 1:
            raise ProtocolError(Status.LENGTH_ERROR, f"COBS run of {code - 1} bytes runs past the end of the frame")
        if 0 in run:
            raise ProtocolError(Status.LENGTH_ERROR, "zero byte inside a COBS frame")
        out += run
        i += code - 1
        if code != 0xFF and i < n:
            out.append(0)
    return bytes(out)


# ------------------------------------------------------------------------ encode/decode
def _payload(msg: Message) -> bytes:
    w = _Writer()
    if isinstance(msg, Frame):
        w.u32(msg.tick)
        w.u16(msg.seq)
        w.raw(msg.motors)
        w.i16(msg.temp_cc)
        w.raw(msg.fans)
    elif isinstance(msg, Hello):
        w.u8(msg.protocol_version)
        for v in msg.firmware_version:
            w.u8(v)
        w.u8(msg.n_actuators)
        w.u8(msg.fan_rows)
        w.u8(msg.fan_cols)
        w.i16(msg.temp_min_cc)
        w.i16(msg.temp_max_cc)
        w.i16(msg.temp_neutral_cc)
        w.u16(msg.temp_rate_cc_per_s)
        w.u16(msg.watchdog_ms)
        w.u16(msg.tick_ms)
        w.u16(msg.max_packet)
        w.raw(msg.name.encode("ascii", "replace").ljust(NAME_LEN, b"\x00"))
    elif isinstance(msg, ChairStatus):
        for key in STATUS_U32:
            w.u32(getattr(msg, key))
        w.u16(msg.last_seq)
        w.u8(msg.flags)
        w.u8(msg.safe_reason)
        w.i16(msg.temp_target_cc)
        w.i16(msg.temp_setpoint_cc)
    return bytes(w.buf)


def encode_packet(msg: Message) -> bytes:
    """The packet before COBS: header, payload, CRC."""
    payload = _payload(msg)
    w = _Writer()
    w.u8(PROTOCOL_VERSION)
    w.u8(msg.type)
    w.u16(len(payload))
    w.raw(payload)
    w.u16(crc16(bytes(w.buf)))
    return bytes(w.buf)


def encode(msg: Message) -> bytes:
    """Wire bytes of ``msg``: COBS(packet) followed by the 0x00 delimiter."""
    return cobs_encode(encode_packet(msg)) + b"\x00"


def _read_payload(mtype: int, payload: bytes) -> Message:
    r = _Reader(payload)
    if mtype == MSG_FRAME:
        tick, seq, motors, temp, fans = r.u32(), r.u16(), r.raw(N_MOTORS), r.i16(), r.raw(N_FANS)
        return Frame(tick=tick, seq=seq, motors=motors, temp_cc=temp, fans=fans)
    if mtype == MSG_HELLO:
        pv = r.u8()
        fw = (r.u8(), r.u8(), r.u8())
        na, fr, fc = r.u8(), r.u8(), r.u8()
        tmin, tmax, tneu = r.i16(), r.i16(), r.i16()
        rate, wd, tick_ms, max_packet = r.u16(), r.u16(), r.u16(), r.u16()
        name = r.raw(NAME_LEN).split(b"\x00", 1)[0].decode("ascii", "replace")
        return Hello(protocol_version=pv, firmware_version=fw, n_actuators=na, fan_rows=fr, fan_cols=fc,
                     temp_min_cc=tmin, temp_max_cc=tmax, temp_neutral_cc=tneu, temp_rate_cc_per_s=rate,
                     watchdog_ms=wd, tick_ms=tick_ms, max_packet=max_packet, name=name)
    if mtype == MSG_STATUS:
        values = {key: r.u32() for key in STATUS_U32}
        values.update(last_seq=r.u16(), flags=r.u8(), safe_reason=r.u8(), temp_target_cc=r.i16(),
                      temp_setpoint_cc=r.i16())
        return ChairStatus(**values)
    return {MSG_HELLO_REQ: HelloRequest, MSG_STATUS_REQ: StatusRequest, MSG_STOP: Stop}[mtype]()


def decode_packet(pkt: bytes) -> Message:
    """Validate and decode one packet (COBS removed): length, CRC, version, type, payload size.

    The same checks in the same order as ``ah_decode_packet`` in C; raises ProtocolError.
    """
    n = len(pkt)
    if n < HEADER_LEN + CRC_LEN:
        raise ProtocolError(Status.LENGTH_ERROR, f"packet of {n} bytes is shorter than header and CRC")
    declared = pkt[2] | (pkt[3] << 8)
    if declared != n - HEADER_LEN - CRC_LEN:
        raise ProtocolError(Status.LENGTH_ERROR,
                            f"length field says {declared} payload bytes, the packet holds {n - HEADER_LEN - CRC_LEN}")
    crc = pkt[n - 2] | (pkt[n - 1] << 8)
    if crc != crc16(pkt[:n - CRC_LEN]):
        raise ProtocolError(Status.CRC_ERROR, f"CRC mismatch: packet says 0x{crc:04X}, data gives 0x{crc16(pkt[:n - 2]):04X}")
    if pkt[0] != PROTOCOL_VERSION:
        raise ProtocolError(Status.VERSION_ERROR, f"protocol version {pkt[0]}, this build speaks {PROTOCOL_VERSION}")
    mtype = pkt[1]
    if mtype not in PAYLOAD_LEN:
        raise ProtocolError(Status.TYPE_ERROR, f"unknown message type 0x{mtype:02X}")
    if declared != PAYLOAD_LEN[mtype]:
        raise ProtocolError(Status.LENGTH_ERROR,
                            f"message type 0x{mtype:02X} carries {PAYLOAD_LEN[mtype]} payload bytes, got {declared}")
    return _read_payload(mtype, bytes(pkt[HEADER_LEN:n - CRC_LEN]))


def decode(wire: bytes) -> Message:
    """Decode exactly one wire frame (with or without its trailing 0x00 delimiter)."""
    data = bytes(wire)
    if data.endswith(b"\x00"):
        data = data[:-1]
    if b"\x00" in data:
        raise ProtocolError(Status.LENGTH_ERROR, "more than one frame: a 0x00 delimiter inside the data")
    if len(data) > MAX_ENCODED:
        raise ProtocolError(Status.OVERFLOW, f"frame of {len(data)} encoded bytes exceeds {MAX_ENCODED}")
    return decode_packet(cobs_decode(data))


# --------------------------------------------------------------------------------- parser
@dataclass
class RxCounters(RxCounts):
    """The host parser's counts (:class:`~autohaptics.chair.messages.RxCounts`)."""

    def count(self, status: Status) -> None:
        key = {Status.OK: "packets_ok", Status.CRC_ERROR: "crc_errors", Status.LENGTH_ERROR: "length_errors",
               Status.OVERFLOW: "overflows", Status.VERSION_ERROR: "version_errors",
               Status.TYPE_ERROR: "type_errors"}.get(status)
        if key:
            setattr(self, key, getattr(self, key) + 1)


@dataclass(frozen=True)
class Parsed:
    """One complete frame from the byte stream: a message, or the status that dropped it."""

    status: Status
    message: Message | None = None
    error: str = ""


@dataclass
class Parser:
    """Incremental parser with the C parser's semantics: feed any bytes, get every completed frame.

    Memory stays bounded: at most ``MAX_ENCODED`` bytes of an unfinished frame are kept; a longer
    one is dropped whole and reported as OVERFLOW at its delimiter. Empty frames (repeated
    delimiters) are skipped silently.
    """

    counters: RxCounters = field(default_factory=RxCounters)
    _buf: bytearray = field(default_factory=bytearray, repr=False)
    _overflowed: bool = False

    @property
    def pending(self) -> int:
        """Bytes of the unfinished frame held (never more than MAX_ENCODED)."""
        return len(self._buf)

    def feed(self, data: bytes) -> list[Parsed]:
        out: list[Parsed] = []
        data = bytes(data)
        start = 0
        n = len(data)
        while start < n:
            end = data.find(b"\x00", start)
            chunk = data[start:n if end < 0 else end]
            if not self._overflowed:
                room = MAX_ENCODED - len(self._buf)
                if len(chunk) > room:
                    self._overflowed = True
                    self._buf.clear()
                else:
                    self._buf += chunk
            if end < 0:
                break
            out_item = self._end_of_frame()
            if out_item is not None:
                self.counters.count(out_item.status)
                out.append(out_item)
            start = end + 1
        return out

    def _end_of_frame(self) -> Parsed | None:
        if self._overflowed:
            self._overflowed = False
            self._buf.clear()
            return Parsed(Status.OVERFLOW, None, f"frame longer than {MAX_ENCODED} bytes")
        if not self._buf:
            return None
        data = bytes(self._buf)
        self._buf.clear()
        try:
            return Parsed(Status.OK, decode_packet(cobs_decode(data)))
        except ProtocolError as exc:
            return Parsed(exc.status, None, str(exc))
