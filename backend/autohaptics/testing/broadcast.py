"""A film as a recorder holds a broadcast of it: an MPEG transport stream of its packets (as a DVB or ATSC channel
sends H.264 or MPEG-2 with AC-3, AAC or MP2), timed on the broadcaster's clock instead of from 0, begun wherever
the recording started (mid-GOP: the frames before the next keyframe cannot be decoded) and, as a channel's sound
may, with its sound's first packet later than its picture's.

The clock counts 33 bits of 90 kHz ticks, so it wraps every :data:`WRAP_S` (26.5 h): a recording across the wrap
holds times that fall back to 0 in its middle. FFmpeg's demuxer reads the times before the wrap as negative, so
such a file's clock starts below 0.

:func:`as_multiplex` writes a recording of a whole multiplex (several channels' programmes, each on its own clock;
:func:`other_channel` is one). :func:`as_adaptive` writes a recording of an adaptive stream (HLS): the picture at
the renditions a player picks in turn, its size changing from segment to segment. :func:`as_rate_break` writes a
channel's recording whose sound changes sample rate for a stretch (an advertisement break inserted at its own 44.1
kHz), from the sound parts :func:`ac3_packets` encodes each at its own layout and rate.
"""

from __future__ import annotations

import math
import os
from fractions import Fraction
from pathlib import Path

import av
import numpy as np

from autohaptics.errors import ParameterError
from autohaptics.media.clock import WRAP_S
from autohaptics.media.programs import crc32_mpeg, packet_pid


def as_recording(src: str | os.PathLike, dst: str | os.PathLike, *, clock_s: float = 0.0, begin_s: float = 0.0,
                 sound_late_s: float = 0.0, programme: int = 1) -> Path:
    """``src``'s first picture and sound streams (codecs a transport stream carries; a radio programme has sound
    only), their packets copied, as the MPEG-TS recording ``dst`` (module docstring); returns ``dst``.

    clock_s : the broadcaster's clock at the source's time 0, s (>= 0; within the file's length of a multiple
    of :data:`WRAP_S`, the file's clock wraps inside it). begin_s : where the recording begins on the
    source's time, s: every packet sent from there on, in the order a channel sends them (by decode
    time), whatever frame it holds. sound_late_s : the sound's packets of the first ``sound_late_s`` after
    ``begin_s`` left out (its first packet that much later than the picture's). programme : its number in
    the file's tables, which also picks its packet ids (:func:`as_multiplex` joins such files).
    """
    if min(clock_s, begin_s, sound_late_s) < 0:
        raise ParameterError(f"clock_s, begin_s and sound_late_s are >= 0, got {clock_s}, {begin_s}, {sound_late_s}")
    dst = Path(dst)
    with av.open(str(src)) as c:
        if not c.streams.audio:
            raise ParameterError(f"{src}: a film or a radio programme, with sound, is needed")
        kept = [*c.streams.video[:1], c.streams.audio[0]]
        packets = [p for p in c.demux(*kept) if p.size and p.dts is not None]
        packets.sort(key=lambda p: float(p.dts * p.time_base))
        first = {"video": begin_s if begin_s > 0 else -math.inf, "audio": begin_s if begin_s > 0 else -math.inf}
        if sound_late_s > 0:
            first["audio"] = begin_s + sound_late_s
        with av.open(str(dst), "w", format="mpegts", options=_programme_options(programme)) as out:
            streams = {s.index: out.add_stream_from_template(s) for s in kept}
            for p in packets:
                if float(p.dts * p.time_base) < first[p.stream.type]:
                    continue
                shift = int(round(clock_s / p.time_base))  # the muxer keeps the low 33 bits: the clock wraps
                p.pts = None if p.pts is None else p.pts + shift
                p.dts = p.dts + shift
                p.stream = streams[p.stream.index]
                out.mux(p)
    return dst


def as_multiplex(sources, dst: str | os.PathLike, *, clocks_s: tuple[float, ...] | None = None) -> Path:
    """The films (or radio programmes) ``sources`` as a recording of a whole multiplex holds them (a DVB mux's
    channels, an ATSC channel's subchannels): each the programme numbered by its place (1, 2, ...), as
    :func:`as_recording` writes it on its own clock (``clocks_s``, s; default 0 for each), their transport packets
    interleaved by their share of each file, under one association table that lists every programme. Returns
    ``dst``."""
    clocks_s = tuple(clocks_s) if clocks_s is not None else (0.0,) * len(sources)
    if len(sources) < 2 or len(clocks_s) != len(sources):
        raise ParameterError(f"a multiplex needs two or more films, each with a clock, got {len(sources)}, {clocks_s}")
    dst = Path(dst)
    parts = []
    for k, (src, clock_s) in enumerate(zip(sources, clocks_s), start=1):
        one = as_recording(src, dst.with_name(f"{dst.stem}.{k}.ts"), clock_s=clock_s, programme=k)
        data = one.read_bytes()
        one.unlink()
        packets = [data[i:i + 188] for i in range(0, len(data), 188)]
        parts.append([p for p in packets if k == 1 or packet_pid(p) not in (0, 0x11)])  # one table, one SDT
    table = [(k, _map_pid(k)) for k in range(1, len(sources) + 1)]
    out, sent, counter = [], [0] * len(parts), 0
    while any(n < len(p) for n, p in zip(sent, parts)):
        k = min((n / len(p), i) for i, (n, p) in enumerate(zip(sent, parts)) if n < len(p))[1]
        packet = parts[k][sent[k]]
        sent[k] += 1
        if packet_pid(packet) == 0:
            packet, counter = _association_packet(table, counter), counter + 1
        out.append(packet)
    dst.write_bytes(b"".join(out))
    return dst


OTHER_BOOMS_S = (0.8, 3.9, 6.8, 9.9)  # the other channel's events, then every 3 s (none at the matrix scene's)


def other_channel(dst: str | os.PathLike, duration_s: float) -> Path:
    """Another channel's programme for a multiplex (:func:`as_multiplex`), the MP4 ``dst``: ``duration_s`` of
    one red shot (256 x 144, 30 fps) whose 5.1 sound booms at :data:`OTHER_BOOMS_S` and every 3 s after,
    more channels than a stereo film has (the stream FFmpeg's own command line would take)."""
    from autohaptics.testing.encode import write_scene
    from autohaptics.testing.scenes import Scene, Segment, impact

    booms = [t for t in OTHER_BOOMS_S + tuple(12.8 + 3.0 * k for k in range(int(duration_s / 3)))
             if t + 1.0 < duration_s]
    scene = Scene(duration_s, background=[Segment(0.0, duration_s, (200, 60, 40))],
                  audio=[e for t in booms for e in impact(t, level_dbfs=-6.0)])
    return write_scene(dst, scene, width=256, height=144, fps=30, channels=6)


def _programme_options(number: int) -> dict[str, str]:
    """FFmpeg's muxer options that number a programme and give it packet ids of its own (its map's:
    :func:`_map_pid`)."""
    return {"mpegts_service_id": str(number), "mpegts_pmt_start_pid": str(_map_pid(number)),
            "mpegts_start_pid": str(0x100 + 0x20 * (number - 1))}


def _map_pid(number: int) -> int:
    return 0x1000 + 0x10 * (number - 1)


def table_section(table_id: int, number: int, body: bytes) -> bytes:
    """A table section (ISO/IEC 13818-1): ``table_id`` (0 association, 2 programme map), ``number`` (the
    stream's id, or the programme's), version 0, one section, ``body``, then its CRC."""
    head = bytes([table_id]) + (0xB000 | (9 + len(body))).to_bytes(2, "big") + number.to_bytes(2, "big") + b"\xc1\0\0"
    return head + body + crc32_mpeg(head + body).to_bytes(4, "big")


def section_packets(pid: int, section: bytes, *, counter: int = 0, adaptation: int = 0) -> bytes:
    """``section`` in transport packets of ``pid``: the first starts it (pointer 0), after an adaptation field
    of ``adaptation`` bytes where > 0; the rest continue it; stuffing ends the last. ``counter``: the first
    packet's continuity count."""
    out, data = [], bytes([0]) + section
    while data:
        first = not out
        field = bytes([adaptation]) + b"\0" * adaptation if first and adaptation else b""
        room = 184 - len(field)
        head = bytes([0x47, (0x40 if first else 0) | pid >> 8, pid & 0xFF,
                      (0x30 if field else 0x10) | (counter + len(out)) & 0xF])
        out.append(head + field + data[:room] + b"\xff" * max(0, room - len(data)))
        data = data[room:]
    return b"".join(out)


def _association_packet(table, counter: int) -> bytes:
    """One transport packet holding a programme association section: ``table`` (programme number, its map's
    packet id), ``counter`` the packet's continuity count."""
    entries = b"".join(n.to_bytes(2, "big") + (0xE000 | pid).to_bytes(2, "big") for n, pid in table)
    return section_packets(0, table_section(0x00, 1, entries), counter=counter)


def as_adaptive(src: str | os.PathLike, dst: str | os.PathLike, *, scales: tuple[float, ...] = (1.0, 0.5, 0.75, 1 / 3),
                segment_s: float = 6.0, crf: int = 20) -> Path:
    """``src`` as a recording of an adaptive stream (HLS) holds it, the MPEG-TS ``dst``: its picture re-encoded
    (H.264, x264 veryfast at ``crf``) at each of ``scales`` of its size in turn, ``segment_s`` each (the
    rendition a player picks as its bandwidth changes), each segment opening on a keyframe with parameter
    sets of its own; the sound's packets copied (a codec a transport stream carries). Returns ``dst``."""
    if not scales or min(scales) <= 0 or segment_s <= 0:
        raise ParameterError(f"scales are > 0 and segment_s > 0, got {scales}, {segment_s}")
    dst = Path(dst)
    with av.open(str(src)) as c, av.open(str(dst), "w", format="mpegts") as out:
        if not c.streams.video or not c.streams.audio:
            raise ParameterError(f"{src}: a film with picture and sound is needed")
        v_in, a_in = c.streams.video[0], c.streams.audio[0]
        width, height = v_in.codec_context.width, v_in.codec_context.height
        rate = v_in.average_rate or Fraction(25)
        video = out.add_stream("h264", rate=rate)
        video.width, video.height, video.time_base = width, height, _CLOCK
        sound = out.add_stream_from_template(a_in)
        segment, encoder = -1, None
        for packet in c.demux(v_in, a_in):
            if packet.stream.type == "audio":
                if packet.size and packet.dts is not None:
                    packet.stream = sound
                    out.mux(packet)
                continue
            for frame in packet.decode():
                t = max(0.0, float(frame.time or 0.0))
                if encoder is None or int(t // segment_s) != segment:
                    if encoder is not None:
                        _flush(out, video, encoder)
                    segment = int(t // segment_s)
                    s = scales[segment % len(scales)]
                    encoder = _encoder(max(2, round(width * s / 2) * 2), max(2, round(height * s / 2) * 2), rate, crf)
                sized = frame.reformat(width=encoder.width, height=encoder.height, format="yuv420p")
                sized.pts, sized.time_base = int(round(t / _CLOCK)), _CLOCK
                for p in encoder.encode(sized):
                    p.stream = video
                    out.mux(p)
        if encoder is not None:
            _flush(out, video, encoder)
    return dst


_CLOCK = Fraction(1, 90_000)


def _encoder(width: int, height: int, rate: Fraction, crf: int) -> av.CodecContext:
    e = av.CodecContext.create("libx264", "w")
    e.width, e.height, e.pix_fmt, e.time_base, e.framerate = width, height, "yuv420p", _CLOCK, rate
    e.options = {"preset": "veryfast", "crf": str(crf), "repeat-headers": "1"}
    return e


def _flush(out, stream, encoder: av.CodecContext) -> None:
    for p in encoder.encode(None):
        p.stream = stream
        out.mux(p)


def ac3_packets(parts, bit_rate: int = 384_000) -> list:
    """AC-3 packets of sound parts in turn, each ``(samples, layout, rate, start_s)``: float samples
    [shape=(channels, n)] in ``layout``'s order at ``rate`` Hz, starting ``start_s`` s on the clock, each
    part with an encoder of its own (a channel's programme and its advertisements: layout and rate their own)."""
    packets = []
    for x, layout, rate, start_s in parts:
        enc = av.CodecContext.create("ac3", "w")
        enc.sample_rate, enc.layout, enc.format, enc.bit_rate = rate, layout, "fltp", bit_rate
        start = int(round(start_s * rate))
        for k in range(0, x.shape[1], 1536):
            chunk = np.zeros((x.shape[0], 1536), np.float32)
            chunk[:, :min(1536, x.shape[1] - k)] = x[:, k:k + 1536]
            frame = av.AudioFrame.from_ndarray(chunk, format="fltp", layout=layout)
            frame.sample_rate, frame.pts, frame.time_base = rate, start + k, Fraction(1, rate)
            packets += enc.encode(frame)
        packets += enc.encode(None)
    return packets


def as_rate_break(src: str | os.PathLike, dst: str | os.PathLike, *, break_s: tuple[float, float] = (10.0, 20.0),
                  rate: int | None = None) -> Path:
    """``src``'s picture packets copied and its sound (at most 6 channels) as AC-3, the part over ``break_s``
    resampled to ``rate`` Hz (default 44100, or 48000 for a sound at 44.1 kHz) and the rest at its own rate,
    the MPEG-TS ``dst`` (a channel's recording with an advertisement break whose sound keeps its own rate).
    Returns ``dst``."""
    dst = Path(dst)
    with av.open(str(src)) as c:
        if not c.streams.video or not c.streams.audio:
            raise ParameterError(f"{src}: a film with picture and sound is needed")
        v_in, a_in = c.streams.video[0], c.streams.audio[0]
        pictures, decoded = [], []
        for p in c.demux(v_in, a_in):
            if p.stream.type == "audio":
                decoded += p.decode()
            elif p.size and p.dts is not None:
                pictures.append(p)
        if not decoded or decoded[0].layout.nb_channels > 6:
            raise ParameterError(f"{src}: AC-3 needs a sound of 1-6 channels")
        layout, own, t0 = decoded[0].layout.name, decoded[0].sample_rate, float(decoded[0].time or 0.0)
        rate = rate or (48000 if own == 44100 else 44100)
        planar = av.AudioResampler(format="fltp", layout=layout, rate=own)
        x = np.concatenate([g.to_ndarray() for f in decoded for g in planar.resample(f)], axis=1).astype(np.float32)
        i0, i1 = (min(x.shape[1], max(0, int(round((b - t0) * own)))) for b in break_s)
        resampler = av.AudioResampler(format="fltp", layout=layout, rate=rate)
        middle = av.AudioFrame.from_ndarray(np.ascontiguousarray(x[:, i0:i1]), format="fltp", layout=layout)
        middle.sample_rate = own
        out_frames = resampler.resample(middle) + resampler.resample(None)
        mid = np.concatenate([f.to_ndarray() for f in out_frames], axis=1) if out_frames else x[:, :0]
        parts = [(x[:, :i0], layout, own, t0), (mid, layout, rate, t0 + i0 / own),
                 (x[:, i1:], layout, own, t0 + i1 / own)]
        with av.open(str(dst), "w", format="mpegts") as out:
            video, sound = out.add_stream_from_template(v_in), out.add_stream("ac3", rate=own, layout=layout)
            items = [(float(p.pts * p.time_base), p, sound) for p in ac3_packets([q for q in parts if q[0].shape[1]])]
            items += [(float(p.dts * p.time_base), p, video) for p in pictures]
            for _, p, stream in sorted(items, key=lambda item: item[0]):
                p.stream = stream
                out.mux(p)
    return dst

