"""Shot-cut detection on proxies, with synthetic shots whose cuts are known (synth.Segment).

The video pass compares RGB proxies of consecutive ticks (0.1 s apart) and the gray proxies of a
flow pair (one frame apart); both comparisons are exercised here at those spacings.
"""

from __future__ import annotations

import cv2
import numpy as np
import pytest

from autohaptics import testing as synth
from autohaptics.airflow import cuts
from autohaptics.errors import ParameterError

W, H = 128, 72  # the RGB proxy of a 16:9 clip
FRAME_DT = 1 / 24
TICK_DT = 0.1


def tex(seed: int, scale: float = 0.15, contrast: float = 0.5) -> synth.Texture:
    return synth.Texture("noise", scale, contrast, seed=seed)


def rgb_at(scene: synth.Scene, t: float) -> np.ndarray:
    return synth.render_frame(scene, t, width=W, height=H)


def gray_at(scene: synth.Scene, t: float) -> np.ndarray:
    return cv2.cvtColor(synth.render_frame(scene, t, width=160, height=90), cv2.COLOR_RGB2GRAY)


def scores(scene: synth.Scene, times) -> tuple[float, float]:
    """Largest cut score over ``times`` between tick frames (RGB, 0.1 s) and flow pairs (gray, 1 frame)."""
    tick = max(cuts.cut_score(cuts.frame_signature(rgb_at(scene, t)), cuts.frame_signature(rgb_at(scene, t + TICK_DT)))
               for t in times)
    pair = max(cuts.cut_score(cuts.frame_signature(gray_at(scene, t)),
                              cuts.frame_signature(gray_at(scene, t + FRAME_DT))) for t in times)
    return tick, pair


def two_shots(a: synth.Segment, b: synth.Segment) -> synth.Scene:
    return synth.Scene(2.0, background=(a, b))


# ---------------------------------------------------------------- cuts that must be found
@pytest.mark.parametrize("first, second", [
    (synth.Segment(0, 1, (60, 90, 160), texture=tex(1)), synth.Segment(1, 2, (170, 120, 60), texture=tex(2))),
    # same mean luma (~115), different colour and layout: the colour histogram tells them apart
    (synth.Segment(0, 1, (40, 160, 60), texture=tex(3)), synth.Segment(1, 2, (115, 115, 115), texture=tex(4, 0.2))),
    # black to a bright scene
    (synth.Segment(0, 1, (0, 0, 0)), synth.Segment(1, 2, (200, 170, 120), texture=tex(5))),
    # a bright scene to black
    (synth.Segment(0, 1, (200, 170, 120), texture=tex(5)), synth.Segment(1, 2, (0, 0, 0))),
])
def test_hard_cut_is_detected(first, second):
    scene = two_shots(first, second)
    assert scene.cut_times() == [1.0]
    t0 = 1.0 - 0.02  # both spacings straddle the cut
    assert cuts.is_cut(cuts.frame_signature(rgb_at(scene, t0)), cuts.frame_signature(rgb_at(scene, t0 + TICK_DT)))
    assert cuts.is_cut(cuts.frame_signature(gray_at(scene, t0)), cuts.frame_signature(gray_at(scene, t0 + FRAME_DT)))


def test_no_cut_inside_a_shot():
    scene = two_shots(synth.Segment(0, 1, (60, 90, 160), texture=tex(1)),
                      synth.Segment(1, 2, (170, 120, 60), texture=tex(2)))
    tick, pair = scores(scene, np.arange(0.0, 0.85, 0.1))
    assert tick < 0.05 and pair < 0.05


# ---------------------------------------------------------------- transitions that are not cuts
@pytest.mark.parametrize("start, end, seconds", [
    ((200, 40, 30), (30, 60, 200), 0.5),   # a fast colour fade (red to blue in half a second)
    ((200, 40, 30), (30, 60, 200), 2.0),
    ((0, 0, 0), (180, 150, 120), 1.0),     # fade in from black
    ((180, 150, 120), (0, 0, 0), 1.0),     # fade out to black
])
def test_fade_is_not_a_cut(start, end, seconds):
    scene = synth.Scene(seconds + 0.5, background=(synth.Segment(0, seconds, start, rgb_end=end, texture=tex(3)),
                                                   synth.Segment(seconds, seconds + 0.5, end, texture=tex(3))))
    assert scene.cut_times() == []
    tick, pair = scores(scene, np.arange(0.0, seconds - TICK_DT + 1e-9, 0.05))
    assert tick < 0.5 and pair < 0.5, (tick, pair)


@pytest.mark.parametrize("speed", [0.25, 0.5, 1.0, 2.0])  # frame widths per second
@pytest.mark.parametrize("scale", [0.05, 0.15, 0.3])
def test_panning_textured_shot_is_not_a_cut(speed, scale):
    scene = synth.Scene(2.0, background=(synth.Segment(0, 2, (120, 100, 80), texture=tex(6, scale), pan=(speed, 0.2 * speed)),))
    tick, pair = scores(scene, np.arange(0.0, 1.5, 0.1))
    assert tick < 0.5 and pair < 0.5, (tick, pair)


def test_flat_frames_are_compared_by_brightness():
    """A title card is flat: between two flat frames only a brightness jump of >= 40 grey levels
    counts (a fade moves a few levels per frame)."""
    def flat(v):
        return cuts.frame_signature(np.full((H, W, 3), v, np.uint8))
    assert not cuts.is_cut(flat(0), flat(10))
    assert cuts.cut_score(flat(0), flat(20)) == pytest.approx(0.25)  # 0.5 * 20 / 40
    assert cuts.is_cut(flat(0), flat(40))
    assert cuts.cut_score(flat(0), flat(255)) == 1.0


# ---------------------------------------------------------------- the signature and the score
@pytest.mark.parametrize("shape, size", [((H, W, 3), 48 + 144), ((H, W), 32 + 144), ((1, 1, 3), 192), ((1, 1), 176),
                                         ((16, 16, 3), 192), ((90, 1), 176)])
def test_signature_layout(shape, size):
    f = np.random.default_rng(0).integers(0, 256, shape, dtype=np.uint8)
    sig = cuts.frame_signature(f)
    assert sig.shape == (size,) and sig.dtype == np.float32 and np.isfinite(sig).all()
    nh = size - 144
    assert sig[:nh].sum() == pytest.approx(1.0, abs=1e-5)


def test_score_is_symmetric_bounded_and_zero_for_identical_frames():
    rng = np.random.default_rng(2)
    a, b = (cuts.frame_signature(rng.integers(0, 256, (H, W, 3), dtype=np.uint8)) for _ in range(2))
    assert cuts.cut_score(a, a) == 0.0
    assert cuts.cut_score(a, b) == cuts.cut_score(b, a)
    assert 0.0 <= cuts.cut_score(a, b) <= 1.0


def test_gray_and_colour_signatures_do_not_mix():
    with pytest.raises(ParameterError, match="gray vs colour"):
        cuts.cut_score(cuts.frame_signature(np.zeros((9, 16, 3), np.uint8)), cuts.frame_signature(np.zeros((9, 16), np.uint8)))
    with pytest.raises(ParameterError, match="gray"):
        cuts.frame_signature(np.zeros((9, 16, 4), np.uint8))


@pytest.mark.parametrize("kwargs", [{"hist_threshold": 0.0}, {"corr_threshold": 2.0}, {"flat_jump": 0.0},
                                    {"flat_std": -1.0}])
def test_params_are_checked(kwargs):
    with pytest.raises(ParameterError):
        cuts.CutParams(**kwargs)
