"""Property tests (hypothesis) over the vision stages: what must hold for every input. Frames that
break naive code (black, white, pure red/green/blue, grey, noise, ramps, one pixel wide) give
finite outputs in range with no division by zero; a brighter red is never colder; any salient
shape, including single pixels on triangle vertices and edges, gives valid actuator weights.
The per-stage contract (shape, dtype, range, determinism for fixed sizes) is test_vision_contract.py.
"""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from autohaptics import airflow, cuts, depth, fusion, saliency, thermal
from autohaptics.layout import ACTUATOR_IDS

A5 = np.eye(9)[ACTUATOR_IDS.index("A5")]


def _gray(rgb: np.ndarray) -> np.ndarray:
    return (rgb.astype(np.float64) @ [0.299, 0.587, 0.114]).round().astype(np.uint8)


# ---------------------------------------------------------------- hypothesis
KINDS = ("black", "white", "red", "green", "blue", "grey", "noise", "gradient")


def _frame(kind: str, h: int, w: int, seed: int) -> np.ndarray:
    colours = {"black": (0, 0, 0), "white": (255, 255, 255), "red": (255, 0, 0), "green": (0, 255, 0),
               "blue": (0, 0, 255), "grey": (128, 128, 128)}
    if kind in colours:
        return np.broadcast_to(np.array(colours[kind], np.uint8), (h, w, 3)).copy()
    if kind == "noise":
        return np.random.default_rng(seed).integers(0, 256, (h, w, 3), dtype=np.uint8)
    ramp = np.linspace(0, 255, w, dtype=np.float64)[None, :, None] * np.ones((h, 1, 3))
    return ramp.astype(np.uint8)


frames = st.builds(_frame, st.sampled_from(KINDS), st.integers(1, 48), st.sampled_from([1, 2, 17, 64]),
                   st.integers(0, 2**16))


@settings(max_examples=60, deadline=None)
@given(frames, frames)
def test_any_frame_gives_finite_outputs_in_range(f0, f1):
    if f1.shape != f0.shape:
        f1 = np.resize(f1, f0.shape)
    with np.errstate(divide="raise", invalid="raise"):
        smap = saliency.saliency_map(f0)
        beta = fusion.actuator_weights(smap)
        temp = thermal.temperature_target(thermal.mean_colour(f0)[None])
        flow = airflow.optical_flow(_gray(f0), _gray(f1))
        mag = airflow.motion_magnitude(flow, dt_s=0.04, width_px=f0.shape[1])
        near = depth.nearness_map(f0, flow=flow)
        fans = airflow.fan_levels(airflow.cell_motion(mag), airflow.grid_means(near))
        score = cuts.cut_score(cuts.frame_signature(f0), cuts.frame_signature(f1))
    for arr, lo, hi in ((smap, 0, 1), (beta, 0, 1), (temp, 30, 55), (near, 0, 1), (fans, 0, 1),
                        (np.float64(score), 0, 1)):
        assert np.isfinite(arr).all() and np.min(arr) >= lo and np.max(arr) <= hi
    assert beta.max() == 1.0
    assert np.isfinite(mag).all() and (mag >= 0).all()


@settings(max_examples=40, deadline=None)
@given(st.sampled_from(["black", "white", "red", "green", "blue", "grey"]), st.integers(1, 40), st.integers(1, 40))
def test_flat_frames_have_no_salient_region(kind, h, w):
    f = _frame(kind, h, w, 0)
    smap = saliency.saliency_map(f)
    assert not smap.any()
    np.testing.assert_array_equal(fusion.actuator_weights(smap), A5)
    assert not airflow.optical_flow(_gray(f), _gray(f)).any()


@settings(max_examples=200, deadline=None)
@given(st.integers(0, 255), st.integers(0, 255), st.integers(0, 255), st.integers(1, 255), st.booleans())
def test_a_brighter_red_is_never_colder(r, g, b, dr, neutral_aware):
    params = thermal.ThermalParams(neutral_aware=neutral_aware)
    # Pure reds of rising brightness, in both modes.
    lo, hi = sorted((r, min(255, r + dr)))
    t_lo, t_hi = thermal.temperature_target(np.array([[lo, 0, 0], [hi, 0, 0]], float), params=params)
    assert t_hi >= t_lo - 1e-12
    # More red in any colour (DisR falls, DisG rises; neutral-aware: see the thermal module docstring).
    c0 = np.array([[r, g, b]], float)
    c1 = np.array([[min(255, r + dr), g, b]], float)
    t0, t1 = (thermal.temperature_target(c, params=params)[0] for c in (c0, c1))
    assert t1 >= t0 - 1e-9


@settings(max_examples=100, deadline=None)
@given(st.integers(1, 60), st.integers(1, 60), st.data())
def test_any_salient_shape_gives_weights_in_range(h, w, data):
    """Random shapes, including single pixels on triangle vertices and edges: no division by zero."""
    n = data.draw(st.integers(0, 5))
    shape = np.zeros((h, w), bool)
    for _ in range(n):
        shape[data.draw(st.integers(0, h - 1)), data.draw(st.integers(0, w - 1))] = True
    with np.errstate(divide="raise", invalid="raise"):
        for variant in fusion.VARIANTS:
            beta = fusion.actuator_weights(shape=shape, params=fusion.FusionParams(variant=variant))
            assert beta.shape == (9,) and np.isfinite(beta).all()
            assert beta.min() >= 0 and beta.max() == 1.0
    if n == 0:
        np.testing.assert_array_equal(beta, A5)


@pytest.mark.parametrize("xy", [(1 / 3, 0.0), (2 / 3, 0.0), (0.0, 0.5), (0.25, 0.5), (0.5, 0.5), (0.75, 0.5),
                                (1.0, 0.5), (1 / 3, 1.0), (2 / 3, 1.0), (0.0, 0.0), (1.0, 1.0)])
def test_centroid_on_any_vertex_is_safe(xy):
    for tri in range(14):
        with np.errstate(divide="raise", invalid="raise"):
            w = fusion.triangle_weights(xy, tri)
        assert np.isfinite(w).all() and w.sum() == pytest.approx(1.0)


@settings(max_examples=100, deadline=None)
@given(st.lists(st.floats(20.0, 60.0), min_size=1, max_size=80), st.floats(0.05, 20.0), st.integers(0, 80))
def test_slew_limit_respects_the_rate_and_chunked_equals_whole(temps, rate, split):
    x = np.asarray(temps)
    whole = thermal.slew_limit(x, max_rate_c_per_s=rate, tick_s=0.1)
    assert np.all(np.abs(np.diff(whole)) <= rate * 0.1 + 1e-9)
    assert whole[0] == x[0]
    k = min(split, x.size)
    first = thermal.slew_limit(x[:k], max_rate_c_per_s=rate, tick_s=0.1)
    rest = thermal.slew_limit(x[k:], max_rate_c_per_s=rate, tick_s=0.1,
                              start_c=float(first[-1]) if k else None)
    np.testing.assert_allclose(np.concatenate([first, rest]), whole, rtol=0, atol=1e-9)
