"""Medians, percentiles and quantiles (:mod:`autohaptics.quantiles`) are numpy's, bit for bit, and
computing them loads no masked-array module."""

from __future__ import annotations

import subprocess
import sys

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays

from autohaptics.quantiles import median, percentile, quantile

from shared_data import REPO

_values = st.one_of(
    arrays(np.float64, st.integers(1, 300), elements=st.floats(-1e6, 1e6, allow_nan=False, width=64)),
    arrays(np.float64, st.integers(1, 300), elements=st.sampled_from([0.0, 0.5, 1.0, 2.0, 1e-300])),
    arrays(np.uint8, st.integers(1, 300)),
    arrays(np.int64, st.integers(1, 50), elements=st.integers(-10**6, 10**6)))


@settings(max_examples=300, deadline=None)
@given(_values, st.one_of(st.floats(0, 100), st.integers(0, 100),
                          st.lists(st.floats(0, 100), min_size=1, max_size=4).map(tuple)))
def test_percentile_is_numpys(x, q):
    got, want = percentile(x, q), np.percentile(x, q)
    np.testing.assert_array_equal(got, want)
    assert np.asarray(got).dtype == np.asarray(want).dtype and np.ndim(got) == np.ndim(want)


@settings(max_examples=200, deadline=None)
@given(_values, st.floats(0, 1))
def test_quantile_is_numpys(x, q):
    np.testing.assert_array_equal(quantile(x, q), np.quantile(x, q))


def test_the_input_is_left_as_it_was():
    x = np.array([5.0, 1.0, 4.0, 2.0, 3.0])
    assert percentile(x, (5, 50, 95)).tolist() == np.percentile(x, (5, 50, 95)).tolist()
    assert x.tolist() == [5.0, 1.0, 4.0, 2.0, 3.0]


def test_no_masked_array_module_is_loaded():
    code = ("import sys, numpy as np\nfrom autohaptics.quantiles import median, percentile, quantile\n"
            "percentile(np.arange(10.0), (5, 50, 95)); quantile(np.arange(7, dtype=np.uint8), 0.3)\n"
            "median(np.arange(6.0)); median(np.ones((3, 4)), axis=1)\n"
            "print('numpy.ma' in sys.modules)")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120,
                         env={"PYTHONPATH": str(REPO / "backend")}).stdout.strip()
    assert out == "False"


@settings(max_examples=300, deadline=None)
@given(arrays(np.float64, st.tuples(st.integers(1, 40), st.integers(1, 12)),
              elements=st.floats(-1e6, 1e6, allow_nan=False, width=64)), st.sampled_from([None, 0, 1]))
def test_median_is_numpys(x, axis):
    got, want = median(x, axis=axis), np.median(x, axis=axis)
    np.testing.assert_array_equal(got, want)
    assert np.ndim(got) == np.ndim(want)
