"""Encoding a :class:`~autohaptics.testing.scenes.Scene` with PyAV (container from the suffix: .mp4
.mov .mkv .webm .avi .wav .m4a .aac), streaming frame by frame and chunk by chunk: memory does not grow
with the duration, so 2-hour low-resolution files are fine (``long=True``: fastest settings).
"""

from __future__ import annotations

import contextlib
import math
import os
from collections.abc import Iterator
from fractions import Fraction
from pathlib import Path

import av
import numpy as np

from autohaptics.errors import ParameterError
from autohaptics.testing.render import AudioRenderer, iter_frames
from autohaptics.testing.scenes import Scene, check_size, fps_fraction, sample_scene

# suffix -> (FFmpeg muxer, default video codec or None for audio-only, default audio codec)
CONTAINERS: dict[str, tuple[str, str | None, str]] = {
    ".mp4": ("mp4", "libx264", "aac"),
    ".mov": ("mov", "libx264", "aac"),
    ".mkv": ("matroska", "libx264", "aac"),
    ".webm": ("webm", "libvpx", "libopus"),
    ".avi": ("avi", "mpeg4", "pcm_s16le"),
    ".wav": ("wav", None, "pcm_s16le"),
    ".m4a": ("ipod", None, "aac"),
    ".aac": ("adts", None, "aac"),  # raw ADTS: no field for the encoder's priming
}
STANDARD_LAYOUTS = {1: "mono", 2: "stereo", 6: "5.1", 8: "7.1"}
_OPUS_RATES = (8000, 12000, 16000, 24000, 48000)
_PCM_CODECS = ("pcm_s16le", "pcm_s24le", "pcm_s32le", "pcm_f32le")
_AUDIO_CHUNK_S = 0.5


def write_scene(path: str | os.PathLike, scene: Scene, *, width: int = 320, height: int = 180,
                fps: float | Fraction = 24, video_codec: str | None = None,
                audio_codec: str | None = None, sample_rate: int = 48000, channels: int = 2,
                channel_layout: str | None = "auto", video: bool = True, audio: bool = True,
                long: bool = False, quality: str = "high",
                picture: tuple[int, int, int, int] | None = None,
                bar_rgb: tuple[int, int, int] = (0, 0, 0)) -> Path:
    """Encode ``scene`` to ``path`` and return the path.

    The container comes from the suffix (.mp4 .mov .mkv .webm .avi; audio-only .wav .m4a .aac).
    video_codec / audio_codec default per container (libx264 + aac; webm: libvpx + libopus;
    avi: mpeg4 + pcm_s16le; wav: pcm_s16le). ``video=False`` or ``audio=False`` writes a file without
    that stream. channels : 1, 2, 6 or 8 with ``channel_layout="auto"`` (mono, stereo, 5.1, 7.1),
    an explicit FFmpeg layout name, or None for an unlabelled layout ("6 channels", PCM codecs only).
    fps : frames per second (float or Fraction; 23.976 and 29.97 are fine).
    long : fastest encoder settings, for multi-hour files (memory is constant either way).
    quality : "high" (near-lossless, for analysis tests) or "low" (small files, quicker to write:
        x264 at crf 28, AAC with FFmpeg's fast coder at 32 kbit/s per channel).
    picture : (x, y, w, h) px: the scene is rendered w x h and placed there in the width x height
        frame, the rest ``bar_rgb`` (letterbox, pillarbox or windowbox bars; default RGB 0, black);
        default the whole frame.

    Raises ParameterError for impossible combinations (odd sizes with 4:2:0 codecs, Opus at a rate
    other than 8/12/16/24/48 kHz, AAC without a channel layout, no stream at all).
    """
    path = Path(path)
    suffix = path.suffix.lower()
    if suffix not in CONTAINERS:
        raise ParameterError(f"{path}: unknown container suffix {suffix!r}; use one of {sorted(CONTAINERS)}")
    fmt, v_default, a_default = CONTAINERS[suffix]
    want_video = video and v_default is not None
    vcodec = (video_codec or v_default) if want_video else None
    acodec = (audio_codec or a_default) if audio else None
    if vcodec is None and acodec is None:
        raise ParameterError(f"{path}: nothing to write (no video for {suffix} and audio=False)")
    if quality not in ("high", "low"):
        raise ParameterError(f"quality must be 'high' or 'low', got {quality!r}")
    rate = fps_fraction(fps)
    if picture is not None:
        px, py, pw, ph = (int(v) for v in picture)
        if min(px, py) < 0 or min(pw, ph) < 1 or px + pw > width or py + ph > height:
            raise ParameterError(f"{path}: picture {picture} does not fit in the {width}x{height} frame")
    if vcodec is not None:
        check_size(width, height)
        if width % 2 or height % 2:
            raise ParameterError(f"{path}: {vcodec} encodes 4:2:0 video, which needs even width and height; "
                                 f"got {width}x{height}")
    layout = None
    if acodec is not None:
        layout = _audio_layout(channels, channel_layout, acodec, sample_rate, path)
    with media_output(path, f"{vcodec}/{acodec} in {fmt}") as tmp, av.open(str(tmp), mode="w", format=fmt) as out:
        vs = _add_video_stream(out, vcodec, width, height, rate, long, quality) if vcodec else None
        as_ = out.add_stream(acodec, rate=sample_rate, layout=layout) if acodec else None
        if as_ is not None and acodec == "aac" and quality == "low":
            # FFmpeg's default AAC coder (two-loop search, 128 kbit/s stereo) took half the time
            # of writing the 2-hour test film; the "fast" coder at 32 kbit/s per channel takes
            # about a third of that (0.44 instead of 1.22 s per minute of stereo)
            as_.codec_context.options = {"aac_coder": "fast"}
            as_.bit_rate = 32_000 * channels
        _encode(out, scene, vs, as_, width, height, rate, sample_rate, channels, layout, picture, bar_rgb)
    return path


def sample_clip(path: str | os.PathLike, *, width: int = 640, height: int = 360, fps: float = 24,
                **kwargs) -> Path:
    """Write :func:`sample_scene` (10 s) to ``path``; keyword arguments go to :func:`write_scene`."""
    return write_scene(path, sample_scene(), width=width, height=height, fps=fps, **kwargs)


def _audio_layout(channels: int, channel_layout: str | None, codec: str, sample_rate: int, path: Path) -> str:
    if channels < 1:
        raise ParameterError(f"{path}: channels must be >= 1, got {channels}")
    if codec == "libopus" and sample_rate not in _OPUS_RATES:
        raise ParameterError(f"{path}: libopus encodes only at {_OPUS_RATES} Hz, got {sample_rate}")
    if channel_layout is None:
        if codec not in _PCM_CODECS:
            raise ParameterError(f"{path}: an unlabelled {channels}-channel layout needs a PCM codec, not {codec}")
        return f"{channels} channels"
    if channel_layout == "auto":
        if channels not in STANDARD_LAYOUTS:
            raise ParameterError(f"{path}: no standard layout for {channels} channels; "
                                 "pass channel_layout= or None")
        return STANDARD_LAYOUTS[channels]
    n = av.AudioLayout(channel_layout).nb_channels
    if n != channels:
        raise ParameterError(f"{path}: layout {channel_layout!r} has {n} channels, not {channels}")
    return channel_layout


def _add_video_stream(out, codec: str, width: int, height: int, rate: Fraction, long: bool, quality: str):
    vs = out.add_stream(codec, rate=rate)
    vs.width, vs.height = width, height
    vs.pix_fmt = "yuv420p"
    bits = int(width * height * float(rate) * (0.15 if quality == "low" else 1.0))
    if codec == "libx264":
        vs.options = {"crf": "28" if quality == "low" else "12", "preset": "ultrafast" if long else "veryfast"}
    elif codec in ("libvpx", "libvpx-vp9"):
        vs.bit_rate = max(200_000, bits)
        vs.options = {"deadline": "realtime", "cpu-used": "8"} if long else {"deadline": "good", "cpu-used": "4"}
    else:
        vs.bit_rate = max(200_000, bits)
    vs.codec_context.gop_size = max(1, int(round(float(rate) * (10 if long else 2))))
    return vs


def _encode(out, scene: Scene, vs, as_, width, height, rate: Fraction, sample_rate: int, channels: int,
            layout: str | None, picture: tuple[int, int, int, int] | None = None,
            bar_rgb: tuple[int, int, int] = (0, 0, 0)) -> None:
    """Interleave video frames and audio chunks in time order (the muxer's buffers stay small);
    ``picture`` as :func:`write_scene`."""
    arend = AudioRenderer(scene, sample_rate, channels) if as_ is not None else None
    total_a = int(round(scene.duration_s * sample_rate))
    chunk_a = max(1, int(_AUDIO_CHUNK_S * sample_rate))

    def audio_until(t_s: float) -> None:
        while arend.pos < total_a and arend.pos < t_s * sample_rate:
            n = min(chunk_a, total_a - arend.pos)
            pts = arend.pos
            x = arend.next(n)
            # Packed float: PyAV converts to the encoder's sample format and frame size.
            frame = av.AudioFrame.from_ndarray(np.ascontiguousarray(x.T).reshape(1, -1), format="flt",
                                               layout=layout)
            frame.sample_rate = sample_rate
            frame.pts = pts
            frame.time_base = Fraction(1, sample_rate)
            for p in as_.encode(frame):
                out.mux(p)

    if vs is not None:
        px, py, pw, ph = picture if picture is not None else (0, 0, width, height)
        canvas = np.empty((height, width, 3), np.uint8)
        canvas[:] = np.asarray(bar_rgb, np.uint8)
        for i, (t, rgb) in enumerate(iter_frames(scene, width=pw, height=ph, fps=rate)):
            if arend is not None:
                audio_until(t + 1.0)
            if picture is not None:
                canvas[py:py + ph, px:px + pw] = rgb
                rgb = canvas
            frame = av.VideoFrame.from_ndarray(rgb, format="rgb24")
            frame.pts = i
            frame.time_base = 1 / rate
            for p in vs.encode(frame):
                out.mux(p)
    if arend is not None:
        audio_until(math.inf)
        for p in as_.encode(None):
            out.mux(p)
    if vs is not None:
        for p in vs.encode(None):
            out.mux(p)


@contextlib.contextmanager
def media_output(path: Path, what: str) -> Iterator[Path]:
    """A temporary file beside ``path`` to write a media file into: renamed onto ``path`` when the
    block ends, removed when it fails; FFmpeg refusing the job becomes a ParameterError naming
    ``path`` and ``what`` (e.g. the codecs)."""
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_name(path.name + ".part")
    try:
        yield tmp
        os.replace(tmp, path)
    except av.error.FFmpegError as exc:
        tmp.unlink(missing_ok=True)
        raise ParameterError(f"{path}: FFmpeg refused {what}: {exc}") from None
    except BaseException:
        tmp.unlink(missing_ok=True)
        raise


def encode_frames(out, stream, frames) -> None:
    """Encode each of ``frames`` (``av`` frames, timed) into ``stream`` of ``out``, then flush the encoder."""
    for frame in frames:
        for packet in stream.encode(frame):
            out.mux(packet)
    for packet in stream.encode(None):
        out.mux(packet)


def encode_samples(out, stream, x: np.ndarray, *, step: int = 1024) -> None:
    """Encode float samples ``x`` [shape=(channels, n)], -1..1, at ``stream``'s rate and layout into
    ``stream`` of ``out`` from time 0, ``step`` samples a frame, and flush the encoder."""
    rate, layout = stream.codec_context.sample_rate, stream.codec_context.layout.name
    x = np.asarray(x, np.float32)

    def frames():
        for k in range(0, x.shape[1], step):
            frame = av.AudioFrame.from_ndarray(np.ascontiguousarray(x[:, k:k + step]), format="fltp", layout=layout)
            frame.sample_rate, frame.pts, frame.time_base = rate, k, Fraction(1, rate)
            yield frame

    encode_frames(out, stream, frames())
