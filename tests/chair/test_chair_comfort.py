"""Timeline tick -> chair frame: quantisation, comfort scaling, zone muting, temperature clamp."""

from __future__ import annotations

import math

import numpy as np
import pytest

from autohaptics.chair.comfort import Comfort, DeviceProfile, compose_frame, temperature_cc
from autohaptics.timeline.quantise import to_u8 as quantize_u8
from autohaptics.chair.protocol import Hello
from autohaptics.errors import ParameterError
from autohaptics.timeline import Timeline

ARMRESTS = [2, 6]  # A3, A7
SEAT = [7, 8]  # A8, A9
BACK = [0, 1, 3, 4, 5]


def _timeline(n=4, seed=0):
    rng = np.random.default_rng(seed)
    tl = Timeline.empty(n)
    tl.vibration[:] = rng.random((n, 9))
    tl.fans[:] = rng.random((n, 9, 17))
    tl.temperature_c[:] = np.linspace(30.0, 55.0, n)
    return tl.validate()


def test_quantisation_rounds_half_up_and_clips():
    assert list(quantize_u8(np.array([0.0, 1.0, 0.5, 1 / 255 * 0.5, 1 / 255 * 0.49, 2.0, -1.0]))) == \
        [0, 255, 128, 1, 0, 255, 0]
    assert list(quantize_u8(np.array([1.0, 0.5]), 0.5)) == [128, 64]


def test_full_comfort_frame_equals_quantised_timeline():
    tl = _timeline()
    profile = DeviceProfile()
    for k in range(tl.n_ticks):
        f = compose_frame(tl, k, comfort=Comfort(), profile=profile)
        assert f.tick == k
        np.testing.assert_array_equal(np.frombuffer(f.motors, np.uint8),
                                      np.floor(tl.vibration[k].astype(np.float64) * 255 + 0.5))
        np.testing.assert_array_equal(np.frombuffer(f.fans, np.uint8).reshape(9, 17),
                                      np.floor(tl.fans[k].astype(np.float64) * 255 + 0.5))
        expected = min(max(float(tl.temperature_c[k]), 18.0), 40.0)
        assert f.temp_cc == math.floor(expected * 100 + 0.5)


def test_fan_grid_is_row_major_top_left_first():
    tl = Timeline.empty(1)
    tl.fans[0, 0, 0] = 1.0
    tl.fans[0, 0, 16] = 0.5
    tl.fans[0, 8, 0] = 0.25
    f = compose_frame(tl, 0, comfort=Comfort(), profile=DeviceProfile())
    assert f.fans[0] == 255 and f.fans[16] == 128 and f.fans[8 * 17] == 64
    assert sum(1 for b in f.fans if b) == 3


def test_intensity_and_zone_mutes():
    tl = _timeline()
    comfort = Comfort(intensity=0.6, mute=frozenset({"armrests", "fans"}))
    f = compose_frame(tl, 1, comfort=comfort, profile=DeviceProfile())
    motors = np.frombuffer(f.motors, np.uint8)
    assert motors[ARMRESTS].tolist() == [0, 0]
    np.testing.assert_array_equal(motors[BACK + SEAT],
                                  np.floor(np.clip(tl.vibration[1, BACK + SEAT].astype(np.float64) * 0.6, 0, 1) * 255 + 0.5))
    assert f.fans == bytes(153)
    silent = compose_frame(tl, 1, comfort=Comfort(intensity=0.0), profile=DeviceProfile())
    assert silent.motors == bytes(9) and silent.fans == bytes(153) and silent.temp_cc == 3300


def test_temperature_scaling_mute_and_device_clamp():
    profile = DeviceProfile(temp_min_c=18.0, temp_max_c=40.0, temp_neutral_c=33.0)
    assert temperature_cc(55.0, Comfort(), profile) == 4000  # clamped to the device's safe maximum
    assert temperature_cc(10.0, Comfort(), profile) == 1800
    assert temperature_cc(37.0, Comfort(intensity=0.5), profile) == 3500  # half the distance from neutral
    assert temperature_cc(39.0, Comfort(mute=frozenset({"heat"})), profile) == 3300
    narrow = DeviceProfile.from_hello(Hello(temp_min_cc=2500, temp_max_cc=3600, temp_neutral_cc=3200))
    assert (narrow.temp_min_c, narrow.temp_max_c, narrow.temp_neutral_c) == (25.0, 36.0, 32.0)
    assert temperature_cc(50.0, Comfort(), narrow) == 3600


@pytest.mark.parametrize("kwargs,match", [
    ({"intensity": 1.5}, r"\[0, 1\]"),
    ({"intensity": float("nan")}, r"\[0, 1\]"),
    ({"intensity": "loud"}, "number"),
    ({"mute": frozenset({"legs"})}, "unknown comfort zone"),
    ({"mute": "heat"}, "collection"),
])
def test_comfort_rejects_bad_values(kwargs, match):
    with pytest.raises(ParameterError, match=match):
        Comfort(**kwargs)


def test_profile_and_tick_range_are_validated():
    with pytest.raises(ParameterError, match="temp_min <= neutral <= temp_max"):
        DeviceProfile(temp_min_c=35.0, temp_max_c=40.0, temp_neutral_c=33.0)
    with pytest.raises(ParameterError, match="outside the timeline"):
        compose_frame(_timeline(), 4, comfort=Comfort(), profile=DeviceProfile())
    assert Comfort.from_dict(Comfort(0.3, frozenset({"seat"})).to_dict()) == Comfort(0.3, frozenset({"seat"}))
