"""The programmes of a transport stream that carries several (a recording of a whole multiplex: a
DVB mux's channels, an ATSC channel's subchannels), so that the film's picture and sound come from one.

Each programme has its own streams and its own clock. FFmpeg lists every programme's streams as the
file's, one after another, and gives no word of which belongs to which; the file says it in its
tables (ISO/IEC 13818-1 section 2.4.4): the programme association table (packet id 0) names each
programme's map, and each map names its streams' packet ids, which PyAV gives as ``Stream.id``.
:func:`program_pids` reads both from the start of the file (no decoding).
"""

from __future__ import annotations

import os

SYNC = 0x47  # every transport packet's first byte
PACKET_SIZES = (188, 192, 204)  # plain (broadcast), with a 4-byte time before it (M2TS), with 16 bytes of FEC after
READ_LIMIT = 8 << 20  # bytes read at most for the tables (they repeat every 0.1-0.5 s)
CHUNK = 1 << 18  # bytes read at a time
PAT_PID, PAT_TABLE, PMT_TABLE = 0x0000, 0x00, 0x02


def crc32_mpeg(data: bytes) -> int:
    """The CRC-32 that ends every table section (polynomial 0x04C11DB7, register starting at all ones,
    not reflected, no final XOR): 0 over a whole section, its CRC included, when the section is intact."""
    crc = 0xFFFFFFFF
    for byte in data:
        crc ^= byte << 24
        for _ in range(8):
            crc = ((crc << 1) ^ 0x04C11DB7) & 0xFFFFFFFF if crc & 0x80000000 else (crc << 1) & 0xFFFFFFFF
    return crc


def program_pids(path: str | os.PathLike) -> dict[int, tuple[int, ...]]:
    """Each programme of the transport stream ``path`` (its number) and its streams' packet ids, in
    the order the association table lists them; {} where the file is not a transport stream or its
    tables are not found in its first :data:`READ_LIMIT` bytes (intact: a section whose CRC fails is
    passed over for a later copy)."""
    maps: dict[int, int] = {}  # programme number -> its map's packet id
    streams: dict[int, tuple[int, ...]] = {}
    pending: dict[int, bytearray] = {}  # packet id -> the section being gathered
    with open(path, "rb") as f:
        data = f.read(CHUNK)
        found = _layout(data)
        if found is None:
            return {}
        at, size = found
        while not maps or len(streams) < len(maps):
            if at + 188 > len(data):
                more = f.read(CHUNK) if f.tell() < READ_LIMIT else b""
                if not more:
                    break
                at, data = max(0, at - len(data)), data[at:] + more
                continue
            pid, payload = _payload(data[at:at + 188])
            at += size
            if payload is None or (pid != PAT_PID and pid not in maps.values()):
                continue
            for section in _sections(pending, pid, payload):
                if crc32_mpeg(section) != 0:
                    continue
                if section[0] == PAT_TABLE and pid == PAT_PID and not maps:
                    maps = _association(section)
                elif section[0] == PMT_TABLE and pid != PAT_PID:
                    number = int.from_bytes(section[3:5], "big")
                    if maps.get(number) == pid:
                        streams.setdefault(number, _map_streams(section))
    return {number: streams[number] for number in maps if number in streams}


def film_programme(path: str | os.PathLike, c, pictures: set[int]) -> set[int] | None:
    """The indices of the streams of the programme the film is read from in a transport stream of several
    (PyAV's open container ``c`` of ``path``): the first, in the association table's order, that holds one of
    ``pictures`` (indices of streams that are a film's picture, not cover art), else the first; None for any
    other file, every stream of which is the film's. Its streams' clock is the film's."""
    if c.format.name != "mpegts":
        return None
    programmes = program_pids(path)
    if len(programmes) < 2:
        return None
    # each programme's streams (one packet id may carry two: a Blu-ray's TrueHD and its AC-3 core)
    groups = [{s.index for s in c.streams if s.id in pids} for pids in programmes.values()]
    groups = [g for g in groups if g]
    return next((g for g in groups if g & pictures), groups[0]) if groups else None


def packet_pid(packet: bytes) -> int:
    """A transport packet's packet id (13 bits of its second and third bytes)."""
    return ((packet[1] & 0x1F) << 8) | packet[2]


def _layout(data: bytes) -> tuple[int, int] | None:
    """(byte of the first packet's sync byte, packet size) where ``data`` is a run of transport
    packets (ten sync bytes in a row at one of :data:`PACKET_SIZES`), else None."""
    for size in PACKET_SIZES:
        for first in range(min(size, len(data))):
            if all(first + k * size < len(data) and data[first + k * size] == SYNC for k in range(10)):
                return first, size
    return None


def _payload(packet: bytes) -> tuple[int, bytes | None]:
    """(packet id, payload after the adaptation field; None for a packet without one, or damaged),
    the payload starting with its pointer byte when the packet starts a section (flagged by 0x40 in
    its second byte: kept as the payload's first byte for :func:`_sections` as a marker)."""
    if packet[0] != SYNC or packet[1] & 0x80:  # transport error indicator
        return -1, None
    pid = packet_pid(packet)
    control, at = (packet[3] >> 4) & 0x3, 4
    if not control & 0x1:
        return pid, None
    if control & 0x2:
        at += 1 + packet[4]
    if at >= 188:
        return pid, None
    return pid, bytes([packet[1] & 0x40]) + packet[at:]


def _sections(pending: dict[int, bytearray], pid: int, payload: bytes) -> list[bytes]:
    """The whole sections that ``payload`` (a marker byte, then the packet's payload) completes for
    ``pid``, gathering across packets in ``pending``."""
    starts, body = bool(payload[0]), payload[1:]
    done = []
    if starts:
        pointer = body[0]
        if pid in pending:  # the section before ends in the bytes ahead of the pointer
            pending[pid] += body[1:1 + pointer]
            done += _complete(pending, pid)
        pending[pid] = bytearray(body[1 + pointer:])
    elif pid in pending:
        pending[pid] += body
    done += _complete(pending, pid)
    return done


def _complete(pending: dict[int, bytearray], pid: int) -> list[bytes]:
    """The whole sections at the head of ``pending[pid]``, taken out of it (stuffing, 0xFF, ends them)."""
    done, buf = [], pending.get(pid)
    while buf is not None and len(buf) >= 3 and buf[0] != 0xFF:
        length = 3 + (((buf[1] & 0x0F) << 8) | buf[2])
        if len(buf) < length:
            break
        done.append(bytes(buf[:length]))
        del buf[:length]
    if buf is not None and (not buf or buf[0] == 0xFF):  # ended, or stuffing to the packet's end
        del pending[pid]
    return done


def _association(section: bytes) -> dict[int, int]:
    """Programme number -> its map's packet id, from a programme association section (number 0,
    the network's table, left out)."""
    entries = section[8:-4]
    out = {}
    for k in range(0, len(entries) - 3, 4):
        number = int.from_bytes(entries[k:k + 2], "big")
        if number:
            out[number] = int.from_bytes(entries[k + 2:k + 4], "big") & 0x1FFF
    return out


def _map_streams(section: bytes) -> tuple[int, ...]:
    """The packet ids of the streams a programme map section lists, in its order."""
    at = 12 + (int.from_bytes(section[10:12], "big") & 0x0FFF)  # after the programme's descriptors
    out = []
    while at + 5 <= len(section) - 4:
        out.append(int.from_bytes(section[at + 1:at + 3], "big") & 0x1FFF)
        at += 5 + (int.from_bytes(section[at + 3:at + 5], "big") & 0x0FFF)
    return tuple(out)
