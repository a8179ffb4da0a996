"""The loudness kernels as loaded (the extension built ahead of time) compute exactly what their
source does under numba's JIT; filter designs read back from the cache folder are the ones built."""

from __future__ import annotations

import numpy as np
import pytest
import scipy.signal as ss

from autohaptics import cachedir
from autohaptics.intensity import compiled
from autohaptics.intensity import kernels as jit
from autohaptics.intensity.filterbank import fast_design, plan

RNG = np.random.default_rng(7)


def _run_both(name: str, make_args) -> None:
    """Run kernel ``name`` through the loaded module and the JIT on identical copies of its arguments;
    every array (outputs and in/out states) must come out bit-identical."""
    a, b = make_args(), make_args()
    getattr(compiled.load(), name)(*a)
    getattr(jit, name)(*b)
    for x, y in zip(a, b):
        if isinstance(x, np.ndarray):
            np.testing.assert_array_equal(x, y)


def test_loaded_kernels_are_the_extension_module():
    mod = compiled.load()
    assert mod.__name__ == compiled.module_name()
    assert all(callable(getattr(mod, name)) for name in compiled.SIGNATURES)


@pytest.mark.parametrize("layout", ["contiguous", "strided"])
def test_filter_kernels_match_jit(layout):
    x = RNG.standard_normal(4801)
    if layout == "strided":  # any layout is accepted
        x = np.repeat(x, 2)[::2]
    sos = np.ascontiguousarray(plan("fast").stages[0].sos)
    _run_both("sos_decimate", lambda: (x, sos, np.zeros((sos.shape[0], 2)), 1, 2, np.empty(2400)))
    grp = plan("fast").groups[1]
    n_b = len(grp.bands)
    _run_both("bank_square_smooth", lambda: (x, grp.sos, grp.gain, grp.smooth_a, np.zeros((n_b, 3, 2)),
                                             np.zeros((n_b, 3)), 0, grp.step,
                                             np.empty((n_b, -(-x.shape[0] // grp.step)))))
    _run_both("bank_mean_square", lambda: (x, grp.sos, grp.gain, 100, np.empty(n_b)))


def test_first_order_kernel_is_lfilter():
    x = np.abs(RNG.standard_normal(3000)) * 10.0
    b_now, b_prev, pole = 0.03, 0.01, 0.96
    y = np.empty_like(x)
    state = np.array([0.5])
    compiled.first_order(x, b_now, b_prev, pole, state, y)
    ref, zf = ss.lfilter([b_now, b_prev], [1.0, -pole], x, zi=[0.5])
    np.testing.assert_array_equal(y, ref)
    assert state[0] == zf[0]


def test_cached_arrays_round_trip(tmp_path, monkeypatch):
    monkeypatch.setenv(cachedir.CACHE_ENV, str(tmp_path / "cache"))
    cachedir._root.cache_clear()
    try:
        first = cachedir.cached_arrays("filters", "fast-test", fast_design)
        built = list((tmp_path / "cache" / "filters").glob("fast-test.npz"))
        again = cachedir.cached_arrays("filters", "fast-test", lambda: pytest.fail("read from the cache, not rebuilt"))
    finally:
        cachedir._root.cache_clear()
    assert built and first.keys() == again.keys()
    for k in first:
        np.testing.assert_array_equal(first[k], again[k])


def test_unwritable_cache_folder_still_computes(tmp_path, monkeypatch):
    ro = tmp_path / "ro"
    ro.mkdir()
    ro.chmod(0o500)
    monkeypatch.setenv(cachedir.CACHE_ENV, str(ro / "cache"))
    cachedir._root.cache_clear()
    try:
        arrays = cachedir.cached_arrays("filters", "k", lambda: {"a": np.arange(3.0)})
    finally:
        cachedir._root.cache_clear()
        ro.chmod(0o700)
    np.testing.assert_array_equal(arrays["a"], np.arange(3.0))
