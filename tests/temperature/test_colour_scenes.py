"""Known answers through the whole pipeline: a generated film of colour shots (encoded with
FFmpeg, decoded, analysed, derived) gives the chair a curve with red/orange above grey above
blue/cyan/green, greys within 1 C of neutral, every value in the device's range and slew-limited.

Shots are 4 s each, a colour always after a neutral one: at 1 C/s the chair moves at most 4 C in
a shot, so every neutral shot ends back at neutral and every colour's end shows where it goes.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from autohaptics import pipeline
from autohaptics import testing as synth
from autohaptics.params import GenerateParams
from autohaptics.temperature import ThermalParams
from autohaptics.temperature.device import CURVE_SLACK_C
from autohaptics.testing import Scene, Segment, Texture

SHOT_S = 4.0
SHOTS = (("grey", (128, 128, 128)), ("red", (220, 30, 30)), ("grey", (128, 128, 128)), ("blue", (30, 60, 220)),
         ("black", (0, 0, 0)), ("orange", (240, 140, 30)), ("white", (255, 255, 255)), ("cyan", (30, 210, 220)),
         ("grey", (90, 90, 90)), ("green", (30, 200, 40)), ("grey", (160, 160, 160)))
WARM, COOL, NEUTRAL = ("red", "orange"), ("blue", "cyan", "green"), ("grey", "black", "white")
P = ThermalParams()


def _scene() -> Scene:
    return Scene(SHOT_S * len(SHOTS), name="colours", background=tuple(
        Segment(i * SHOT_S, (i + 1) * SHOT_S, rgb, texture=Texture("noise", 0.08, 0.2 if sum(rgb) else 0.0, seed=i))
        for i, (_, rgb) in enumerate(SHOTS)))


@pytest.fixture(scope="module", params=[(320, 180, 24, ".mp4"), (480, 270, 30, ".webm")],
                ids=["h264-320x180@24", "vp8-480x270@30"])
def chair_curve(request, tmp_path_factory):
    w, h, fps, suffix = request.param
    path = synth.write_scene(tmp_path_factory.mktemp("colours") / f"colours{suffix}", _scene(), width=w, height=h,
                             fps=fps, audio=False)
    tl = pipeline.generate(path, dataclasses.replace(GenerateParams(), tracks=("temperature",)))
    return tl.temperature_c.astype(np.float64), tl


def _shot_ends(curve: np.ndarray) -> list[tuple[str, float]]:
    """(name, the chair's mean temperature over the last 0.5 s of the shot) for every shot."""
    ticks = int(SHOT_S * 10)
    return [(name, float(curve[(i + 1) * ticks - 5:(i + 1) * ticks].mean())) for i, (name, _) in enumerate(SHOTS)]


def test_warm_above_neutral_above_cool(chair_curve):
    curve, _ = chair_curve
    ends = _shot_ends(curve)
    print(ends)
    warm = [t for name, t in ends if name in WARM]
    cool = [t for name, t in ends if name in COOL]
    neutral = [t for name, t in ends if name in NEUTRAL]
    assert min(warm) > max(neutral) + 1.0 and min(neutral) > max(cool) + 1.0


def test_grey_black_and_white_end_within_1_c_of_neutral(chair_curve):
    curve, _ = chair_curve
    for name, t in _shot_ends(curve):
        if name in NEUTRAL:
            assert abs(t - P.neutral_c) <= 1.0, (name, t)


def test_every_value_in_the_device_range_and_slew_limited(chair_curve):
    curve, tl = chair_curve
    assert tl.temp_range == (P.device_min_c, P.device_max_c)
    assert np.isfinite(curve).all() and curve.min() >= P.device_min_c and curve.max() <= P.device_max_c
    steps = np.abs(np.diff(np.concatenate([[P.neutral_c], curve])))
    assert steps.max() <= P.device_rate_c_per_s * 0.1 + CURVE_SLACK_C
    assert curve.max() - curve.min() >= 6.0  # not vacuous: the chair does move
    assert tl.stats["temperature"]["mapping"] == "warmcool"
    target = tl.features["temperature_target_c"]
    assert target.min() >= P.device_min_c and target.max() <= P.device_max_c
