"""Re-encoding a media file as a distributor would: another size, another codec and bit rate,
another frame rate by repeating frames or by 3:2 pulldown. The known-answer tests and the
benchmarks compare a film's timeline with its re-encode's (the fans must not depend on the encoding).

Frame-rate conversion: ``"repeat"`` shows, at each output time t, the last source frame at or
before t (25 -> 30 fps repeats every fifth frame); ``"pulldown"`` is 2:3 telecine from 24 to 30
fps with interlaced fields, as NTSC video carries film: of every four film frames A B C D come
five frames A B (B top + C bottom) (C top + D bottom) D, the two mixed frames combed where
something moves.
"""

from __future__ import annotations

import os
from fractions import Fraction
from pathlib import Path

import av
import numpy as np

from autohaptics.errors import ParameterError
from autohaptics.media import probe
from autohaptics.testing.encode import CONTAINERS, media_output
from autohaptics.testing.scenes import check_size, fps_fraction

CONVERSIONS = ("repeat", "pulldown")
_PULLDOWN = ((0, 0), (1, 1), (1, 2), (2, 3), (3, 3))  # (top field's film frame, bottom field's) per output frame


def reencode(src: str | os.PathLike, dst: str | os.PathLike, *, width: int | None = None, height: int | None = None,
             fps: float | Fraction | None = None, conversion: str = "repeat", video_codec: str | None = None,
             audio_codec: str | None = None, video_bit_rate: int | None = None,
             audio_bit_rate: int | None = None, video_options: dict[str, str] | None = None) -> Path:
    """Re-encode ``src`` into ``dst`` (container from the suffix, codecs default per container as in
    :func:`~autohaptics.testing.encode.write_scene`) and return ``dst``.

    width, height : output picture size, px (even; default the source's). fps : output frame rate
    (default the source's); conversion : "repeat" or "pulldown" (module docstring; "pulldown" needs
    a 24 fps source and 30 fps out). video_bit_rate, audio_bit_rate : bit/s (default: the encoder's).
    video_options : the video encoder's own options (e.g. ``{"bf": "0"}``: no B-frames).
    The audio is decoded and encoded again (resampled to 48 kHz for Opus).
    """
    info = probe(src)
    if info.video is None:
        raise ParameterError(f"{src}: no video stream to re-encode")
    dst = Path(dst)
    suffix = dst.suffix.lower()
    if suffix not in CONTAINERS or CONTAINERS[suffix][1] is None:
        raise ParameterError(f"{dst}: re-encoding needs a video container, one of "
                             f"{sorted(k for k, v in CONTAINERS.items() if v[1])}")
    if conversion not in CONVERSIONS:
        raise ParameterError(f"conversion must be one of {CONVERSIONS}, got {conversion!r}")
    fmt, v_default, a_default = CONTAINERS[suffix]
    w = int(width or info.video.display_size[0])
    h = int(height or info.video.display_size[1])
    check_size(w, h)
    if w % 2 or h % 2:
        raise ParameterError(f"{dst}: 4:2:0 video needs an even width and height, got {w}x{h}")
    src_rate = fps_fraction(info.video.fps)
    rate = fps_fraction(fps) if fps is not None else src_rate
    if conversion == "pulldown" and (round(float(src_rate), 2) != 24 or round(float(rate), 2) != 30):
        raise ParameterError(f"3:2 pulldown turns 24 fps into 30 fps, got {float(src_rate):g} -> {float(rate):g}")
    with media_output(dst, f"to re-encode {src}") as tmp:
        with av.open(str(src)) as inp, av.open(str(tmp), mode="w", format=fmt) as out:
            vs = out.add_stream(video_codec or v_default, rate=rate)
            vs.width, vs.height, vs.pix_fmt = w, h, "yuv420p"
            if video_bit_rate:
                vs.bit_rate = int(video_bit_rate)
            if video_options:
                vs.options = dict(video_options)
            audio = _audio_stream(inp, out, audio_codec or a_default, audio_bit_rate) if info.audio else None
            frames = _source_frames(inp.streams.video[0], w, h)
            for i, rgb in enumerate(_pulldown(frames) if conversion == "pulldown" else _repeat(frames, rate)):
                frame = av.VideoFrame.from_ndarray(rgb, format="rgb24")
                frame.pts, frame.time_base = i, 1 / rate
                for p in vs.encode(frame):
                    out.mux(p)
            for p in vs.encode(None):
                out.mux(p)
            if audio is not None:
                with av.open(str(src)) as again:
                    _copy_audio(again.streams.audio[0], out, *audio)
    return dst


def _source_frames(stream, width: int, height: int):
    """(time_s, rgb uint8 [shape=(height, width, 3)]) of every decoded source frame, in order."""
    stream.thread_type = "AUTO"
    container = stream.container
    start = float(stream.start_time * stream.time_base) if stream.start_time is not None else 0.0
    for frame in container.decode(stream):
        t = float(frame.time) - start if frame.time is not None else 0.0
        yield t, frame.to_ndarray(width=width, height=height, format="rgb24", interpolation="AREA")


def _repeat(frames, rate: Fraction):
    """At every output time i / rate, the last source frame shown at or before it."""
    i = 0
    prev = None
    for t, rgb in frames:
        while prev is not None and i / rate < t - 1e-6:
            yield prev
            i += 1
        prev = rgb
    if prev is not None:  # the last source frame lasts one source interval at most
        yield prev


def _pulldown(frames):
    """2:3 telecine: five interlaced frames from every four film frames (module docstring)."""
    group: list[np.ndarray] = []
    for _t, rgb in frames:
        group.append(rgb)
        if len(group) == 4:
            for top, bottom in _PULLDOWN:
                img = group[bottom].copy()
                img[0::2] = group[top][0::2]
                yield img
            group = []
    yield from group  # a short last group as it is


def _audio_stream(inp, out, codec: str, bit_rate: int | None):
    """The output audio stream for ``inp``'s first audio stream, and the resampler that feeds it."""
    a_in = inp.streams.audio[0]
    rate = 48000 if codec == "libopus" else a_in.codec_context.sample_rate
    layout = a_in.codec_context.layout.name
    a_out = out.add_stream(codec, rate=rate, layout=layout)
    if bit_rate:
        a_out.bit_rate = int(bit_rate)
    return a_out, av.AudioResampler(format=a_out.codec_context.format.name, layout=layout, rate=rate)


def _copy_audio(a_in, out, a_out, resampler) -> None:
    """Decode the audio stream ``a_in`` and encode it into ``a_out`` of ``out``."""
    for frame in a_in.container.decode(a_in):
        frame.pts = None
        for r in resampler.resample(frame):
            for p in a_out.encode(r):
                out.mux(p)
    for r in resampler.resample(None):
        for p in a_out.encode(r):
            out.mux(p)
    for p in a_out.encode(None):
        out.mux(p)
