import numpy as np
import pytest

from autohaptics import timebase as tb
from autohaptics.errors import ParameterError


@pytest.mark.parametrize("duration, expected", [
    (0.001, 1), (0.1, 1), (0.1000001, 1), (0.15, 2), (1.0, 10), (2.0, 20), (52.663, 527), (52.167, 522),
    (30.003, 301), (7200.0, 72000),
])
def test_n_ticks_is_ceil_of_duration(duration, expected):
    assert tb.n_ticks(duration) == expected


@pytest.mark.parametrize("bad", [0.0, -1.0, float("nan"), float("inf")])
def test_empty_or_invalid_duration_is_an_error(bad):
    with pytest.raises(ParameterError):
        tb.n_ticks(bad)


def test_frames_to_ticks_takes_the_max_of_five_frames():
    x = np.zeros(12)
    x[3] = 0.7  # a 20 ms gunshot inside tick 0
    x[9] = 0.2
    x[10] = 0.4  # tick 2 (frames 10..14), frames 12..14 missing -> padded with 0
    out = tb.frames_to_ticks(x, 3)
    np.testing.assert_allclose(out, [0.7, 0.2, 0.4])


def test_frames_to_ticks_keeps_trailing_axes_and_truncates():
    x = np.arange(40, dtype=float).reshape(20, 2)
    out = tb.frames_to_ticks(x, 3)
    assert out.shape == (3, 2)
    np.testing.assert_allclose(out[:, 0], [8, 18, 28])


@pytest.mark.parametrize("dtype", [np.float64, np.float32, np.uint8, bool])
def test_frames_to_ticks_equals_the_max_over_each_ticks_frames(dtype):
    rng = np.random.default_rng(3)
    x = (rng.random((503, 3)) * 200).astype(dtype)
    out = tb.frames_to_ticks(x, 101)  # 503 frames: the last tick has 3, padded with zeros
    padded = np.concatenate([x, np.zeros((2, 3), dtype=dtype)])
    np.testing.assert_array_equal(out, padded.reshape(101, 5, 3).max(axis=1))
    assert out.dtype == x.dtype
    y = np.array([0.1, np.nan, 0.3, 0.2, 0.0, 0.5])
    np.testing.assert_array_equal(tb.frames_to_ticks(y, 2), [np.nan, 0.5])  # NaN propagates, as a max does


def test_tick_of_time_tolerates_rounding():
    assert tb.tick_of_time(0.3) == 3
    assert tb.tick_of_time(0.29999999) == 3
    np.testing.assert_array_equal(tb.tick_of_time(np.array([0.0, 0.05, 0.1, 0.19])), [0, 0, 1, 1])
