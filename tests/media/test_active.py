"""The active picture (autohaptics.media.active) and frames cropped to it (media.Frame's crop):
the rectangle inside black bars from sampled luma (bars, dark and partly black samples, subtitles
and noise in a bar), from encoded synthetic scenes with known bars, and the crop as a view of
the decoded planes in every display orientation."""

from __future__ import annotations

import av
import cv2
import numpy as np
import pytest

from autohaptics import media
from autohaptics import testing as synth
from autohaptics.media.active import active_area, find_active_area, sample_lumas
from autohaptics.media.frames import Frame, _stored_rect
from autohaptics.testing import Scene, Segment, Shape, Texture

RNG = np.random.default_rng(7)


def _luma(size, rect, level=120, noise=3.0, bar=0.0) -> np.ndarray:
    """A full-range luma frame ``size`` (w, h): textured picture in ``rect``, noisy bars at ``bar`` around."""
    w, h = size
    out = np.clip(bar + RNG.normal(0.0, noise, (h, w)), 0, 255)
    x, y, pw, ph = rect
    out[y:y + ph, x:x + pw] = np.clip(level + 40 * RNG.standard_normal((ph, pw)), 0, 255)
    return out.astype(np.uint8)


@pytest.mark.parametrize("size, rect", [((320, 240), (0, 30, 320, 180)),  # letterbox
                                        ((320, 180), (40, 0, 240, 180)),  # pillarbox
                                        ((320, 240), (32, 24, 256, 192)),  # windowbox
                                        ((320, 180), (0, 0, 320, 180))])  # no bars
def test_the_rectangle_inside_the_bars(size, rect):
    assert active_area([_luma(size, rect) for _ in range(3)]) == rect


def test_dark_and_black_samples_leave_the_picture_to_the_lit_ones():
    size, rect = (320, 240), (0, 30, 320, 180)
    x, y, w, h = rect
    black = np.zeros((240, 320), np.uint8)  # a fade's end, a cut to black
    dark = _luma(size, rect, level=25, noise=1.0)  # a night shot: most of it just above black
    own_border = _luma(size, rect)
    own_border[y:y + 40] = own_border[y + h - 40:y + h] = 0  # the picture's own black border, this frame only
    assert active_area([black, dark, own_border]) == rect
    assert active_area([black, black]) == (0, 0, 320, 240)  # nothing lit: the whole frame


def test_subtitles_noise_and_a_ragged_edge_in_a_bar():
    size, rect = (320, 240), (0, 30, 320, 180)
    samples = []
    for i in range(5):
        f = _luma(size, rect, noise=4.0)
        if i % 2:  # a burnt-in subtitle line in the bottom bar: white glyph strokes over 60 % of the width
            f[218:230, 64:256:3] = 235
        f[28:30, : 320 // (i + 2)] = 40  # the picture's edge ragged by up to two rows
        samples.append(f)
    x, y, w, h = active_area(samples)
    assert (x, w) == (0, 320) and abs(y - 30) <= 2 and abs(y + h - 210) <= 2


@pytest.mark.parametrize("bar, noise", [(16, 3.0), (24, 3.0), (30, 2.0), (20, 6.0)])
def test_bars_that_are_not_pure_black(bar, noise):
    """Bars at full-range 16-30 (video-range black read as full range, a lifted master) with
    grain: still bars, found by their own flat level, in every kind of box."""
    for size, rect in [((320, 240), (0, 30, 320, 180)), ((320, 180), (40, 0, 240, 180)),
                       ((320, 240), (32, 24, 256, 192))]:
        assert active_area([_luma(size, rect, bar=bar, noise=noise) for _ in range(3)]) == rect, (bar, rect)


def test_a_dark_sky_over_darker_ground_is_not_lifted_bars():
    """No bars: a flat night sky (20) above a lit band and flat ground (8) below it in every sample.
    Two flat dark edges at different levels are not bars; the frame is read whole, as before."""
    f = np.full((240, 320), 20, np.uint8)
    f[80:160] = np.clip(120 + 40 * RNG.standard_normal((80, 320)), 0, 255).astype(np.uint8)
    f[160:] = 8
    assert active_area([f, f.copy()]) == (0, 0, 320, 240)
    # flat dark walls at one level (40) on both sides of a lit middle: brighter than any lifted black
    g = np.full((240, 320), 40, np.uint8)
    g[:, 60:260] = np.clip(120 + 40 * RNG.standard_normal((240, 200)), 0, 255).astype(np.uint8)
    assert active_area([g, g.copy()]) == (0, 0, 320, 240)


@pytest.mark.parametrize("boxed", [False, True])
def test_a_subtitle_inside_the_lower_bar_is_not_picture(boxed):
    """Bold burnt-in subtitles (solid strokes over 70 % of the width, or white text on a grey box)
    in the lower bar of some samples, apart from the picture by a few black rows."""
    size, rect = (320, 240), (0, 30, 320, 180)
    samples = []
    for i in range(5):
        f = _luma(size, rect)
        if i % 2:
            if boxed:
                f[216:232, 30:290] = 70
            f[219:229, 40:280] = 235
            f[219:229, 40:280:9] = 70 if boxed else 0  # the gaps between letters
        samples.append(f)
    assert active_area(samples) == rect


@pytest.mark.parametrize("bars", [(40, 0), (40, 10), (2, 2)])
def test_what_is_not_clearly_bars_keeps_the_whole_frame(bars):
    """One-sided (a sky black in every sample), lopsided or too thin: not bars."""
    top, bottom = bars
    rect = (0, top, 320, 240 - top - bottom)
    assert active_area([_luma((320, 240), rect)]) == (0, 0, 320, 240)


def test_stored_rect_is_the_display_rect_in_every_rotation():
    stored = np.arange(6 * 10).reshape(6, 10)
    for rotation in (0, 90, 180, 270):
        shown = np.rot90(stored, rotation // 90)
        rect = (1, 2, 3, 2)
        x, y, w, h = rect
        sx, sy, sw, sh = _stored_rect(rect, rotation, 10, 6)
        np.testing.assert_array_equal(np.rot90(stored[sy:sy + sh, sx:sx + sw], rotation // 90), shown[y:y + h, x:x + w])
    assert _stored_rect((4, 0, 8, 6), 0, 10, 6) is None  # does not fit


def _picture(w=240, h=136) -> np.ndarray:
    xx, yy = np.meshgrid(np.linspace(0, 1, w), np.linspace(0, 1, h))
    return np.stack([200 * xx + 30, 180 * yy + 40, 120 + 60 * np.sin(9 * xx * yy)], axis=-1).astype(np.uint8)


@pytest.mark.parametrize("rotation", [0, 90, 180, 270])
def test_a_cropped_frame_is_the_picture_without_its_bars(rotation):
    """A 240 x 136 picture letterboxed and pillarboxed into 320 x 200: the cropped frame's size,
    proxies and full copy are the bare picture's (within a grey level or two of its own encode)."""
    pic = _picture()
    boxed = np.zeros((200, 320, 3), np.uint8)
    boxed[32:168, 40:280] = pic
    k = rotation // 90
    bare = Frame(av.VideoFrame.from_ndarray(pic, format="rgb24").reformat(format="yuv420p"), 0, 0.0, rotation)
    vf = av.VideoFrame.from_ndarray(boxed, format="rgb24").reformat(format="yuv420p")
    # the rectangle as shown: the stored one rotated with the picture
    shown = np.rot90(np.pad(np.ones((136, 240), bool), ((32, 32), (40, 40))), k)
    ys, xs = np.flatnonzero(shown.any(axis=1)), np.flatnonzero(shown.any(axis=0))
    crop = (int(xs[0]), int(ys[0]), int(xs.size), int(ys.size))
    f = Frame(vf, 0, 0.0, rotation, crop)
    assert (f.width, f.height) == (bare.width, bare.height)
    full, ref = f.full(fmt="gray").astype(int), bare.full(fmt="gray").astype(int)
    assert full.shape == ref.shape and np.abs(full - ref).max() <= 2
    rgb, gray = f.rgb_and_gray(64, 48)
    rgb_b, gray_b = bare.rgb_and_gray(64, 48)
    assert rgb.shape == rgb_b.shape and gray.shape == gray_b.shape
    assert np.abs(gray.astype(int) - gray_b).max() <= 2 and np.abs(rgb.astype(int) - rgb_b).mean() < 1.5
    assert Frame(vf, 0, 0.0, rotation, (0, 0, 400, 400)).width == vf.height if k % 2 else vf.width  # no fit: whole


# ---------------------------------------------------------------- encoded scenes with known bars
def _tex(seed):
    return Texture("noise", 0.08, 0.4, seed=seed)


LIT = Scene(8.0, background=(Segment(0, 8.0, (150, 110, 90), texture=_tex(1)),),
            shapes=(Shape("circle", (240, 230, 200), t_on=1.0, t_off=7.0, xy0=(0.2, 0.5), xy1=(0.8, 0.5),
                          size0=(0.2, 0.3)),))
DARK = Scene(8.0, background=(Segment(0, 8.0, (34, 30, 44), texture=Texture("noise", 0.05, 0.6, seed=2)),))
FADE = Scene(8.0, background=(Segment(0, 5.0, (170, 150, 120), rgb_end=(0, 0, 0), texture=_tex(3)),
                              Segment(5.0, 8.0, (0, 0, 0))))
# the picture's own black border (top and bottom fifth) for its first half
OWN_BORDER = Scene(8.0, background=(Segment(0, 8.0, (120, 140, 160), texture=_tex(4)),),
                   shapes=(Shape("rect", (0, 0, 0), t_on=0, t_off=4.0, xy0=(0.5, 0.1), size0=(1.0, 0.2)),
                           Shape("rect", (0, 0, 0), t_on=0, t_off=4.0, xy0=(0.5, 0.9), size0=(1.0, 0.2))))
BOXES = {"letterbox": ((320, 240), (0, 30, 320, 180)), "pillarbox": ((320, 180), (40, 0, 240, 180)),
         "windowbox": ((320, 240), (32, 24, 256, 192)), "none": ((320, 180), (0, 0, 320, 180))}


@pytest.mark.parametrize("scene", [LIT, DARK, FADE, OWN_BORDER], ids=["lit", "dark", "fade", "own_border"])
@pytest.mark.parametrize("box", list(BOXES))
def test_the_active_area_of_an_encoded_scene_is_its_picture(tmp_path, scene, box):
    (w, h), rect = BOXES[box]
    path = synth.write_scene(tmp_path / "s.mp4", scene, width=w, height=h, fps=24, audio=False,
                             picture=None if box == "none" else rect)
    info = media.probe(path)
    assert len(sample_lumas(info)) >= 4  # the keyframes at 0, 2, 4, 6 s (and at a cut)
    got = find_active_area(info)
    assert max(abs(a - b) for a, b in zip(got, rect)) <= 2, (got, rect)


def test_grey_bars_of_an_encoded_scene(tmp_path):
    """Bars at RGB 20 (luma 20 full range, 33 as coded), letterbox: the picture inside them."""
    path = synth.write_scene(tmp_path / "grey.mp4", LIT, width=320, height=240, fps=24, audio=False,
                             picture=(0, 30, 320, 180), bar_rgb=(20, 20, 20))
    got = find_active_area(media.probe(path))
    assert max(abs(a - b) for a, b in zip(got, (0, 30, 320, 180))) <= 2, got


@pytest.mark.parametrize("opening", ["cut", "fade"])
def test_a_short_film_whose_only_keyframe_is_black(tmp_path, opening):
    """A 6 s letterboxed clip in one 10 s GOP (``long``: no keyframe at its cut or fade from black):
    its one keyframe is black, so frames after it are sampled too."""
    first = Segment(0, 1.0, (0, 0, 0)) if opening == "cut" else Segment(0, 1.0, (0, 0, 0), rgb_end=(150, 110, 90))
    scene = Scene(6.0, background=(first, Segment(1.0, 6.0, (150, 110, 90), texture=_tex(5))), shapes=LIT.shapes)
    path = synth.write_scene(tmp_path / "one_gop.mp4", scene, width=320, height=240, fps=24, audio=False,
                             picture=(0, 30, 320, 180), long=True)
    got = find_active_area(media.probe(path))
    assert max(abs(a - b) for a, b in zip(got, (0, 30, 320, 180))) <= 2, got


def test_a_black_film_is_read_whole(tmp_path):
    path = synth.write_scene(tmp_path / "black.mp4", Scene(4.0, background=(Segment(0, 4.0, (0, 0, 0)),)),
                             width=320, height=240, fps=24, audio=False, picture=(0, 30, 320, 180))
    assert find_active_area(media.probe(path)) == (0, 0, 320, 240)


def test_the_luma_samples_are_full_range_and_spread(tmp_path):
    path = synth.write_scene(tmp_path / "lit.mp4", LIT, width=320, height=240, fps=24, audio=False,
                             picture=(0, 30, 320, 180))
    lumas = sample_lumas(media.probe(path), samples=3)
    assert len(lumas) == 3 and all(lu.shape == (240, 320) and lu.dtype == np.uint8 for lu in lumas)
    assert max(int(lu[:28].max()) for lu in lumas) <= 8  # the bars: black, full range
    assert min(float(lu[40:200].mean()) for lu in lumas) > 60
    assert cv2.absdiff(lumas[0], lumas[2]).mean() > 1  # different frames (the disc has moved)
