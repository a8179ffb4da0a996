"""Re-encoding a media file as a distributor would: another size, another codec and bit rate,
another frame rate by repeating frames or by 3:2 pulldown. The known-answer tests and the
benchmarks compare a film's timeline with its re-encode's (the fans must not depend on the encoding).

Frame-rate conversion: ``"repeat"`` shows, at each output time t, the last source frame at or
before t (25 -> 30 fps repeats every fifth frame); ``"pulldown"`` is 2:3 telecine from 24 to 30
fps with interlaced fields, as NTSC video carries film: of every four film frames A B C D come
five frames A B (B top + C bottom) (C top + D bottom) D, the two mixed frames combed where
something moves.

:func:`screener` makes the small, low-quality encode a screener or a streaming service's lowest rung
carries (VP9 crf 32 realtime at 240p, or H.264 crf 32 at 360p; 30 fps; stereo): its block noise is
what the fans must not follow.
"""

from __future__ import annotations

import os
from fractions import Fraction
from pathlib import Path

import av
import numpy as np

from autohaptics.errors import ParameterError
from autohaptics.media import probe
from autohaptics.media.audio import AudioClock, timestamp_slack_s
from autohaptics.testing import grade
from autohaptics.testing.encode import CONTAINERS, encode_frames, media_output
from autohaptics.testing.scenes import check_size, fps_fraction

CONVERSIONS = ("repeat", "pulldown", "vfr")
FITS = ("stretch", "pad", "fill")
PIXEL_FORMATS = ("yuv420p", "yuv420p10le", "yuv422p10le")
AUDIO_TRACKS = ("one", "mono")
_VFR_STEPS = (1, 1, 2, 1, 1, 1, 2, 1, 3, 1, 1, 2)  # source frames from one kept frame to the next
_VFR_TIME_BASE = Fraction(1, 1000)
# a source frame's time may be this much late (Matroska/WebM store times rounded to the millisecond:
# a 24 fps frame at 0.042 s is the one due at 1/24 s, not a reason to repeat the one before it)
_TIME_SLACK_S = 1e-3
_PULLDOWN = ((0, 0), (1, 1), (1, 2), (2, 3), (3, 3))  # (top field's film frame, bottom field's) per output frame
# codec -> (container suffix, video codec, audio codec, default height px, encoder options besides crf)
SCREENERS: dict[str, tuple[str, str, str, int, dict[str, str]]] = {
    "vp9": (".webm", "libvpx-vp9", "libopus", 240, {"deadline": "realtime", "cpu-used": "8", "b": "0"}),
    "h264": (".mp4", "libx264", "aac", 360, {"preset": "veryfast"}),
}


def reencode(src: str | os.PathLike, dst: str | os.PathLike, *, width: int | None = None, height: int | None = None,
             fps: float | Fraction | None = None, conversion: str = "repeat", video_codec: str | None = None,
             audio_codec: str | None = None, video_bit_rate: int | None = None, audio_bit_rate: int | None = None,
             video_options: dict[str, str] | None = None, audio_layout: str | None = None, audio_gain_db: float = 0.0,
             audio_tracks: str = "one", fit: str = "stretch", pix_fmt: str = "yuv420p", transfer: str = "sdr",
             start_s: float = 0.0, duration_s: float | None = None, pixel_aspect: Fraction | None = None) -> Path:
    """Re-encode ``src`` into ``dst`` (container from the suffix, codecs default per container as in
    :func:`~autohaptics.testing.encode.write_scene`) and return ``dst``.

    width, height : output picture size, px (even; default the source's). fps : output frame rate
    (default the source's); conversion : "repeat" or "pulldown" (module docstring; "pulldown" needs
    a 24 fps source and 30 fps out). video_bit_rate, audio_bit_rate : bit/s (default: the encoder's).
    video_options : the video encoder's own options (e.g. ``{"bf": "0"}``: no B-frames).
    audio_layout : the output's channel layout (e.g. "stereo": FFmpeg's downmix; default the source's).
    audio_gain_db : the sound's level against the source's, dB (a quieter or louder mix; samples past
    full scale are clipped where the source's format is an integer one). audio_tracks : "one" stream
    or "mono" (each channel in a mono track, as a master keeps them; a PCM one labelled with its role).
    video_codec "copy" : the video packets as they are (only the sound changes; no other video option).
    fit : how the picture meets ``width`` x ``height``: "stretch" (scaled to it), "pad" (scaled to fit
    inside, centred on black: letterbox, pillarbox or windowbox) or "fill" (scaled to cover, the
    overhang cropped evenly). pix_fmt : "yuv420p", "yuv420p10le" (10-bit) or "yuv422p10le" (a
    ProRes or DNxHR master's 10-bit 4:2:2). transfer : "sdr", or an HDR grade of the picture, "pq"
    (HDR10) or "hlg", 10-bit 4:2:0 (:mod:`autohaptics.testing.grade`). pixel_aspect : the output pixels'
    width / height on screen (default 1; a 16:9 PAL DVD's 720 x 576: 64/45); "pad" and "fill" fit to that.
    start_s, duration_s : the stretch of ``src`` kept, s (a reel cut mid-film; default all of it). A cut
    at the source's rate keeps each frame at its film time from ``start_s`` (the frame on screen there
    first), wherever the cut falls between two frames.
    The audio is decoded and encoded again (resampled to 48 kHz for Opus), its encoder's priming
    marked in the container as FFmpeg's own tools write it (the decoded sound starts where the
    source's did).
    """
    info = probe(src)
    if info.video is None:
        raise ParameterError(f"{src}: no video stream to re-encode")
    dst = Path(dst)
    suffix = dst.suffix.lower()
    if suffix not in CONTAINERS or CONTAINERS[suffix][1] is None:
        raise ParameterError(f"{dst}: re-encoding needs a video container, one of "
                             f"{sorted(k for k, v in CONTAINERS.items() if v[1])}")
    end_s = _checked_options(conversion, fit, pix_fmt, audio_tracks, transfer, start_s, duration_s)
    sar = Fraction(pixel_aspect or 1)
    if not 0.1 <= sar <= 10:
        raise ParameterError(f"pixel_aspect must lie in 0.1..10, got {pixel_aspect!r}")
    fmt, v_default, a_default = CONTAINERS[suffix]
    sound = (audio_codec or a_default, audio_bit_rate, audio_layout, audio_tracks == "mono")
    w = int(width or info.video.display_size[0])
    h = int(height or info.video.display_size[1])
    check_size(w, h)
    if w % 2 or h % 2:
        raise ParameterError(f"{dst}: 4:2:0 video needs an even width and height, got {w}x{h}")
    src_rate = fps_fraction(info.video.fps)
    rate = fps_fraction(fps) if fps is not None else src_rate
    if conversion == "pulldown" and (round(float(src_rate), 2) != 24 or round(float(rate), 2) != 30):
        raise ParameterError(f"3:2 pulldown turns 24 fps into 30 fps, got {float(src_rate):g} -> {float(rate):g}")
    if video_codec == "copy":
        return _copy_video(src, dst, fmt, sound, info, gain_db=audio_gain_db)
    with media_output(dst, f"to re-encode {src}") as tmp:
        with av.open(str(src)) as inp, av.open(str(tmp), mode="w", format=fmt) as out:
            as_shown = conversion == "vfr" or (float(start_s) > 0 and fps is None and conversion == "repeat")
            vs = _video_stream(out, video_codec or v_default, rate, (w, h), pix_fmt, sar=sar, as_shown=as_shown,
                               bit_rate=video_bit_rate, options=video_options, transfer=transfer)
            audio = _audio_stream(inp, out, *sound) if info.audio else None
            v_in = inp.streams.video[0]
            origin = _origin(v_in, info, as_shown)
            frames = _source_frames(v_in, w, h, fit=fit, origin=origin, start_s=float(start_s), end_s=end_s, sar=sar)
            timed = _timed(frames, conversion, rate, as_shown)
            encode_frames(out, vs, (_picture(rgb, pix_fmt, transfer, t) for t, rgb in timed))
            if audio is not None:
                with av.open(str(src)) as again:
                    _copy_audio(again.streams.audio[0], out, *audio, origin=origin, start_s=float(start_s), end_s=end_s,
                                gain_db=audio_gain_db)
    return dst


def _video_stream(out, codec: str, rate: Fraction, size: tuple[int, int], pix_fmt: str, *, sar: Fraction,
                  as_shown: bool, bit_rate: int | None, options: dict | None, transfer: str):
    """:func:`reencode`'s output video stream (``as_shown``: each kept frame at its own time, in ms)."""
    vs = out.add_stream(codec, rate=rate)
    (vs.width, vs.height), vs.pix_fmt = size, pix_fmt
    if sar != 1:
        vs.codec_context.sample_aspect_ratio = sar
    if as_shown:  # a variable rate, or a cut: the picture keeps the film's time
        vs.codec_context.time_base = _VFR_TIME_BASE
    if bit_rate:
        vs.bit_rate = int(bit_rate)
    if options:
        vs.options = dict(options)
    grade.tag(vs.codec_context, transfer)
    return vs


def _picture(rgb: np.ndarray, pix_fmt: str, transfer: str, timing: tuple) -> av.VideoFrame:
    """One output picture from RGB, in ``pix_fmt`` (an HDR grade: :func:`~autohaptics.testing.grade.hdr_frame`),
    at ``timing`` (pts, time base)."""
    if transfer != "sdr":
        frame = grade.hdr_frame(rgb, transfer)
    else:
        frame = av.VideoFrame.from_ndarray(rgb, format="rgb24")
        frame = frame if pix_fmt == "yuv420p" else frame.reformat(format=pix_fmt)
    frame.pts, frame.time_base = timing
    return frame


def _checked_options(conversion: str, fit: str, pix_fmt: str, audio_tracks: str, transfer: str, start_s: float,
                     duration_s: float | None) -> float | None:
    """The end (s) of the stretch :func:`reencode` keeps (None: the source's end); ParameterError for an
    unknown conversion, fit, pixel format, audio tracks or transfer, or a stretch that is not one."""
    if transfer not in grade.TRANSFERS or (transfer != "sdr" and pix_fmt != "yuv420p10le"):
        raise ParameterError(f"transfer must be one of {grade.TRANSFERS} (an HDR grade with pix_fmt "
                             f"'yuv420p10le'), got {transfer!r} with {pix_fmt!r}")
    if conversion not in CONVERSIONS:
        raise ParameterError(f"conversion must be one of {CONVERSIONS}, got {conversion!r}")
    if audio_tracks not in AUDIO_TRACKS:
        raise ParameterError(f"audio_tracks must be one of {AUDIO_TRACKS}, got {audio_tracks!r}")
    if fit not in FITS or pix_fmt not in PIXEL_FORMATS:
        raise ParameterError(f"fit must be one of {FITS} and pix_fmt one of {PIXEL_FORMATS}, got {fit!r}, {pix_fmt!r}")
    end_s = None if duration_s is None else float(start_s) + float(duration_s)
    if not (float(start_s) >= 0 and (end_s is None or end_s > start_s)):
        raise ParameterError(f"the kept stretch needs start_s >= 0 and duration_s > 0, got {start_s!r}, {duration_s!r}")
    return end_s


def _copy_video(src, dst: Path, fmt: str, sound: tuple, info, *, gain_db: float = 0.0) -> Path:
    """``src``'s video packets copied into ``dst``, its sound decoded and encoded again (``sound``:
    :func:`_audio_stream`'s arguments after ``out``)."""
    with media_output(dst, f"to re-encode the sound of {src}") as tmp:
        with av.open(str(src)) as inp, av.open(str(tmp), mode="w", format=fmt) as out:
            v_in = inp.streams.video[0]
            v_out = out.add_stream_from_template(v_in)
            audio = _audio_stream(inp, out, *sound) if info.audio else None
            for packet in inp.demux(v_in):
                if packet.dts is None:
                    continue
                packet.stream = v_out
                out.mux(packet)
            if audio is not None:
                with av.open(str(src)) as again:
                    _copy_audio(again.streams.audio[0], out, *audio, origin=info.start_s, gain_db=gain_db)
    return dst


def screener(src: str | os.PathLike, dst: str | os.PathLike, *, codec: str = "vp9", height: int | None = None,
             crf: int = 32, fps: float = 30) -> Path:
    """Re-encode ``src`` into ``dst`` as a screener: small, 30 fps by repeated frames, stereo, and
    coded at constant quality ``crf`` (32 and up: visible block noise). Returns ``dst``.

    codec : "vp9" (``dst`` .webm: libvpx-vp9, deadline realtime, cpu-used 8, no bit-rate cap;
    Opus) or "h264" (``dst`` .mp4: libx264 veryfast; AAC). height : px, default 240 (vp9) or 360
    (h264); the width keeps the source's aspect, rounded down to even (854x480 -> 426x240, 640x360).
    """
    if codec not in SCREENERS:
        raise ParameterError(f"screener codec must be one of {sorted(SCREENERS)}, got {codec!r}")
    suffix, vcodec, acodec, default_h, options = SCREENERS[codec]
    if Path(dst).suffix.lower() != suffix:
        raise ParameterError(f"{dst}: a {codec} screener is written as {suffix}")
    if not (0 <= int(crf) <= 63):
        raise ParameterError(f"crf must lie in 0..63, got {crf!r}")
    info = probe(src)
    if info.video is None:
        raise ParameterError(f"{src}: no video stream to re-encode")
    h = int(height or default_h)
    sw, sh = info.video.display_size
    w = int(h * sw / sh) // 2 * 2
    return reencode(src, dst, width=w, height=h, fps=fps, video_codec=vcodec, audio_codec=acodec,
                    video_options={**options, "crf": str(int(crf))}, audio_layout="stereo")


def _origin(v_in, info, as_shown: bool) -> float:
    """The source's time (s) that is the output's time 0, for picture and sound: the container's
    start where frames keep their own times (a cut's film time, as ``bench.matrix.cut_analysis``
    reads it), else the source's first picture (one starting a few ms after the container would
    otherwise lag every frame of the output's grid by one)."""
    if as_shown or v_in.start_time is None:
        return info.start_s
    return float(v_in.start_time * v_in.time_base)


def _source_frames(stream, width: int, height: int, *, fit: str = "stretch", origin: float = 0.0,
                   start_s: float = 0.0, end_s: float | None = None, sar: Fraction = Fraction(1)):
    """(time_s from ``start_s``, rgb uint8 [shape=(height, width, 3)]) of every decoded source frame
    shown from ``start_s`` to ``end_s``, in order, fitted as :func:`reencode`'s ``fit`` says (to pixels
    ``sar`` wide). Times count from ``origin`` (s)."""
    stream.thread_type = "AUTO"
    container = stream.container
    held = None  # the last frame before start_s: on screen at the cut
    for frame in container.decode(stream):
        t = (float(frame.time) - origin if frame.time is not None else 0.0) - start_s
        if end_s is not None and t >= end_s - start_s - 1e-6:
            break
        if t < -1e-6:
            held = frame
            continue
        if held is not None and t > 1e-6:
            yield 0.0, _fitted(held, width, height, fit, sar)
        held = None
        yield t, _fitted(frame, width, height, fit, sar)


def _fitted(frame: av.VideoFrame, width: int, height: int, fit: str, sar: Fraction = Fraction(1)) -> np.ndarray:
    """``frame`` as rgb uint8 [shape=(height, width, 3)] of pixels ``sar`` wide: stretched, padded on
    black, or cropped to fill (the source's square pixels fitted to the picture as shown)."""
    if fit == "stretch":
        return frame.to_ndarray(width=width, height=height, format="rgb24", interpolation="AREA")
    scale = (min if fit == "pad" else max)(width * float(sar) / frame.width, height / frame.height)
    w = max(2, int(round(frame.width * scale / float(sar) / 2)) * 2)
    h = max(2, int(round(frame.height * scale / 2)) * 2)
    rgb = frame.to_ndarray(width=w, height=h, format="rgb24", interpolation="AREA")
    out = np.zeros((height, width, 3), np.uint8)
    top, left = (height - h) // 2, (width - w) // 2
    src = rgb[max(0, -top):max(0, -top) + min(h, height), max(0, -left):max(0, -left) + min(w, width)]
    out[max(0, top):max(0, top) + src.shape[0], max(0, left):max(0, left) + src.shape[1]] = src
    return out


def _timed(frames, conversion: str, rate: Fraction, as_shown: bool):
    """((pts, time base), rgb) of each output frame: ``as_shown`` (a variable rate, or a cut at the
    source's rate) at its own time, else on the grid of ``rate`` as ``conversion`` says."""
    if as_shown:
        kept = _vfr(frames) if conversion == "vfr" else frames
        return (((int(round(t / _VFR_TIME_BASE)), _VFR_TIME_BASE), rgb) for t, rgb in kept)
    shown = _pulldown(frames) if conversion == "pulldown" else _repeat(frames, rate)
    return (((i, 1 / rate), rgb) for i, rgb in enumerate(shown))


def _vfr(frames):
    """A variable frame rate: source frames kept at their own times, 1, 2 or 3 source frames apart
    in a fixed irregular pattern (a phone's or a screen recording's stream)."""
    nxt, k = 0, 0
    for i, (t, rgb) in enumerate(frames):
        if i == nxt:
            yield t, rgb
            nxt += _VFR_STEPS[k % len(_VFR_STEPS)]
            k += 1


def _repeat(frames, rate: Fraction):
    """At every output time i / rate, the last source frame shown at or before it (its time within
    ``_TIME_SLACK_S``)."""
    i = 0
    prev = None
    for t, rgb in frames:
        while prev is not None and i / rate < t - _TIME_SLACK_S:
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


def _audio_stream(inp, out, codec: str, bit_rate: int | None, layout: str | None, mono_tracks: bool = False):
    """The output audio stream for ``inp``'s first audio stream (in ``layout``, default its own; with
    ``mono_tracks``, a :class:`_MonoTracks` of its channels), and the resampler that feeds it."""
    a_in = inp.streams.audio[0]
    rate = 48000 if codec == "libopus" else a_in.codec_context.sample_rate
    layout = layout or a_in.codec_context.layout.name
    labelled = codec.startswith("pcm_")  # other encoders take a plain mono layout only
    channels = ([av.AudioLayout(ch.name if labelled else "mono") for ch in av.AudioLayout(layout).channels]
                if mono_tracks else [layout])
    streams = [out.add_stream(codec, rate=rate, layout=ch) for ch in channels]
    fmt = _sample_format(streams[0].codec_context.codec.audio_formats, a_in.codec_context.format)
    for a_out in streams:
        a_out.codec_context.format = fmt
        if bit_rate:
            a_out.bit_rate = int(bit_rate)
    a_out = _MonoTracks(streams) if mono_tracks else streams[0]
    return a_out, av.AudioResampler(format=fmt.name, layout=layout, rate=rate)


class _MonoTracks:
    """Mono output streams, one per channel of a layout, encoded as one stream: :meth:`encode` takes a
    frame of the whole layout and returns every track's packets."""

    def __init__(self, streams: list):
        self.streams = streams
        self.codec_context = streams[0].codec_context

    def encode(self, frame: av.AudioFrame | None) -> list:
        if frame is None:
            return [p for s in self.streams for p in s.encode(None)]
        x = frame.to_ndarray()
        x = x if frame.format.is_planar else x.reshape(frame.samples, len(self.streams)).T
        packets = []
        for k, s in enumerate(self.streams):
            mono = av.AudioFrame.from_ndarray(np.ascontiguousarray(x[k:k + 1]), format=s.codec_context.format.name,
                                              layout=s.codec_context.layout)
            mono.sample_rate, mono.pts, mono.time_base = frame.sample_rate, frame.pts, frame.time_base
            packets += s.encode(mono)
        return packets


def _sample_format(offered, source):
    """The encoder's sample format for ``source``'s samples, as FFmpeg's command line picks it: the
    narrowest of ``offered`` at least as wide as the source's (then the source's planarity, then
    float), else the widest. Why: a downmix into an integer format is normalised against clipping (-7.7 dB for 5.1 ->
    stereo), which a float one is not; ``ffmpeg -ac 2 -c:a libopus`` hands the encoder floats."""
    wide = [f for f in offered if f.bytes >= source.bytes]
    if not wide:
        return max(offered, key=lambda f: f.bytes)
    return min(wide, key=lambda f: (f.bytes, f.is_planar != source.is_planar, f.name.startswith(("s", "u"))))


def _copy_audio(a_in, out, a_out, resampler, *, origin: float = 0.0, start_s: float = 0.0,
                end_s: float | None = None, gain_db: float = 0.0) -> None:
    """Decode the audio stream ``a_in`` and encode its samples from ``start_s`` to ``end_s`` into
    ``a_out`` of ``out``, each at the time the analysis reads it at (``media.audio.AudioClock``),
    counted from ``origin`` (s): a gap before a frame, such as a Vorbis stream's first sound 23 ms
    in, is silence in the output too. gain_db : the level against the source's (:func:`reencode`)."""
    rate = a_in.codec_context.sample_rate
    clock = AudioClock(origin, rate, timestamp_slack_s(a_in.time_base, rate))
    n, pending = 0, None
    for frame in a_in.container.decode(a_in):
        if pending is not None:
            n = _place_audio(clock, pending, frame.time, out, a_out, resampler, n, start_s, end_s)
        pending = _scaled(frame, 10.0 ** (float(gain_db) / 20.0)) if gain_db else frame
        if end_s is not None and frame.time is not None and frame.time - origin > end_s + 1.0:
            break
    if pending is not None:
        n = _place_audio(clock, pending, None, out, a_out, resampler, n, start_s, end_s)
    _encode_audio(resampler.resample(None), out, a_out, n)
    for p in a_out.encode(None):
        out.mux(p)


def _place_audio(clock: AudioClock, frame: av.AudioFrame, t_next: float | None, out, a_out, resampler, n: int,
                 start_s: float, end_s: float | None) -> int:
    """Encode ``frame`` where ``clock`` places it (after the silence of a gap, or cut by an overlap),
    only its part from ``start_s`` to ``end_s``; the next output sample's index."""
    pos = clock.next_s
    shift = clock.offset(frame.time, frame.samples, t_next)
    rate = frame.sample_rate
    parts = [(pos, _silent(frame, shift))] if shift > 0 else []
    parts.append((pos + max(shift, 0) / rate, _trimmed(frame, -shift, frame.samples) if shift < 0 else frame))
    for at, part in parts:
        first = max(0, int(round((start_s - at) * rate)))
        last = part.samples if end_s is None else min(part.samples, int(round((end_s - at) * rate)))
        if last > first:
            part = _trimmed(part, first, last) if first > 0 or last < part.samples else part
            part.pts = None
            n = _encode_audio(resampler.resample(part), out, a_out, n)
    return n


def _encode_audio(frames, out, a_out, n: int) -> int:
    """Encode ``frames`` from sample ``n`` of ``a_out`` on; the next sample's index. Each frame
    carries its own time, so the encoder's priming goes before 0 (marked in the container: an edit
    list, a codec delay) and the decoded sound starts where the source's did."""
    rate = a_out.codec_context.sample_rate
    for r in frames:
        r.pts, r.time_base = n, Fraction(1, rate)
        n += r.samples
        for p in a_out.encode(r):
            out.mux(p)
    return n


def _scaled(frame: av.AudioFrame, gain: float) -> av.AudioFrame:
    """``frame``'s samples times ``gain``, in its format, layout, rate and time (an integer format clipped)."""
    x = frame.to_ndarray()
    y = x.astype(np.float64) * gain
    if np.issubdtype(x.dtype, np.integer):
        info = np.iinfo(x.dtype)
        y = np.clip(np.rint(y), info.min, info.max)
    out = _like(frame, y.astype(x.dtype))
    out.pts, out.time_base = frame.pts, frame.time_base
    return out


def _silent(frame: av.AudioFrame, n: int) -> av.AudioFrame:
    """``n`` samples of silence in ``frame``'s format, layout and rate."""
    x = frame.to_ndarray()
    shape = (x.shape[0], n) if frame.format.is_planar else (1, n * len(frame.layout.channels))
    return _like(frame, np.zeros(shape, x.dtype))


def _trimmed(frame: av.AudioFrame, first: int, last: int) -> av.AudioFrame:
    """Samples ``first:last`` of ``frame`` as a new frame of the same format, layout and rate."""
    x = frame.to_ndarray()
    x = x[:, first:last] if frame.format.is_planar else x[:, first * len(frame.layout.channels):last * len(frame.layout.channels)]
    return _like(frame, np.ascontiguousarray(x))


def _like(frame: av.AudioFrame, x: np.ndarray) -> av.AudioFrame:
    """The samples ``x`` (``frame.to_ndarray()``'s shape convention) as a frame of ``frame``'s format, layout and rate."""
    out = av.AudioFrame.from_ndarray(x, format=frame.format.name, layout=frame.layout.name)
    out.sample_rate = frame.sample_rate
    return out
