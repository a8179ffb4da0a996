"""A transport stream's clock: made continuous where it jumps, and its keyframes found by their bytes.

MPEG transport and program streams (a broadcast recording, a Blu-ray's M2TS, a DVD's VOB) carry the
broadcaster's clock, which may jump: two recordings joined (``cat a.ts b.ts``), a channel's splice
into another programme. FFmpeg's demuxer takes a jump back for its clock's wrap (26.5 h on). A player
plays on across such a jump, and FFmpeg's command line takes a step of more than :data:`DISCONTINUITY_S`
as a new clock. The file's time here does the same: the new clock goes on from where what came before
it ends (:func:`continuous_times`).

Such a file has no index, and FFmpeg seeks in it by a search over its bytes that stops near the time
asked for, not at the keyframe before it: the first picture decoded then may come seconds after that
time, or none at all near the end. :func:`read_clock` reads the packets once (no decoding, about 30 ms a
minute of film) and keeps each keyframe's time and byte, so :func:`seek` lands on the keyframe at or
before a time, on a clock that jumps or not.
"""

from __future__ import annotations

import bisect
from array import array
from dataclasses import dataclass

import av
import numpy as np

TRANSPORT_FORMATS = ("mpegts", "mpeg")  # FFmpeg's demuxers of MPEG-TS/M2TS and MPEG-PS/VOB
DISCONTINUITY_S = 10.0  # a step between a stream's packets beyond this is a jump (FFmpeg's dts_delta_threshold)
WRAP_S = 2**33 / 90_000  # the transport stream clock's period, s (33 bits of 90 kHz ticks: 26.5 h)
LOOK_AHEAD = 64  # packets read on from a jump for the new clock's earliest


@dataclass(frozen=True)
class Clock:
    """A transport stream's clock. From byte ``jump_positions[k]`` of the file on, ``jump_offsets_s[k]`` is
    added to every packet's time (positions increasing; none: the clock runs on). ``key_times_s``,
    ``key_positions`` : the time (s, on the continuous clock) and byte position of each keyframe packet
    of the picture, in order."""

    jump_positions: tuple[int, ...] = ()
    jump_offsets_s: tuple[float, ...] = ()
    key_times_s: tuple[float, ...] = ()
    key_positions: tuple[int, ...] = ()

    def offset_at(self, pos: int | None) -> float:
        """Seconds added to the time of a packet at byte ``pos`` (0 before the first jump, or unknown ``pos``)."""
        if not self.jump_positions or pos is None or pos < 0:
            return 0.0
        k = bisect.bisect_right(self.jump_positions, pos) - 1
        return self.jump_offsets_s[k] if k >= 0 else 0.0

    def fix(self, packet: av.Packet) -> None:
        """Put ``packet``'s timestamps on the continuous clock."""
        offset = self.offset_at(packet.pos)
        if offset and packet.time_base:
            ticks = int(round(offset / packet.time_base))
            if packet.pts is not None:
                packet.pts += ticks
            if packet.dts is not None:
                packet.dts += ticks

    def to_dict(self) -> dict:
        """The jumps as JSON (the keyframes left out: they are for seeking, and many)."""
        return {"jump_positions": list(self.jump_positions), "jump_offsets_s": list(self.jump_offsets_s)}


def read_clock(c, streams) -> tuple[Clock, float | None]:
    """(``c``'s clock over ``streams``; the end of their last packet on the continuous clock s, None where
    no packet is timed), demuxing the file from its start.

    The packets are taken in the order of their bytes (a stream's packets are written in the order they
    are decoded; the demuxer gives a long one when it ends), their times made continuous by
    :func:`continuous_times` (a stream without packets for a while, a sound that stops, is no jump)."""
    got = _packets(c, streams)
    if got is None:
        return Clock(), None
    at, t0, dt, keys = got
    times, jumps = continuous_times(t0, dt)
    by_time = np.argsort(times[keys], kind="stable")
    return Clock(tuple(int(at[i]) for i, _ in jumps), tuple(offset for _, offset in jumps),
                 tuple(times[keys][by_time].tolist()), tuple(at[keys][by_time].tolist())), float(np.max(times + dt))


def continuous_times(t0: np.ndarray, dt: np.ndarray) -> tuple[np.ndarray, list[tuple[int, float]]]:
    """Packet times on a continuous clock: ``t0`` their presentation times s and ``dt`` their durations s, each
    [shape=(n,)] in the order of their bytes. Returns (the times s [shape=(n,)], the jumps: (index of the packet
    where a new clock starts, seconds added from it on)). A packet more than :data:`DISCONTINUITY_S` from the
    latest end so far of any stream starts a new clock, its earliest packet going on from there (what came
    before has all been shown: a player plays the first recording to its end, then the second). A step of whole
    :data:`WRAP_S` (within that) is FFmpeg's demuxer taking a clock that fell back for a wrap, only for the
    times under its guess: undone exactly."""
    t0, dt = np.asarray(t0, np.float64), np.asarray(dt, np.float64)
    ends = np.maximum.accumulate(t0 + dt)
    if not np.any(np.abs(t0[1:] - ends[:-1]) > DISCONTINUITY_S):  # the clock runs on (most files)
        return t0.copy(), []
    offset, latest, jumps = 0.0, None, []
    out = np.empty_like(t0)
    for i in range(t0.size):
        t = t0[i] + offset
        if latest is not None and abs(t - latest) > DISCONTINUITY_S:
            wraps = round((t - latest) / WRAP_S)
            if wraps and abs(t - latest - wraps * WRAP_S) <= DISCONTINUITY_S:
                offset -= wraps * WRAP_S  # FFmpeg's guess at a wrap, undone to the tick
            else:  # the new clock's earliest packet among the next few (their bytes' order is not their times')
                ahead = t0[i:i + LOOK_AHEAD]
                offset = latest - float(ahead[np.abs(ahead - t0[i]) <= DISCONTINUITY_S].min())
            t = t0[i] + offset
            jumps.append((i, float(offset)))
        out[i] = t
        latest = t + dt[i] if latest is None else max(latest, t + dt[i])
    return out, jumps


def _packets(c, streams):
    """The timed packets of ``streams`` in ``c`` from its start, in the order of their bytes: (byte
    position int64, presentation time s, duration s, a picture's keyframe bool), each [shape=(n,)]; None
    where there is none."""
    pos, start, length, key = array("q"), array("d"), array("d"), array("b")
    c.seek(0)
    try:
        for p in c.demux(*streams):
            stamp = p.pts if p.pts is not None else p.dts
            if stamp is None or p.time_base is None or p.pos is None or p.pos < 0:
                continue
            pos.append(int(p.pos))
            start.append(float(stamp * p.time_base))
            length.append(float((p.duration or 0) * p.time_base))
            key.append(1 if p.is_keyframe and p.stream.type == "video" else 0)
    except av.error.FFmpegError:
        pass  # a damaged tail: what was read stands
    if not pos:
        return None
    order = np.argsort(np.frombuffer(pos, np.int64), kind="stable")
    return (np.frombuffer(pos, np.int64)[order], np.frombuffer(start, np.float64)[order],
            np.frombuffer(length, np.float64)[order], np.frombuffer(key, np.int8)[order].astype(bool))


def seek(c, stream, clock: Clock | None, t_s: float) -> None:
    """Seek ``c`` to the keyframe of ``stream`` at or before ``t_s`` (s on the file's clock, the container's
    start included): with a ``clock`` that knows the keyframes, to that keyframe's byte."""
    if clock is None or not clock.key_positions:
        if stream.time_base:
            c.seek(int(t_s / stream.time_base), backward=True, any_frame=False, stream=stream)
        return
    k = bisect.bisect_right(clock.key_times_s, t_s) - 1
    c.seek(clock.key_positions[max(k, 0)], unsupported_byte_offset=True)
