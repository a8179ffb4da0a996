"""Burnt-in overlays (``media.overlays``): found in sampled pictures of a film, nothing found in a clean
film or a clip of one scene, filled from the picture around them, or, a translucent one across the
picture, unblended."""

from __future__ import annotations

import json

import cv2
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from autohaptics.media.overlays import MAX_COVER, MIN_SHOTS, EdgeTally, Overlays, find_overlays
from autohaptics.testing.burnin import OVERLAYS, burn, timecode, timecode_box

W, H = 640, 272


def _scene(k: int) -> np.ndarray:
    """Picture ``k`` of a film: a lit, textured scene, different for every ``k`` (RGB uint8)."""
    rng = np.random.default_rng(k)
    small = rng.integers(40, 230, size=(9, 16, 3)).astype(np.uint8)
    img = cv2.resize(small, (W, H), interpolation=cv2.INTER_CUBIC)
    for _ in range(6):
        x, y = int(rng.integers(0, W)), int(rng.integers(0, H))
        cv2.circle(img, (x, y), int(rng.integers(10, 60)), [int(v) for v in rng.integers(0, 255, 3)], -1)
    return img


def _luma(rgb: np.ndarray) -> np.ndarray:
    return cv2.cvtColor(rgb, cv2.COLOR_RGB2GRAY)


def _samples(kind: str | None, n: int = 9) -> list[np.ndarray]:
    """``n`` pictures spread over a film at 24 fps (frames 37 s apart), ``kind`` burnt in (None: clean)."""
    out = []
    for k in range(n):
        rgb = _scene(k)
        out.append(_luma(rgb if kind is None else burn(rgb, kind, 37 * 24 * k + 5 * k, 24.0)))
    return out


def test_timecode_is_found_whole_with_its_changing_digits():
    ov = find_overlays(_samples("timecode"))
    assert ov is not None and ov.alpha is None  # small and opaque: filled
    mask = ov.mask
    scale = mask.shape[1] / W
    x, y, w, h = timecode_box(W, H)
    box = np.zeros(mask.shape, bool)
    box[int(y * scale):int(np.ceil((y + h) * scale)), int(x * scale):int(np.ceil((x + w) * scale))] = True
    assert mask[box].mean() >= 0.97  # the box, the frame digits that change in every sample included
    assert mask.sum() <= 2.5 * box.sum()  # and not much more than it (the margin)


def test_a_logo_is_found_where_it_is():
    ov = find_overlays(_samples("logo"))
    assert ov is not None and ov.alpha is None  # small: filled, though the film shows through it
    ys, xs = np.nonzero(ov.mask)
    assert xs.min() > 0.8 * ov.mask.shape[1] and ys.max() < 0.3 * ov.mask.shape[0]  # top right


def _shrunk_to(rgb: np.ndarray, width: int) -> np.ndarray:
    return cv2.resize(rgb, (width, width * H // W), interpolation=cv2.INTER_AREA)


def test_a_watermark_across_the_picture_is_unblended():
    """A line of words at 35 % white across the picture: filled, it would take the film under it; unblended,
    the film stays and the words fade (at the proxies' sizes, in pictures the search never saw)."""
    ov = find_overlays(_samples("watermark", 20))
    assert ov is not None and ov.share == 0.0 and ov.alpha is not None
    ys, _ = np.nonzero(ov.alpha)
    assert ys.min() > 0.3 * ov.alpha.shape[0] and ys.max() < 0.65 * ov.alpha.shape[0]  # on its line
    assert 0.0 < ov.translucent < MAX_COVER and 200 < ov.colour <= 255
    for k in (40, 41, 42):
        clean = _scene(k)
        for width in (320, 160):
            picture, film = _shrunk_to(burn(clean, "watermark", 5, 24.0), width), _shrunk_to(clean, width)
            out = ov.fill(picture)
            words = np.abs(picture.astype(int) - film).max(axis=2) > 3
            before, after = (float(np.abs(p.astype(int) - film)[words].mean()) for p in (picture, out))
            assert after < 0.7 * before, (k, width, before, after)  # 0.57-0.61 x
            untouched = ov.alpha_at(*picture.shape[:2]) == 0
            assert np.array_equal(out[untouched], picture[untouched])


def test_opacity_and_level_known_answer():
    """Flat shots of different greys under a line at 30 % of grey 200: each shot's line reads 0.7 x its
    grey + 60, so the fit gives opacity 0.3 and level 60 on the line (two rows at the detect size, half
    the pictures' size), and none off it."""
    tally = EdgeTally()
    for k, grey in enumerate((40, 200, 90, 150, 60, 230, 120, 180)):
        film = np.full((H, W), grey, np.float64)
        film[130:132, 40:600] = 0.7 * grey + 0.3 * 200
        tally.add(np.rint(film).astype(np.uint8), shot=k)
    alpha, level = tally.opacity()
    assert alpha.shape == (H // 2, W // 2)
    on = np.zeros(alpha.shape, bool)
    on[65, 20:300] = True
    assert np.allclose(alpha[on], 0.3, atol=0.01) and np.allclose(level[on], 60.0, atol=1.5)
    assert not alpha[~on].any() and not level[~on].any()


def test_a_dark_translucent_overlay_reads_its_colour():
    """Black words at 40 % across the picture: unblended with a dark level."""
    lumas = []
    for k in range(12):
        rgb = _scene(k)
        over = rgb.copy()
        cv2.putText(over, "SCREENER  PROPERTY OF ACME", (int(W * 0.1), int(H * 0.5)), cv2.FONT_HERSHEY_SIMPLEX,
                    H / 300, (0, 0, 0), 2, cv2.LINE_AA)
        lumas.append(_luma(cv2.addWeighted(over, 0.4, rgb, 0.6, 0)))
    ov = find_overlays(lumas)
    assert ov is not None and ov.alpha is not None and ov.colour < 60


def test_nothing_is_found_in_a_clean_film():
    assert find_overlays(_samples(None)) is None


def test_a_clip_of_one_scene_has_no_overlays():
    """Every sample of one shot keeps the scene's own edges: nothing changes around them."""
    rng = np.random.default_rng(3)
    base = _scene(1).astype(np.int16)
    lumas = [_luma(np.clip(base + rng.integers(-3, 4, base.shape), 0, 255).astype(np.uint8)) for _ in range(9)]
    assert find_overlays(lumas) is None
    tc = [_luma(burn(np.clip(base + rng.integers(-3, 4, base.shape), 0, 255).astype(np.uint8), "timecode", k * 24, 24.0))
          for k in range(9)]
    assert find_overlays(tc) is None  # a timecode over one still scene: the scene cannot be told from it


def test_a_long_shot_counts_once():
    """A shot's scene stands still in all its samples: however many, they count as one shot."""
    rng = np.random.default_rng(5)
    still = _scene(11).astype(np.int16)
    tally = EdgeTally()
    for k in range(40):  # one long shot, its edges in every sample
        tally.add(_luma(np.clip(still + rng.integers(-3, 4, still.shape), 0, 255).astype(np.uint8)), shot=0)
    for k in range(1, 4):  # then three short ones
        tally.add(_luma(_scene(20 + k)), shot=k)
    assert tally.find() is None and tally.n == 4 and tally.edges.max() <= 4
    each = EdgeTally()
    for k in range(40):  # the same samples, each taken as a shot of its own: they repeat one another
        each.add(_luma(np.clip(still + rng.integers(-3, 4, still.shape), 0, 255).astype(np.uint8)))
    for k in range(1, 4):
        each.add(_luma(_scene(20 + k)))
    assert each.find() is None and each.n == 4 and each.edges.max() <= 4


def test_a_looped_clip_counts_each_shot_once():
    """A clip of three shots played ten times over (a loop: its copies coded again, a grey level of
    noise) is three shots, too few to tell: nothing is found (every sample a shot of another copy, the
    scenes' own edges stood in all 30 and the pictures' fit ran through three points); a film whose
    shots repeat among others keeps its timecode, read from the shots it has."""
    rng = np.random.default_rng(8)

    def noisy(picture):
        return np.clip(picture.astype(np.int16) + rng.integers(-1, 2, picture.shape), 0, 255).astype(np.uint8)

    loop = EdgeTally()
    for copy in range(10):
        for k in range(3):
            loop.add(noisy(_luma(_scene(k))), shot=3 * copy + k)
    assert loop.find() is None and loop.n == 3 and loop.fitted == 3
    repeated = EdgeTally()
    for k, picture in enumerate(_samples("timecode", 9) * 3):
        repeated.add(noisy(picture), shot=k)
    ov = repeated.find()
    assert repeated.n == 9 and ov is not None and ov.mask.mean() <= MAX_COVER


def test_too_few_or_dark_samples_tell_nothing():
    assert find_overlays(_samples("timecode", MIN_SHOTS - 1)) is None
    tally = EdgeTally()
    for k in range(12):  # dark pictures (a fade, a title card) are passed over
        tally.add(_luma(burn(np.full((H, W, 3), 4, np.uint8), "timecode", k * 50, 24.0)))
    assert tally.n == 0 and tally.find() is None
    for luma in _samples("timecode"):
        tally.add(luma)
    assert tally.find() is not None and tally.n == 9


def test_fill_takes_the_picture_around_and_leaves_the_rest():
    ov = find_overlays(_samples("timecode"))
    rgb = burn(_scene(4), "timecode", 100, 24.0)
    for picture in (rgb, _luma(rgb), cv2.resize(rgb, (160, 68), interpolation=cv2.INTER_AREA)):
        filled = ov.fill(picture)
        inside = ov.mask_at(*picture.shape[:2]).astype(bool)
        assert filled.shape == picture.shape and filled.dtype == np.uint8
        assert np.array_equal(filled[~inside], picture[~inside])
        ring = (cv2.dilate(inside.astype(np.uint8), np.ones((9, 9), np.uint8)) > 0) & ~inside
        assert abs(float(filled[inside].mean()) - float(picture[ring].mean())) < 25  # the scene around it,
        sy, sx = picture.shape[0] / H, picture.shape[1] / W
        x, y, w, h = timecode_box(W, H)
        box = (slice(int(y * sy) + 1, int((y + h) * sy) - 1), slice(int(x * sx) + 1, int((x + w) * sx) - 1))
        assert float(filled[box].mean()) > float(picture[box].mean()) + 40  # not the black box


def test_boxes_and_share():
    ov = find_overlays(_samples("timecode"))
    (x, y, w, h), = ov.boxes(W, H)
    bx, by, bw, bh = timecode_box(W, H)
    assert x <= bx and y <= by and x + w >= bx + bw and y + h >= by + bh
    assert 0.0 < ov.share < 0.06


def test_timecode_text():
    assert timecode(0, 24.0) == "01:00:00:00"
    assert timecode(24 * 61 + 7, 24.0) == "01:01:01:07"
    assert timecode(25 * 3600, 25.0) == "02:00:00:00"


@settings(max_examples=60, deadline=None)
@given(st.integers(1, 40), st.integers(1, 40), st.floats(0.0, 1.0), st.booleans(), st.floats(0.0, 255.0),
       st.integers(0, 2**31))
def test_stats_round_trip(h, w, p, translucent, colour, seed):
    rng = np.random.default_rng(seed)
    mask = rng.random((h, w)) < p
    alpha = (rng.integers(0, 256, (h, w)) * (rng.random((h, w)) < 0.3)).astype(np.uint8) if translucent else None
    ov = Overlays(mask, alpha, colour)
    back = Overlays.from_stats(json.loads(json.dumps(ov.to_stats())))
    assert back is not None and np.array_equal(back.mask, mask)
    assert (back.alpha is None) == (ov.alpha is None)
    if ov.alpha is not None:
        assert np.array_equal(back.alpha, ov.alpha) and abs(back.colour - ov.colour) <= 1e-3
    assert Overlays.from_stats({}) is None and Overlays.from_stats(None) is None


@settings(max_examples=40, deadline=None)
@given(st.integers(8, 64), st.integers(8, 64), st.booleans(), st.floats(0.0, 255.0), st.integers(0, 2**31))
def test_unblending_keeps_every_picture_in_range(h, w, rgb, colour, seed):
    """Any opacity up to 1 and any level: the result is a uint8 picture of the same shape, and where
    there is no overlay it is the picture itself."""
    rng = np.random.default_rng(seed)
    alpha = (rng.integers(0, 256, (24, 24)) * (rng.random((24, 24)) < 0.5)).astype(np.uint8)
    ov = Overlays(np.zeros((24, 24), bool), alpha, colour)
    picture = rng.integers(0, 256, (h, w, 3) if rgb else (h, w)).astype(np.uint8)
    out = ov.fill(picture)
    assert out.shape == picture.shape and out.dtype == np.uint8
    clear = ov.alpha_at(h, w) == 0
    assert np.array_equal(out[clear], picture[clear])
    assert float(ov.alpha_at(h, w).max()) <= 0.75 + 1e-6


@pytest.mark.parametrize("kind", OVERLAYS)
def test_burn_changes_only_its_place(kind):
    rgb = _scene(2)
    out = burn(rgb, kind, 10, 24.0)
    changed = np.any(out != rgb, axis=2)
    assert 0.002 < changed.mean() < 0.2
