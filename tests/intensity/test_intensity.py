import numpy as np
import pytest
from hypothesis import given, settings, strategies as st
from hypothesis.extra import numpy as hnp

from autohaptics import intensity as it
from autohaptics.errors import ParameterError


def _features(values):
    return {name: np.array([v], float) for name, v in zip(it.FEATURES, values)}


def test_thesis_example_takes_the_largest_value():
    # (sharpness, booming, low_energy, loudness) = (0.6, 0.4, 0.5, 0.9) -> 0.9
    out = it.frame_intensity(_features((0.6, 0.4, 0.5, 0.9)), params=it.IntensityParams())
    np.testing.assert_allclose(out, [0.9])


def test_below_every_threshold_is_zero():
    out = it.frame_intensity(_features((0.49, 0.64, 0.79, 0.84)), params=it.IntensityParams())
    assert out[0] == 0.0


def test_one_feature_over_its_threshold_triggers_the_max_of_all():
    # booming over 0.65 triggers, but loudness (0.8, below its own threshold) is the largest
    out = it.frame_intensity(_features((0.1, 0.7, 0.2, 0.8)), params=it.IntensityParams())
    np.testing.assert_allclose(out, [0.8])


def test_silence_normalises_to_zeros_not_nan():
    out = it.normalise(np.zeros(10))
    assert np.all(out == 0) and np.isfinite(out).all()
    out = it.normalise(np.zeros(10), method="percentile")
    assert np.all(out == 0)


def test_percentile_normaliser_resists_one_explosion():
    x = np.full(1000, 1.0)
    x[500] = 1000.0
    by_max = it.normalise(x)
    robust = it.normalise(x, method="percentile", percentile=99.0)
    assert by_max[0] < 0.01
    assert robust[0] == pytest.approx(1.0)
    assert robust.max() == 1.0


def test_ticks_take_the_max_of_their_frames():
    norm = {f: np.zeros(10) for f in it.FEATURES}
    norm["loudness"][7] = 0.95  # one 20 ms frame in tick 1
    out = it.tick_intensity(norm, 2, params=it.IntensityParams())
    np.testing.assert_allclose(out, [0.0, 0.95])


def test_invalid_params_are_rejected():
    with pytest.raises(ParameterError, match="unknown threshold"):
        it.IntensityParams(thresholds={"bass": 0.5})
    with pytest.raises(ParameterError, match="normaliser"):
        it.IntensityParams(normaliser="median")
    with pytest.raises(ParameterError, match="non-finite"):
        it.normalise(np.array([1.0, np.nan]))


@settings(max_examples=60, deadline=None)
@given(hnp.arrays(np.float64, st.integers(1, 60), elements=st.floats(0, 1e6)),
       st.sampled_from(["max", "percentile"]))
def test_normalised_values_are_finite_and_in_range(x, method):
    out = it.normalise(x, method=method)
    assert out.shape == x.shape
    assert np.isfinite(out).all() and out.min() >= 0 and out.max() <= 1


@settings(max_examples=60, deadline=None)
@given(hnp.arrays(np.float64, (4, 15), elements=st.floats(0, 1)),
       st.lists(st.floats(0, 1.2), min_size=4, max_size=4))
def test_intensity_is_in_range_and_zero_or_a_feature_value(stack, thresholds):
    norm = dict(zip(it.FEATURES, stack))
    params = it.IntensityParams(thresholds=dict(zip(it.FEATURES, thresholds)))
    out = it.frame_intensity(norm, params=params)
    assert np.isfinite(out).all() and out.min() >= 0 and out.max() <= 1
    for k in range(stack.shape[1]):
        assert out[k] == 0 or out[k] == stack[:, k].max()
