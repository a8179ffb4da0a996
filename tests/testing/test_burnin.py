"""Film grain as ``testing.burnin`` burns it in (the matrix's grain row): its spread, new every frame,
the same frame's grain in every copy."""

from __future__ import annotations

import numpy as np

from autohaptics.testing import burnin


def test_grain_has_its_spread_and_is_new_every_frame():
    picture = np.full((120, 200, 3), 100, np.uint8)
    a, b = burnin.burn(picture, "grain", 0, 25.0), burnin.burn(picture, "grain", 1, 25.0)
    assert a.shape == picture.shape and a.dtype == np.uint8
    assert abs(float(a[..., 0].astype(float).std()) - burnin.GRAIN_SD) < 0.3
    assert (a[..., 0] == a[..., 1]).all() and (a[..., 0] == a[..., 2]).all()  # brightness only
    assert np.corrcoef(a[..., 0].ravel(), b[..., 0].ravel())[0, 1] < 0.05  # new every frame
    assert (burnin.burn(picture, "grain", 1, 25.0) == b).all()  # the same frame's grain in every copy
    assert (picture == 100).all()  # the source is left as it was
