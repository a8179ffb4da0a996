"""Rendering a :class:`~autohaptics.testing.scenes.Scene`: pictures exact at pixel centres with
analytic anti-aliased edges (textures are smooth value noise, checkers or stripes with features in
frame widths, so they look alike at every resolution), and the sound mix, clipped to [-1, 1].
"""

from __future__ import annotations

import math
from collections.abc import Iterator
from fractions import Fraction

import numpy as np
from scipy.signal import lfilter

from autohaptics.errors import ParameterError
from autohaptics.testing.scenes import Noise, Scene, Segment, Shape, Texture, Tone, check_size, fps_fraction

# Pink noise: Julius O. Smith's 1/f approximation (3 poles, 3 zeros), +-0.3 dB over the audio band.
_PINK_B = np.array([0.049922035, -0.095993537, 0.050612699, -0.004408786])
_PINK_A = np.array([1.0, -2.494956002, 2.017265875, -0.522189400])


def render_frame(scene: Scene, t: float, *, width: int, height: int) -> np.ndarray:
    """The picture at time ``t`` seconds, uint8 [shape=(height, width, 3)], RGB."""
    check_size(width, height)
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
    rate = fps_fraction(fps)
    check_size(width, height)
    n = max(1, int(round(scene.duration_s * rate)))
    prev_key, prev = None, None
    bg_key, bg = None, None
    for i in range(n):
        t = float(i / rate)
        key = _frame_key(scene, t)
        if key is None or key != prev_key:
            seg = _segment_at(scene, t)
            if seg is not None and seg.rgb_end is None and (seg.texture is None or seg.pan == (0.0, 0.0)) \
                    and _dissolve_at(scene, t) is None:
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
    r = AudioRenderer(scene, sample_rate, channels)
    if start:
        r.skip(start)
    return r.next(n)


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


def _dissolve_at(scene: Scene, t: float) -> tuple[Segment, Segment, float] | None:
    """(segment before, segment after, share of the after 0..1) while a cross-dissolve runs at ``t``."""
    for seg in scene.background:
        half = 0.5 * seg.dissolve_s
        if half > 0 and seg.t0 - half <= t < seg.t0 + half:
            before = [s for s in scene.background if s.t1 <= seg.t0 + 1e-9 and s is not seg]
            if before:
                return max(before, key=lambda s: s.t1), seg, (t - (seg.t0 - half)) / seg.dissolve_s
    return None


def _background(scene: Scene, t: float, width: int, height: int) -> np.ndarray:
    blend = _dissolve_at(scene, t)
    if blend is not None:
        a, b, share = blend
        return (1.0 - share) * _segment_picture(a, t, width, height) + share * _segment_picture(b, t, width, height)
    return _segment_picture(_segment_at(scene, t), t, width, height)


def _segment_picture(seg: Segment | None, t: float, width: int, height: int) -> np.ndarray:
    img = np.zeros((height, width, 3), dtype=np.float64)
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
    if _dissolve_at(scene, t) is not None:
        return None
    shapes = []
    for k, sh in enumerate(scene.shapes):
        g = _shape_geometry(sh, t, scene.duration_s)
        if g is not None:
            shapes.append((k, g))
    return (id(seg), tuple(shapes))


class AudioRenderer:
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
            x = x * _gain(ev, np.arange(lo, hi), s0, s1) * _ramp(np.arange(lo, hi), s0, s1, ev.ramp_s * self.sr)
            out[chans, lo - a:hi - a] += x[None, :]
        self.pos = b
        return np.clip(out, -1.0, 1.0).astype(np.float32)


def _gain(ev: Tone | Noise, idx: np.ndarray, s0: int, s1: int) -> np.ndarray | float:
    """Linear gain of an event at sample indices ``idx`` of [s0, s1): its level, or the glide in dB."""
    if ev.level_end_dbfs is None:
        return 10.0 ** (ev.level_dbfs / 20.0)
    db = ev.level_dbfs + (ev.level_end_dbfs - ev.level_dbfs) * (idx - s0) / max(s1 - s0, 1)
    return 10.0 ** (db / 20.0)


def _ramp(idx: np.ndarray, s0: int, s1: int, ramp_n: float) -> np.ndarray:
    """Raised-cosine fade-in/out gain (0..1) at sample indices ``idx`` of an event [s0, s1)."""
    ramp_n = min(ramp_n, 0.5 * (s1 - s0))
    if ramp_n < 1:
        return np.ones(idx.shape)
    d = np.minimum(idx - s0 + 0.5, s1 - idx - 0.5) / ramp_n
    return np.where(d >= 1.0, 1.0, 0.5 - 0.5 * np.cos(np.pi * np.clip(d, 0.0, 1.0)))
