"""Synthetic scenes with known answers, described in normalised coordinates (x to the right, y
downward, both in [0, 1] of the frame) and in seconds, so one scene rendered at 320x180 @ 24 fps and
at 1280x720 @ 30 fps shows the same picture at the same instants.

- ``background``: :class:`Segment` s, each ``[t0, t1)`` with a colour (optionally fading to
  ``rgb_end``), an optional :class:`Texture` and a pan velocity; where one segment ends and a
  different one starts is a hard cut (:meth:`Scene.cut_times`); time not covered is black.
- ``shapes``: :class:`Shape` s (rect or circle) shown during ``[t_on, t_off)``, moving linearly and
  growing ("moving toward the camera" = growing), optionally blinking and textured.
- ``audio``: :class:`Tone` and :class:`Noise` bursts, levels in dBFS RMS (full scale = 1.0).

:func:`sample_scene` is the README's 10 s demonstration scene, with its events listed.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from fractions import Fraction

from autohaptics.errors import ParameterError

RGB = tuple[int, int, int]
IMPACT_LENGTH_S = 0.3


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
    dissolve_s : if > 0, the segment before this one cross-dissolves into it over this many
    seconds centred on ``t0`` (both pictures blended linearly; not a hard cut).
    """

    t0: float
    t1: float
    rgb: RGB
    rgb_end: RGB | None = None
    texture: Texture | None = None
    pan: tuple[float, float] = (0.0, 0.0)
    dissolve_s: float = 0.0

    def __post_init__(self):
        check_interval(self.t0, self.t1, "segment")
        object.__setattr__(self, "rgb", check_rgb(self.rgb))
        if self.rgb_end is not None:
            object.__setattr__(self, "rgb_end", check_rgb(self.rgb_end))
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
        object.__setattr__(self, "rgb", check_rgb(self.rgb))
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
    level_end_dbfs : if given, the level glides linearly in dB to it by ``t1`` (a rising rumble).
    """

    t0: float
    t1: float
    freq_hz: float
    level_dbfs: float = -20.0
    channels: tuple[int, ...] | None = None
    ramp_s: float = 0.005
    level_end_dbfs: float | None = None

    def __post_init__(self):
        check_interval(self.t0, self.t1, "tone")
        if not self.freq_hz > 0:
            raise ParameterError(f"tone frequency must be > 0 Hz, got {self.freq_hz!r}")


@dataclass(frozen=True)
class Noise:
    """A Gaussian noise burst during ``[t0, t1)`` s, ``level_dbfs`` RMS; colour "white" or "pink";
    ``level_end_dbfs`` as for :class:`Tone`."""

    t0: float
    t1: float
    level_dbfs: float = -20.0
    colour: str = "white"
    channels: tuple[int, ...] | None = None
    seed: int = 0
    ramp_s: float = 0.005
    level_end_dbfs: float | None = None

    def __post_init__(self):
        check_interval(self.t0, self.t1, "noise")
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
        """Times (s) of hard cuts: where one background segment ends and a different one starts
        (without a dissolve)."""
        segs = sorted(self.background, key=lambda s: s.t0)
        cuts = []
        for a, b in zip(segs, segs[1:]):
            if abs(a.t1 - b.t0) < 1e-9 and 0 < b.t0 < self.duration_s:
                end_a = a.rgb_end if a.rgb_end is not None else a.rgb
                if b.dissolve_s <= 0 and (end_a != b.rgb or a.texture != b.texture or a.pan != b.pan):
                    cuts.append(b.t0)
        return cuts


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


def left_boom_right_hum_scene() -> Scene:
    """Two sounds at very different levels, each with a bright object (14 s; the refinement tests):

    - 3-4 s a loud 50 Hz boom (-10 dBFS) while a bright disc sits on the LEFT (x = 0.2, 2-5 s);
    - 9-11 s a quiet 60 Hz hum (-26 dBFS) while a bright square sits on the RIGHT (x = 0.8, 8-12 s);
    - a textured blue-grey shot, a hard cut at 7 s to a brown one.

    At thresholds near 1 only the boom vibrates; at 0.3 the hum does too, on the right actuators.
    """
    return Scene(
        14.0,
        name="left_boom_right_hum",
        background=(Segment(0, 7, (50, 55, 70), texture=Texture("noise", 0.08, 0.3, seed=1)),
                    Segment(7, 14, (70, 50, 45), texture=Texture("noise", 0.07, 0.3, seed=2))),
        shapes=(Shape("circle", (255, 255, 240), t_on=2, t_off=5, xy0=(0.2, 0.5), size0=(0.2, 0.35)),
                Shape("rect", (250, 250, 250), t_on=8, t_off=12, xy0=(0.8, 0.5), size0=(0.2, 0.35))),
        audio=(Tone(3, 4, 50.0, level_dbfs=-10.0, ramp_s=0.02), Tone(9, 11, 60.0, level_dbfs=-26.0, ramp_s=0.02)),
    )


def three_motions_scene() -> Scene:
    """Three shots, each with its own motion (6 s; the invariance tests: re-encodes, black bars):

    - 0-2 s a warm textured shot; 0.4-1.8 s a bright disc crossing the lower left;
    - 2-4 s a cool one; 2.4-3.8 s an orange disc on the right rushing at the camera (growing);
    - 4-6 s a grey one panning at 0.25 frame widths/s;
    - a quiet 220 Hz tone (-30 dBFS) with three loud noise bursts at 1, 3 and 5 s.
    """
    def tex(seed: int) -> Texture:
        return Texture("noise", 0.08, 0.35, seed=seed)

    return Scene(6.0, name="three_motions",
                 background=(Segment(0, 2.0, (150, 90, 60), texture=tex(1)),
                             Segment(2.0, 4.0, (70, 110, 170), texture=tex(2)),
                             Segment(4.0, 6.0, (120, 120, 120), texture=tex(3), pan=(0.25, 0.0))),
                 shapes=(Shape("circle", (240, 230, 200), t_on=0.4, t_off=1.8, xy0=(0.1, 0.7), xy1=(0.5, 0.6),
                               size0=(0.18, 0.3), texture=Texture("noise", 0.3, 0.5, seed=5)),
                         Shape("circle", (235, 140, 40), t_on=2.4, t_off=3.8, xy0=(0.75, 0.45),
                               size0=(0.08, 0.14), size1=(0.4, 0.7), texture=Texture("noise", 0.25, 0.5, seed=6))),
                 audio=(Tone(0, 6, 220.0, level_dbfs=-30.0), Noise(1.0, 1.15, level_dbfs=-6.0, seed=1),
                        Noise(3.0, 3.15, level_dbfs=-6.0, seed=2), Noise(5.0, 5.15, level_dbfs=-6.0, seed=3)))


def material_scene(duration_s: float = 24.0) -> Scene:
    """A film-like scene for the material matrix (``bench matrix``; 24 s, 6 s shots cycling):

    - a sustained score throughout (a C major chord, about -20 dBFS), so a file cut anywhere starts
      mid-score, and a loud impact every 3 s from 2.3 s (:data:`MATERIAL_IMPACTS_S`): the only events;
    - shots in turn: a disc crossing the lower left (warm), a disc rushing at the camera on the right
      (cool), a panning textured background (grey), a dark shot with a bright disc on the left:
      motion for the fans, colour for the temperature, a bright spot for the saliency.
    """
    d = float(duration_s)
    looks = (((150, 90, 60), (0.0, 0.0)), ((70, 110, 170), (0.0, 0.0)), ((120, 120, 120), (0.25, 0.0)),
             ((40, 40, 50), (0.0, 0.0)))
    audio: list[Tone | Noise] = [Tone(0.0, d, f, level_dbfs=-26.0, ramp_s=0.05) for f in (130.81, 261.63, 329.63, 392.0)]
    audio += [e for k, t in enumerate(MATERIAL_IMPACTS_S) if t + IMPACT_LENGTH_S < d
              for e in impact(t, level_dbfs=-8.0 - 2.0 * (k % 3), seed=k + 1)]
    background, shapes = [], []
    t, k = 0.0, 0
    while t < d - 1e-9:
        end = min(t + 6.0, d)
        rgb, pan = looks[k % 4]
        background.append(Segment(t, end, rgb, texture=Texture("noise", 0.08, 0.35, seed=k + 1), pan=pan))
        on, off = t + 0.4, min(t + 5.2, end)
        if k % 4 == 0 and off > on:
            shapes.append(Shape("circle", (240, 230, 200), t_on=on, t_off=off, xy0=(0.1, 0.7), xy1=(0.55, 0.6),
                                size0=(0.18, 0.3), texture=Texture("noise", 0.3, 0.5, seed=40 + k)))
        elif k % 4 == 1 and off > on:
            shapes.append(Shape("circle", (235, 140, 40), t_on=on, t_off=off, xy0=(0.75, 0.45), size0=(0.06, 0.1),
                                size1=(0.4, 0.7), texture=Texture("noise", 0.25, 0.5, seed=40 + k)))
        elif k % 4 == 3 and off > on:
            shapes.append(Shape("circle", (255, 250, 235), t_on=on, t_off=off, xy0=(0.25, 0.5), size0=(0.15, 0.27)))
        t, k = end, k + 1
    return Scene(duration_s=d, background=tuple(background), shapes=tuple(shapes), audio=tuple(audio), name="material")


MATERIAL_IMPACTS_S = tuple(2.3 + 3.0 * k for k in range(40))


def impact(t: float, *, level_dbfs: float = -8.0, seed: int = 0) -> list[Tone | Noise]:
    """A loud hit at ``t`` s: a 45 Hz thump and a pink-noise crack, ``IMPACT_LENGTH_S`` long."""
    return [Tone(t, t + IMPACT_LENGTH_S, 45.0, level_dbfs=level_dbfs, ramp_s=0.01),
            Noise(t, t + IMPACT_LENGTH_S * 0.6, level_dbfs=level_dbfs - 2.0, colour="pink", seed=seed, ramp_s=0.005)]


def check_interval(t0: float, t1: float, what: str) -> None:
    """ParameterError unless 0 <= t0 < t1, both finite (seconds of a ``what``)."""
    if not (math.isfinite(t0) and t0 >= 0 and t1 > t0):
        raise ParameterError(f"{what} needs 0 <= t0 < t1, got {t0!r}..{t1!r}")


def check_rgb(rgb: Sequence[float]) -> RGB:
    """An (r, g, b) triple of 0..255 integers; ParameterError otherwise."""
    if len(rgb) != 3 or not all(0 <= float(c) <= 255 for c in rgb):
        raise ParameterError(f"colour must be three values in 0..255, got {rgb!r}")
    return (int(round(rgb[0])), int(round(rgb[1])), int(round(rgb[2])))


def check_size(width: int, height: int) -> None:
    """ParameterError unless the picture size is usable."""
    if int(width) < 1 or int(height) < 1:
        raise ParameterError(f"frame size must be at least 1x1, got {width}x{height}")


def fps_fraction(fps: float | Fraction) -> Fraction:
    """A frame rate as an exact fraction (23.976 -> 24000/1001)."""
    rate = fps if isinstance(fps, Fraction) else Fraction(float(fps)).limit_denominator(1001)
    if not (0 < rate <= 1000):
        raise ParameterError(f"fps must be in (0, 1000], got {fps!r}")
    return rate
