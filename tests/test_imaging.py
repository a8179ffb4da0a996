"""The conversions the stages share (autohaptics.imaging)."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays

from autohaptics.errors import ParameterError
from autohaptics.imaging import finite32, noise_over, noise_response, noise_sd


@given(arrays(st.sampled_from([np.float32, np.float64]), st.tuples(st.integers(1, 6), st.integers(1, 6)),
              elements=st.floats(allow_nan=True, allow_infinity=True, width=32)))
def test_finite32_is_the_masked_select(x):
    """The same values as a masked select of the finite ones, as float32, for any input."""
    out = finite32(x)
    assert out.dtype == np.float32 and out.shape == x.shape
    np.testing.assert_array_equal(out, np.where(np.isfinite(x), x, 0.0).astype(np.float32))


def test_finite32_keeps_a_finite_float32_array():
    x = np.linspace(0, 1, 12, dtype=np.float32).reshape(3, 4)
    assert finite32(x) is x
    y = x.copy()
    y[1, 2] = np.nan
    assert finite32(y) is not y and finite32(y)[1, 2] == 0.0 and np.isnan(y[1, 2])


def test_noise_sd_reads_white_noise_over_flat_ramps_and_edges():
    """Known answers: Gaussian noise of sd 5 reads 5 (within 5 %) on a flat grey, on a ramp and over a
    picture whose edges (a checkerboard of 16 px squares) cover under half of it; the pictures alone read 0;
    two such frames' difference (the difference of their responses) reads 5 x sqrt(2)."""
    rng = np.random.default_rng(3)
    h, w = 90, 160
    flat = np.full((h, w), 120.0)
    ramp = np.tile(np.linspace(40, 200, w), (h, 1))
    checks = np.where((np.indices((h, w)) // 16).sum(axis=0) % 2 == 0, 70.0, 170.0)
    for picture in (flat, ramp, checks):
        assert noise_sd(noise_response(picture.astype(np.uint8))) == 0.0
        noisy = np.clip(picture + rng.normal(0, 5, (h, w)), 0, 255).astype(np.uint8)
        assert noise_sd(noise_response(noisy)) == pytest.approx(5.0, rel=0.05)
    a, b = (noise_response(np.clip(flat + rng.normal(0, 5, (h, w)), 0, 255).astype(np.uint8)) for _ in range(2))
    assert noise_sd(a - b) == pytest.approx(5.0 * np.sqrt(2), rel=0.05)


def test_noise_sd_takes_a_response_only():
    assert noise_response(np.zeros((2, 50), np.uint8)).shape == (0, 48)
    assert noise_sd(noise_response(np.zeros((2, 50), np.uint8))) == 0.0  # no inner pixels
    for bad in (np.zeros((8, 8), np.float32), np.zeros((8, 8), np.uint8), np.zeros((8, 8, 3), np.int16)):
        with pytest.raises(ParameterError, match="noise_sd"):
            noise_sd(bad)


@given(arrays(np.uint8, st.tuples(st.integers(1, 40), st.integers(1, 40))))
def test_noise_sd_is_finite_and_in_range(x):
    """0 <= noise <= 1.4826 x 255 / 6 (a response counts up to 255), for any picture and difference."""
    r = noise_response(x)
    assert r.dtype == np.int16 and r.shape == (max(x.shape[0] - 2, 0), max(x.shape[1] - 2, 0))
    for response in (r, r - noise_response(255 - x)):
        assert 0.0 <= noise_sd(response) <= 1.4826 * 255 / 6


@given(arrays(np.uint8, st.tuples(st.integers(1, 30), st.integers(1, 30))), st.floats(-1.0, 80.0))
def test_noise_over_is_the_estimate_against_a_bar(x, sd):
    """``noise_over(r, sd)`` is ``noise_sd(r) > sd`` for any picture, difference and bar (63 the most it reads)."""
    r = noise_response(x)
    for response in (r, r - noise_response(255 - x)):
        assert noise_over(response, sd) == (noise_sd(response) > sd)
    for bar in (1.4826 * 8 / 6, 63.0105, 1e9, -1e-9):
        assert noise_over(r, bar) == (noise_sd(r) > bar)
    with pytest.raises(ParameterError, match="noise_over"):
        noise_over(x, sd)
