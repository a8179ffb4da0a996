"""Synthetic scenes with known answers: a small renderer and encoder for tests, benchmarks and demos.

A :class:`Scene` describes a clip in normalised coordinates (x to the right, y downward, both in
[0, 1] of the frame width and height) and in seconds, so the same scene rendered at 320x180 @ 24 fps
and at 1280x720 @ 30 fps shows the same picture at the same instants:

- ``background``: :class:`Segment` s, each ``[t0, t1)`` with a colour (optionally fading to
  ``rgb_end``), an optional :class:`Texture` and a pan velocity. A boundary where one segment ends
  and a different one starts is a hard cut (:meth:`Scene.cut_times`). Time not covered is black.
- ``shapes``: :class:`Shape` s (rect or circle) shown during ``[t_on, t_off)``, moving linearly from
  ``xy0`` to ``xy1`` and growing from ``size0`` to ``size1`` ("moving toward the camera" = growing),
  optionally blinking and textured (the texture is attached to the shape and scales with it, so
  optical flow sees a true expansion).
- ``audio``: :class:`Tone` and :class:`Noise` bursts; silence elsewhere.

Levels are dBFS RMS: ``20 log10(rms)`` of the samples in each channel that plays the event, with
full scale = 1.0 (a 0 dBFS RMS sine peaks at 1.414 and clips). The mix is clipped to [-1, 1].

Rendering is exact at pixel centres ``((i + 0.5) / width, (j + 0.5) / height)`` with analytic
anti-aliased edges; textures are smooth value noise, checkers or stripes with features measured in
frame widths, so they look the same at every resolution.

:func:`write_scene` encodes with PyAV (container from the suffix: .mp4 .mov .mkv .webm .avi .wav
.m4a), streaming frame by frame and chunk by chunk: memory does not grow with the duration, so
2-hour low-resolution files are fine (``long=True`` picks the fastest encoder settings).
:func:`sample_clip` writes the README's 10 s demonstration scene.
"""

from __future__ import annotations

import math
import os
from collections.abc import Iterator, Sequence
from dataclasses import dataclass
from fractions import Fraction
from pathlib import Path

import av
import numpy as np
from scipy.signal import lfilter

from autohaptics.errors import ParameterError

RGB = tuple[int, int, int]

# suffix -> (FFmpeg muxer, default video codec or None for audio-only, default audio codec)
CONTAINERS: dict[str, tuple[str, str | None, str]] = {
    ".mp4": ("mp4", "libx264", "aac"),
    ".mov": ("mov", "libx264", "aac"),
    ".mkv": ("matroska", "libx264", "aac"),
    ".webm": ("webm", "libvpx", "libopus"),
    ".avi": ("avi", "mpeg4", "pcm_s16le"),
    ".wav": ("wav", None, "pcm_s16le"),
    ".m4a": ("ipod", None, "aac"),
}
STANDARD_LAYOUTS = {1: "mono", 2: "stereo", 6: "5.1", 8: "7.1"}
_OPUS_RATES = (8000, 12000, 16000, 24000, 48000)
_PCM_CODECS = ("pcm_s16le", "pcm_s24le", "pcm_s32le", "pcm_f32le")
_AUDIO_CHUNK_S = 0.5
# Pink noise: Julius O. Smith's 1/f approximation (3 poles, 3 zeros), +-0.3 dB over the audio band.
_PINK_B = np.array([0.049922035, -0.095993537, 0.050612699, -0.004408786])
_PINK_A = np.array([1.0, -2.494956002, 2.017265875, -0.522189400])


# ------------------------------------------------------------------- scene description
@dataclass(frozen=True)
class Texture:
    """A smooth grey pattern that modulates a colour (gives optical flow something to track).

    kind : "noise" (smooth value noise) | "checker" | "stripes" (vertical bars).
    scale : feature size; frame widths for a background, the shape's width for a shape.
    contrast : modulation depth 0..1; pixel = colour * (1 + contrast * (2 p - 1)), p in [0, 1].
    seed : random lattice of the noise.
    """

    kind: str = "noise"
    scale: float = 0.05
    contrast: float = 0.5
    seed: int = 0

    def __post_init__(self):
        if self.kind not in ("noise", "checker", "stripes"):
            raise ParameterError(f"texture kind must be noise, checker or stripes, got {self.kind!r}")
        if not (self.scale > 0 and math.isfinite(self.scale)):
            raise ParameterError(f"texture scale must be > 0, got {self.scale!r}")
        if not 0.0 <= self.contrast <= 1.0:
            raise ParameterError(f"texture contrast must be in [0, 1], got {self.contrast!r}")


@dataclass(frozen=True)
class Segment:
    """Background during ``[t0, t1)`` seconds.

    rgb : colour 0..255; rgb_end : if given, the colour fades linearly to it over the segment.
    texture : optional :class:`Texture`; pan : texture drift (vx, vy) in frame widths per second
    (a camera pan moves the picture the other way).
    """

    t0: float
    t1: float
    rgb: RGB
    rgb_end: RGB | None = None
    texture: Texture | None = None
    pan: tuple[float, float] = (0.0, 0.0)

    def __post_init__(self):
        _check_interval(self.t0, self.t1, "segment")
        object.__setattr__(self, "rgb", _check_rgb(self.rgb))
        if self.rgb_end is not None:
            object.__setattr__(self, "rgb_end", _check_rgb(self.rgb_end))
        object.__setattr__(self, "pan", (float(self.pan[0]), float(self.pan[1])))


@dataclass(frozen=True)
class Shape:
    """A rectangle or an ellipse ("circle") shown during ``[t_on, t_off)`` seconds.

    xy0, xy1 : centre at the start and end of the move, normalised (x, y) in frame width / height.
    size0, size1 : (width, height) as fractions of the frame width and height at the start and end
    (a circle of size (0.1, 0.1) is an ellipse on a non-square frame).
    move_t0, move_t1 : the move's interval in seconds (default t_on .. t_off, or the scene's end);
    position and size are linear in time inside it and held outside.
    blink_hz : 0 = steady; otherwise shown during the first half of every 1 / blink_hz period.
    """

    kind: str = "rect"
    rgb: RGB = (255, 255, 255)
    t_on: float = 0.0
    t_off: float = math.inf
    xy0: tuple[float, float] = (0.5, 0.5)
    xy1: tuple[float, float] | None = None
    size0: tuple[float, float] = (0.1, 0.1)
    size1: tuple[float, float] | None = None
    move_t0: float | None = None
    move_t1: float | None = None
    texture: Texture | None = None
    blink_hz: float = 0.0

    def __post_init__(self):
        if self.kind not in ("rect", "circle"):
            raise ParameterError(f"shape kind must be rect or circle, got {self.kind!r}")
        if not (self.t_off > self.t_on):
            raise ParameterError(f"shape needs t_off > t_on, got {self.t_on}..{self.t_off}")
        object.__setattr__(self, "rgb", _check_rgb(self.rgb))
        for name in ("size0", "size1"):
            s = getattr(self, name)
            if s is not None and not (s[0] >= 0 and s[1] >= 0):
                raise ParameterError(f"shape {name} must be non-negative, got {s!r}")
        if self.blink_hz < 0:
            raise ParameterError(f"blink_hz must be >= 0, got {self.blink_hz!r}")


@dataclass(frozen=True)
class Tone:
    """A sine burst during ``[t0, t1)`` s at ``freq_hz``, ``level_dbfs`` RMS, with raised-cosine ramps.

    channels : indices of the channels it plays on (None = all).
    """

    t0: float
    t1: float
    freq_hz: float
    level_dbfs: float = -20.0
    channels: tuple[int, ...] | None = None
    ramp_s: float = 0.005

    def __post_init__(self):
        _check_interval(self.t0, self.t1, "tone")
        if not self.freq_hz > 0:
            raise ParameterError(f"tone frequency must be > 0 Hz, got {self.freq_hz!r}")


@dataclass(frozen=True)
class Noise:
    """A Gaussian noise burst during ``[t0, t1)`` s, ``level_dbfs`` RMS; colour "white" or "pink"."""

    t0: float
    t1: float
    level_dbfs: float = -20.0
    colour: str = "white"
    channels: tuple[int, ...] | None = None
    seed: int = 0
    ramp_s: float = 0.005

    def __post_init__(self):
        _check_interval(self.t0, self.t1, "noise")
        if self.colour not in ("white", "pink"):
            raise ParameterError(f"noise colour must be white or pink, got {self.colour!r}")


@dataclass(frozen=True)
class Scene:
    """A synthetic clip: duration (s), background segments, shapes (drawn in order) and audio events."""

    duration_s: float
    background: tuple[Segment, ...] = ()
    shapes: tuple[Shape, ...] = ()
    audio: tuple[Tone | Noise, ...] = ()
    name: str = "scene"

    def __post_init__(self):
        if not (math.isfinite(self.duration_s) and self.duration_s > 0):
            raise ParameterError(f"scene duration must be > 0 s, got {self.duration_s!r}")
        for name in ("background", "shapes", "audio"):
            object.__setattr__(self, name, tuple(getattr(self, name)))

    def cut_times(self) -> list[float]:
        """Times (s) of hard cuts: where one background segment ends and a different one starts."""
        segs = sorted(self.background, key=lambda s: s.t0)
        cuts = []
        for a, b in zip(segs, segs[1:]):
            if abs(a.t1 - b.t0) < 1e-9 and 0 < b.t0 < self.duration_s:
                end_a = a.rgb_end if a.rgb_end is not None else a.rgb
                if end_a != b.rgb or a.texture != b.texture or a.pan != b.pan:
                    cuts.append(b.t0)
        return cuts


# ------------------------------------------------------------------- rendering
def render_frame(scene: Scene, t: float, *, width: int, height: int) -> np.ndarray:
    """The picture at time ``t`` seconds, uint8 [shape=(height, width, 3)], RGB."""
    _check_size(width, height)
    return _render(scene, t, width, height, _background(scene, t, width, height))


def _render(scene: Scene, t: float, width: int, height: int, img: np.ndarray) -> np.ndarray:
    """Draw the shapes visible at ``t`` over ``img`` (float64 background, modified) and quantise."""
    for sh in scene.shapes:
        geom = _shape_geometry(sh, t, scene.duration_s)
        if geom is not None:
            _draw_shape(img, sh, geom, width, height)
    return np.clip(np.rint(img), 0, 255).astype(np.uint8)


def iter_frames(scene: Scene, *, width: int, height: int, fps: float | Fraction
                ) -> Iterator[tuple[float, np.ndarray]]:
    """(time_s, rgb uint8 [shape=(height, width, 3)]) for every frame i at t = i / fps.

    The frame count is round(duration_s * fps), at least 1. A frame whose content cannot differ
    from the previous one (static background, no moving or blinking shape) reuses it, and a static
    background (no fade, no pan) is rendered once per segment with shapes drawn over a copy
    (the same pixels as :func:`render_frame`); the yielded array must be treated as read-only.
    """
    rate = _fps_fraction(fps)
    _check_size(width, height)
    n = max(1, int(round(scene.duration_s * rate)))
    prev_key, prev = None, None
    bg_key, bg = None, None
    for i in range(n):
        t = float(i / rate)
        key = _frame_key(scene, t)
        if key is None or key != prev_key:
            seg = _segment_at(scene, t)
            if seg is not None and seg.rgb_end is None and (seg.texture is None or seg.pan == (0.0, 0.0)):
                if bg_key is not seg:
                    bg_key, bg = seg, _background(scene, t, width, height)
                img = bg.copy()
            else:
                img = _background(scene, t, width, height)
            prev = _render(scene, t, width, height, img)
            prev.flags.writeable = False
            prev_key = key
        yield t, prev


def render_audio(scene: Scene, *, sample_rate: int = 48000, channels: int = 2,
                 start: int = 0, n: int | None = None) -> np.ndarray:
    """Samples ``start .. start + n`` of the mix, float32 [shape=(channels, n)], clipped to [-1, 1].

    ``n`` defaults to the rest of the scene (round(duration_s * sample_rate) samples in all).
    """
    total = int(round(scene.duration_s * sample_rate))
    n = total - start if n is None else n
    if start < 0 or n < 0:
        raise ParameterError(f"audio window start={start}, n={n} must be non-negative")
    r = _AudioRenderer(scene, sample_rate, channels)
    if start:
        r.skip(start)
    return r.next(n)


# ------------------------------------------------------------------- encoding
def write_scene(path: str | os.PathLike, scene: Scene, *, width: int = 320, height: int = 180,
                fps: float | Fraction = 24, video_codec: str | None = None,
                audio_codec: str | None = None, sample_rate: int = 48000, channels: int = 2,
                channel_layout: str | None = "auto", video: bool = True, audio: bool = True,
                long: bool = False, quality: str = "high") -> Path:
    """Encode ``scene`` to ``path`` and return the path.

    The container comes from the suffix (.mp4 .mov .mkv .webm .avi; audio-only .wav .m4a).
    video_codec / audio_codec default per container (libx264 + aac; webm: libvpx + libopus;
    avi: mpeg4 + pcm_s16le; wav: pcm_s16le). ``video=False`` or ``audio=False`` writes a file without
    that stream. channels : 1, 2, 6 or 8 with ``channel_layout="auto"`` (mono, stereo, 5.1, 7.1),
    an explicit FFmpeg layout name, or None for an unlabelled layout ("6 channels", PCM codecs only).
    fps : frames per second (float or Fraction; 23.976 and 29.97 are fine).
    long : fastest encoder settings, for multi-hour files (memory is constant either way).
    quality : "high" (near-lossless, for analysis tests) or "low" (small files, quicker to write:
        x264 at crf 28, AAC with FFmpeg's fast coder at 32 kbit/s per channel).

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
    rate = _fps_fraction(fps)
    if vcodec is not None:
        _check_size(width, height)
        if width % 2 or height % 2:
            raise ParameterError(f"{path}: {vcodec} encodes 4:2:0 video, which needs even width and height; "
                                 f"got {width}x{height}")
    layout = None
    if acodec is not None:
        layout = _audio_layout(channels, channel_layout, acodec, sample_rate, path)
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_name(path.name + ".part")
    try:
        with av.open(str(tmp), mode="w", format=fmt) as out:
            vs = _add_video_stream(out, vcodec, width, height, rate, long, quality) if vcodec else None
            as_ = out.add_stream(acodec, rate=sample_rate, layout=layout) if acodec else None
            if as_ is not None and acodec == "aac" and quality == "low":
                # FFmpeg's default AAC coder (two-loop search, 128 kbit/s stereo) took half the time
                # of writing the 2-hour test film; the "fast" coder at 32 kbit/s per channel takes
                # about a third of that (0.44 instead of 1.22 s per minute of stereo)
                as_.codec_context.options = {"aac_coder": "fast"}
                as_.bit_rate = 32_000 * channels
            _encode(out, scene, vs, as_, width, height, rate, sample_rate, channels, layout)
        os.replace(tmp, path)
    except av.error.FFmpegError as exc:
        tmp.unlink(missing_ok=True)
        raise ParameterError(f"{path}: FFmpeg refused {vcodec}/{acodec} in {fmt}: {exc}") from None
    except BaseException:
        tmp.unlink(missing_ok=True)
        raise
    return path


def sample_scene(duration_s: float = 10.0) -> Scene:
    """The README's demonstration scene (10 s; known events, times in seconds):

    - 0.0-3.0 dark textured room; 0.5-2.0 a bright white disc on the LEFT (x = 0.2) with a low
      50 Hz boom (0.5-1.5 s, -14 dBFS) -> left actuators, strong vibration.
    - 3.0 hard cut to a RED textured scene (3.0-5.0, warm), a 2 kHz sharp blip at 4.0-4.2 s.
    - 5.0 hard cut to a GREEN textured scene (5.0-7.0, cool).
    - 7.0 hard cut to a grey textured scene; 7.5-9.5 a textured orange disc on the RIGHT (x = 0.75)
      grows from 8 % to 60 % of the frame height: something rushing toward the camera -> right fans,
      with a rising pink-noise whoosh (7.5-9.5 s, -20 dBFS).
    """
    d = float(duration_s)
    tex = Texture("noise", scale=0.06, contrast=0.35)
    return Scene(
        duration_s=d,
        name="sample",
        background=(
            Segment(0.0, 3.0, (45, 50, 65), texture=Texture("noise", 0.08, 0.3, seed=1)),
            Segment(3.0, 5.0, (200, 35, 30), texture=Texture("noise", 0.07, 0.3, seed=2)),
            Segment(5.0, 7.0, (35, 165, 55), texture=Texture("noise", 0.07, 0.3, seed=3)),
            Segment(7.0, d, (110, 110, 115), texture=Texture("noise", 0.05, 0.3, seed=4)),
        ),
        shapes=(
            Shape("circle", (255, 255, 245), t_on=0.5, t_off=2.0, xy0=(0.2, 0.5), size0=(0.18, 0.32)),
            Shape("circle", (235, 140, 40), t_on=7.5, t_off=min(9.5, d), xy0=(0.75, 0.5),
                  size0=(0.045, 0.08), size1=(0.34, 0.6), texture=tex),
        ),
        audio=(
            Tone(0.5, 1.5, 50.0, level_dbfs=-14.0, ramp_s=0.02),
            Tone(4.0, 4.2, 2000.0, level_dbfs=-22.0),
            Noise(7.5, min(9.5, d), level_dbfs=-20.0, colour="pink", seed=7, ramp_s=0.3),
        ),
    )


def sample_clip(path: str | os.PathLike, *, width: int = 640, height: int = 360, fps: float = 24,
                **kwargs) -> Path:
    """Write :func:`sample_scene` (10 s) to ``path``; keyword arguments go to :func:`write_scene`."""
    return write_scene(path, sample_scene(), width=width, height=height, fps=fps, **kwargs)


# ------------------------------------------------------------------- private: checks
def _check_interval(t0: float, t1: float, what: str) -> None:
    if not (math.isfinite(t0) and t0 >= 0 and t1 > t0):
        raise ParameterError(f"{what} needs 0 <= t0 < t1, got {t0!r}..{t1!r}")


def _check_rgb(rgb: Sequence[float]) -> RGB:
    if len(rgb) != 3 or not all(0 <= float(c) <= 255 for c in rgb):
        raise ParameterError(f"colour must be three values in 0..255, got {rgb!r}")
    return (int(round(rgb[0])), int(round(rgb[1])), int(round(rgb[2])))


def _check_size(width: int, height: int) -> None:
    if int(width) < 1 or int(height) < 1:
        raise ParameterError(f"frame size must be at least 1x1, got {width}x{height}")


def _fps_fraction(fps: float | Fraction) -> Fraction:
    rate = fps if isinstance(fps, Fraction) else Fraction(float(fps)).limit_denominator(1001)
    if not (0 < rate <= 1000):
        raise ParameterError(f"fps must be in (0, 1000], got {fps!r}")
    return rate


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


# ------------------------------------------------------------------- private: pictures
def _pixel_grid(width: int, height: int) -> tuple[np.ndarray, np.ndarray]:
    """Normalised pixel-centre coordinates x [shape=(1, w)] and y [shape=(h, 1)]."""
    x = ((np.arange(width, dtype=np.float64) + 0.5) / width)[None, :]
    y = ((np.arange(height, dtype=np.float64) + 0.5) / height)[:, None]
    return x, y


def _segment_at(scene: Scene, t: float) -> Segment | None:
    for seg in scene.background:
        if seg.t0 <= t < seg.t1:
            return seg
    return None


def _segment_colour(seg: Segment, t: float) -> np.ndarray:
    c0 = np.asarray(seg.rgb, dtype=np.float64)
    if seg.rgb_end is None:
        return c0
    f = min(1.0, max(0.0, (t - seg.t0) / (seg.t1 - seg.t0)))
    return c0 + f * (np.asarray(seg.rgb_end, dtype=np.float64) - c0)


def _background(scene: Scene, t: float, width: int, height: int) -> np.ndarray:
    img = np.zeros((height, width, 3), dtype=np.float64)
    seg = _segment_at(scene, t)
    if seg is None:
        return img
    colour = _segment_colour(seg, t)
    if seg.texture is None:
        img[:] = colour
        return img
    x, y = _pixel_grid(width, height)
    dt = t - seg.t0
    # Texture coordinates in frame widths (isotropic); panning drifts the pattern.
    u = x - seg.pan[0] * dt
    v = y * (height / width) - seg.pan[1] * dt
    p = _pattern(seg.texture, u / seg.texture.scale, v / seg.texture.scale)
    img[:] = colour[None, None, :] * (1.0 + seg.texture.contrast * (2.0 * p - 1.0))[..., None]
    return img


def _shape_geometry(sh: Shape, t: float, duration_s: float) -> tuple[float, float, float, float] | None:
    """(cx, cy, w, h) normalised at time t, or None when the shape is hidden."""
    if not (sh.t_on <= t < sh.t_off):
        return None
    if sh.blink_hz > 0 and ((t - sh.t_on) * sh.blink_hz) % 1.0 >= 0.5:
        return None
    m0 = sh.t_on if sh.move_t0 is None else sh.move_t0
    m1 = sh.move_t1 if sh.move_t1 is not None else (sh.t_off if math.isfinite(sh.t_off) else duration_s)
    f = 0.0 if m1 <= m0 else min(1.0, max(0.0, (t - m0) / (m1 - m0)))
    xy1 = sh.xy0 if sh.xy1 is None else sh.xy1
    s1 = sh.size0 if sh.size1 is None else sh.size1
    cx = sh.xy0[0] + f * (xy1[0] - sh.xy0[0])
    cy = sh.xy0[1] + f * (xy1[1] - sh.xy0[1])
    w = sh.size0[0] + f * (s1[0] - sh.size0[0])
    h = sh.size0[1] + f * (s1[1] - sh.size0[1])
    return cx, cy, w, h


def _draw_shape(img: np.ndarray, sh: Shape, geom: tuple[float, float, float, float],
                width: int, height: int) -> None:
    cx, cy, w, h = geom
    # Pixel-space geometry; work only inside the bounding box (+1 px for the anti-aliased edge).
    pcx, pcy, hw, hh = cx * width, cy * height, 0.5 * w * width, 0.5 * h * height
    if hw <= 0 or hh <= 0:
        return
    i0, i1 = max(0, int(math.floor(pcx - hw - 1))), min(width, int(math.ceil(pcx + hw + 1)))
    j0, j1 = max(0, int(math.floor(pcy - hh - 1))), min(height, int(math.ceil(pcy + hh + 1)))
    if i0 >= i1 or j0 >= j1:
        return
    px = (np.arange(i0, i1, dtype=np.float64) + 0.5)[None, :] - pcx
    py = (np.arange(j0, j1, dtype=np.float64) + 0.5)[:, None] - pcy
    if sh.kind == "rect":
        cov = np.clip(hw - np.abs(px) + 0.5, 0, 1) * np.clip(hh - np.abs(py) + 0.5, 0, 1)
    else:
        r = np.sqrt((px / hw) ** 2 + (py / hh) ** 2)
        cov = np.clip((1.0 - r) * min(hw, hh) + 0.5, 0, 1)
    colour = np.asarray(sh.rgb, dtype=np.float64)
    if sh.texture is not None:
        # Attached to the shape: coordinates in units of the shape's width, so it expands with it.
        scale = sh.texture.scale * 2.0 * hw
        p = _pattern(sh.texture, px / scale, py / scale)
        fill = colour[None, None, :] * (1.0 + sh.texture.contrast * (2.0 * p - 1.0))[..., None]
    else:
        fill = colour[None, None, :]
    box = img[j0:j1, i0:i1]
    box += cov[..., None] * (fill - box)


_LATTICE = 64


def _lattice(seed: int) -> np.ndarray:
    return np.random.default_rng(seed).random((_LATTICE, _LATTICE))


_LATTICES: dict[int, np.ndarray] = {}


def _pattern(tex: Texture, u: np.ndarray, v: np.ndarray) -> np.ndarray:
    """Pattern value in [0, 1] at texture coordinates (u, v) in feature units (broadcast)."""
    u, v = np.broadcast_arrays(u, v)
    if tex.kind == "stripes":
        return 0.5 + 0.5 * np.sin(np.pi * u)
    if tex.kind == "checker":
        return 0.5 + 0.5 * np.clip(3.0 * np.sin(np.pi * u) * np.sin(np.pi * v), -1.0, 1.0)
    lat = _LATTICES.get(tex.seed)
    if lat is None:
        lat = _LATTICES.setdefault(tex.seed, _lattice(tex.seed))
    if u.ndim == 2 and u.strides[0] == 0 and v.strides[1] == 0:
        # u varies along x only and v along y only (every caller): the interpolation is separable.
        # Rows first (Wv @ lattice, two weights per row of Wv), then two columns per pixel column.
        rows = _lattice_weights(v[:, 0]) @ lat  # (h, 64)
        iu = np.floor(u[0])
        fu = u[0] - iu
        fu = fu * fu * (3.0 - 2.0 * fu)
        a = iu.astype(np.int64) % _LATTICE
        left = rows[:, a]
        return left + fu * (rows[:, (a + 1) % _LATTICE] - left)
    iu, iv = np.floor(u), np.floor(v)
    fu, fv = u - iu, v - iv
    fu = fu * fu * (3.0 - 2.0 * fu)  # smoothstep: C1 across lattice cells
    fv = fv * fv * (3.0 - 2.0 * fv)
    a = iu.astype(np.int64) % _LATTICE
    b = iv.astype(np.int64) % _LATTICE
    a1, b1 = (a + 1) % _LATTICE, (b + 1) % _LATTICE
    top = lat[b, a] + fu * (lat[b, a1] - lat[b, a])
    bot = lat[b1, a] + fu * (lat[b1, a1] - lat[b1, a])
    return top + fv * (bot - top)


def _lattice_weights(c: np.ndarray) -> np.ndarray:
    """Smoothstep interpolation weights [shape=(n, 64)] of coordinates ``c`` on the periodic lattice."""
    i = np.floor(c)
    f = c - i
    f = f * f * (3.0 - 2.0 * f)
    a = i.astype(np.int64) % _LATTICE
    rows = np.arange(c.size)
    wts = np.zeros((c.size, _LATTICE))
    wts[rows, a] += 1.0 - f
    wts[rows, (a + 1) % _LATTICE] += f
    return wts


def _frame_key(scene: Scene, t: float):
    """A hashable summary of everything frame t depends on, or None when it must be rendered."""
    seg = _segment_at(scene, t)
    if seg is not None and (seg.rgb_end is not None or (seg.texture is not None and seg.pan != (0.0, 0.0))):
        return None
    shapes = []
    for k, sh in enumerate(scene.shapes):
        g = _shape_geometry(sh, t, scene.duration_s)
        if g is not None:
            shapes.append((k, g))
    return (id(seg), tuple(shapes))


# ------------------------------------------------------------------- private: sound
class _AudioRenderer:
    """Sequential chunks of the mix; noise generators and filters carry their state across chunks."""

    def __init__(self, scene: Scene, sample_rate: int, channels: int):
        if sample_rate <= 0 or channels < 1:
            raise ParameterError(f"audio needs sample_rate > 0 and channels >= 1, got {sample_rate}, {channels}")
        self.sr = sample_rate
        self.nch = channels
        self.pos = 0
        self.events = []
        for ev in scene.audio:
            chans = list(range(channels)) if ev.channels is None else list(ev.channels)
            if any(c < 0 or c >= channels for c in chans):
                raise ParameterError(f"audio event channels {ev.channels} outside 0..{channels - 1}")
            s0, s1 = int(round(ev.t0 * sample_rate)), int(round(ev.t1 * sample_rate))
            state = {}
            if isinstance(ev, Noise):
                state["rng"] = np.random.default_rng(ev.seed)
                state["drawn"] = s0
                if ev.colour == "pink":
                    h = lfilter(_PINK_B, _PINK_A, np.r_[1.0, np.zeros(1 << 15)])
                    state["gain"] = 1.0 / math.sqrt(float(np.sum(h * h)))
                    state["zi"] = np.zeros(len(_PINK_A) - 1)
            self.events.append((ev, chans, s0, s1, state))

    def skip(self, n: int) -> None:
        self.next(n)

    def next(self, n: int) -> np.ndarray:
        out = np.zeros((self.nch, n), dtype=np.float64)
        a, b = self.pos, self.pos + n
        for ev, chans, s0, s1, state in self.events:
            lo, hi = max(a, s0), min(b, s1)
            if isinstance(ev, Noise) and state["drawn"] < hi:
                # Draw exactly the samples of [drawn, hi): chunked output equals whole output.
                start = state["drawn"]
                x = state["rng"].standard_normal(hi - start)
                if ev.colour == "pink":
                    x, state["zi"] = lfilter(_PINK_B, _PINK_A, x, zi=state["zi"])
                    x = x * state["gain"]
                state["drawn"] = hi
                x = x[lo - start:] if lo > start else x
            elif lo < hi and isinstance(ev, Tone):
                tt = (np.arange(lo, hi, dtype=np.float64) - s0) / self.sr
                x = math.sqrt(2.0) * np.sin(2.0 * np.pi * ev.freq_hz * tt)
            else:
                continue
            if lo >= hi:
                continue
            x = x * (10.0 ** (ev.level_dbfs / 20.0)) * _ramp(np.arange(lo, hi), s0, s1, ev.ramp_s * self.sr)
            out[chans, lo - a:hi - a] += x[None, :]
        self.pos = b
        return np.clip(out, -1.0, 1.0).astype(np.float32)


def _ramp(idx: np.ndarray, s0: int, s1: int, ramp_n: float) -> np.ndarray:
    """Raised-cosine fade-in/out gain (0..1) at sample indices ``idx`` of an event [s0, s1)."""
    ramp_n = min(ramp_n, 0.5 * (s1 - s0))
    if ramp_n < 1:
        return np.ones(idx.shape)
    d = np.minimum(idx - s0 + 0.5, s1 - idx - 0.5) / ramp_n
    return np.where(d >= 1.0, 1.0, 0.5 - 0.5 * np.cos(np.pi * np.clip(d, 0.0, 1.0)))


# ------------------------------------------------------------------- private: encoding
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
            layout: str | None) -> None:
    """Interleave video frames and audio chunks in time order (the muxer's buffers stay small)."""
    arend = _AudioRenderer(scene, sample_rate, channels) if as_ is not None else None
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
        for i, (t, rgb) in enumerate(iter_frames(scene, width=width, height=height, fps=rate)):
            if arend is not None:
                audio_until(t + 1.0)
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


__all__ = [
    "Texture", "Segment", "Shape", "Tone", "Noise", "Scene", "render_frame", "iter_frames", "render_audio",
    "write_scene", "sample_scene", "sample_clip", "CONTAINERS", "STANDARD_LAYOUTS",
]
