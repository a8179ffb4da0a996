"""A film as a recorder holds a broadcast of it: an MPEG transport stream of its packets (as a DVB or ATSC channel
sends H.264 or MPEG-2 with AC-3, AAC or MP2), timed on the broadcaster's clock instead of from 0, begun wherever
the recording started (mid-GOP: the frames before the next keyframe cannot be decoded) and, as a channel's sound
may, with its sound's first packet later than its picture's.

The clock counts 33 bits of 90 kHz ticks, so it wraps every :data:`WRAP_S` (26.5 h): a recording across the wrap
holds times that fall back to 0 in its middle. FFmpeg's demuxer reads the times before the wrap as negative, so
such a file's clock starts below 0.
"""

from __future__ import annotations

import math
import os
from pathlib import Path

import av

from autohaptics.errors import ParameterError

WRAP_S = 2**33 / 90_000  # the transport stream clock's period, s


def as_recording(src: str | os.PathLike, dst: str | os.PathLike, *, clock_s: float = 0.0, begin_s: float = 0.0,
                 sound_late_s: float = 0.0) -> Path:
    """``src``'s first picture and sound streams (codecs a transport stream carries), their packets copied, as
    the MPEG-TS recording ``dst`` (module docstring); returns ``dst``.

    clock_s : the broadcaster's clock at the source's time 0, s (>= 0; within the file's length of a multiple
    of :data:`WRAP_S`, the file's clock wraps inside it). begin_s : where the recording begins on the
    source's time, s: every packet sent from there on, in the order a channel sends them (by decode
    time), whatever frame it holds. sound_late_s : the sound's packets of the first ``sound_late_s`` after
    ``begin_s`` left out (its first packet that much later than the picture's).
    """
    if min(clock_s, begin_s, sound_late_s) < 0:
        raise ParameterError(f"clock_s, begin_s and sound_late_s are >= 0, got {clock_s}, {begin_s}, {sound_late_s}")
    dst = Path(dst)
    with av.open(str(src)) as c:
        if not c.streams.video or not c.streams.audio:
            raise ParameterError(f"{src}: a film with picture and sound is needed")
        packets = [p for p in c.demux(c.streams.video[0], c.streams.audio[0]) if p.size and p.dts is not None]
        packets.sort(key=lambda p: float(p.dts * p.time_base))
        first = {"video": begin_s if begin_s > 0 else -math.inf, "audio": begin_s if begin_s > 0 else -math.inf}
        if sound_late_s > 0:
            first["audio"] = begin_s + sound_late_s
        with av.open(str(dst), "w", format="mpegts") as out:
            streams = {s.index: out.add_stream_from_template(s) for s in (c.streams.video[0], c.streams.audio[0])}
            for p in packets:
                if float(p.dts * p.time_base) < first[p.stream.type]:
                    continue
                shift = int(round(clock_s / p.time_base))  # the muxer keeps the low 33 bits: the clock wraps
                p.pts = None if p.pts is None else p.pts + shift
                p.dts = p.dts + shift
                p.stream = streams[p.stream.index]
                out.mux(p)
    return dst
