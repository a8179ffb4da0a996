"""The conversions the stages share (autohaptics.imaging)."""

from __future__ import annotations

import numpy as np
from hypothesis import given
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays

from autohaptics.imaging import finite32


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
