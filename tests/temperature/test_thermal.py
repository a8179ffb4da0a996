"""Colour -> temperature (ALGORITHM.md section 4): r = DisR / (DisR + DisG), T = 55 - 25 r."""

from __future__ import annotations

import math

import numpy as np
import pytest

from autohaptics import temperature as thermal
from autohaptics.errors import ParameterError


def frame(rgb, h=9, w=16) -> np.ndarray:
    return np.broadcast_to(np.asarray(rgb, np.uint8), (h, w, 3)).copy()


@pytest.mark.parametrize("rgb, expected", [
    ((255, 0, 0), 55.0),    # pure red: DisR = 0
    ((0, 255, 0), 30.0),    # pure green: DisG = 0 (the thesis's ratio divides by zero here)
    ((0, 0, 0), 42.5),      # any grey is equidistant from red and green: r = 1/2
    ((255, 255, 255), 42.5),
    ((128, 128, 128), 42.5),
    ((0, 0, 255), 42.5),    # blue: both distances sqrt(2) * 255
    ((255, 255, 0), 42.5),  # yellow: both distances 255
])
def test_reference_colours(rgb, expected):
    with np.errstate(all="raise"):
        t = thermal.temperature_target(thermal.mean_colour(frame(rgb)))
    assert float(t) == pytest.approx(expected, abs=1e-9)


def test_hand_computed_colour():
    """(200, 35, 30): DisR = sqrt(55^2 + 35^2 + 30^2) = 71.7635, DisG = sqrt(200^2 + 220^2 + 30^2)
    = 298.8311; r = 71.7635 / 370.5946 = 0.193644; T = 55 - 25 r = 50.15890 C."""
    assert float(thermal.warmth_ratio(np.array([200.0, 35.0, 30.0]))) == pytest.approx(0.193644, abs=1e-6)
    assert float(thermal.temperature_target(np.array([200.0, 35.0, 30.0]))) == pytest.approx(50.15890, abs=1e-4)


def test_mean_colour_of_a_frame():
    f = np.zeros((4, 4, 3), np.uint8)
    f[:2] = (255, 0, 0)
    f[2:] = (0, 0, 255)
    np.testing.assert_allclose(thermal.mean_colour(f), [127.5, 0.0, 127.5])
    with pytest.raises(ParameterError, match="RGB frame"):
        thermal.mean_colour(np.zeros((4, 4)))


def test_red_hotter_than_neutral_hotter_than_green():
    temps = thermal.temperature_target(np.array([[220, 30, 30], [128, 128, 128], [30, 200, 40]], float))
    assert temps[0] > temps[1] > temps[2]
    assert temps[1] == pytest.approx(42.5)


def test_vectorised_shapes():
    seq = np.random.default_rng(1).uniform(0, 255, (7, 3))
    out = thermal.temperature_target(seq)
    assert out.shape == (7,)
    np.testing.assert_allclose(out, [float(thermal.temperature_target(c)) for c in seq], rtol=1e-12)
    assert np.ndim(thermal.temperature_target(seq[0])) == 0


def test_out_of_range_and_nan_inputs_stay_in_range():
    out = thermal.temperature_target(np.array([[np.nan, 0, 0], [np.inf, -5, 300], [-1e9, 1e9, 0]]))
    assert np.isfinite(out).all() and (out >= 30).all() and (out <= 55).all()


def test_neutral_aware_pulls_greys_to_skin_neutral():
    p = thermal.ThermalParams(neutral_aware=True)
    for grey in (0.0, 90.0, 255.0):
        assert float(thermal.temperature_target(np.array([grey] * 3), params=p)) == pytest.approx(33.0)
    # (145, 90, 90): DisR = sqrt(28300) = 168.226, DisG = sqrt(56350) = 237.382, r = 0.414750;
    # re-mapped (r = 1/2 -> 33): 55 - 22 * 2r = 36.7510; chroma 55 is half way between 20 and 90,
    # so half way back to 33: 34.8755
    assert float(thermal.temperature_target(np.array([145.0, 90, 90]), params=p)) == pytest.approx(34.8755, abs=1e-4)
    # saturated colours keep their full temperature
    assert float(thermal.temperature_target(np.array([255.0, 0, 0]), params=p)) == pytest.approx(55.0)
    assert float(thermal.temperature_target(np.array([0.0, 255, 0]), params=p)) == pytest.approx(30.0)


def test_neutral_aware_adding_red_never_cools():
    """Light cyan (200, 255, 255) plus red is white: the pull must not make it colder."""
    p = thermal.ThermalParams(neutral_aware=True)
    cyan, white = thermal.temperature_target(np.array([[200.0, 255, 255], [255.0, 255, 255]]), params=p)
    assert white >= cyan


def test_custom_range():
    p = thermal.ThermalParams(temp_low=28.0, temp_high=36.0, neutral_c=32.0)
    np.testing.assert_allclose(thermal.temperature_target(np.array([[255.0, 0, 0], [0, 255, 0]]), params=p),
                               [36.0, 28.0])


def test_slew_limit_by_hand():
    # 20 C/s at 0.1 s ticks: at most 2 C per tick
    np.testing.assert_allclose(thermal.slew_limit(np.array([30.0, 40, 40, 40, 35]), max_rate_c_per_s=20.0),
                               [30, 32, 34, 36, 35])
    np.testing.assert_allclose(thermal.slew_limit(np.array([30.0, 30]), max_rate_c_per_s=20.0, start_c=35.0),
                               [33, 31])
    assert thermal.slew_limit(np.array([]), max_rate_c_per_s=1.0).size == 0
    with pytest.raises(ParameterError):
        thermal.slew_limit(np.array([1.0]), max_rate_c_per_s=0.0)


def test_clamp_to_device():
    np.testing.assert_allclose(thermal.clamp_to_device(np.array([55.0, 10.0, np.nan, 33.5])), [40, 18, 33, 33.5])
    np.testing.assert_allclose(thermal.clamp_to_device(np.array([55.0]), min_c=20, max_c=38), [38])
    with pytest.raises(ParameterError):
        thermal.clamp_to_device(np.array([30.0]), min_c=40, max_c=20)


@pytest.mark.parametrize("kwargs, match", [
    ({"temp_low": 50.0, "temp_high": 40.0}, "temp_low < temp_high"),
    ({"temp_low": math.nan}, "finite"),
    ({"neutral_c": 70.0}, "neutral_c"),
    ({"chroma_low": 95.0}, "chroma_low"),
    ({"slew_c_per_s": -1.0}, "slew"),
])
def test_params_are_checked(kwargs, match):
    with pytest.raises(ParameterError, match=match):
        thermal.ThermalParams(**kwargs)
