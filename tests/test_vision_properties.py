"""Contract and property tests over every vision stage (like PySceneDetect's ALL_DETECTORS):
shape for any input size (down to one pixel wide), dtype, range, finiteness and determinism;
hypothesis properties for frames that break naive code (black, white, pure colours, noise)."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from autohaptics import airflow, cuts, depth, fusion, saliency, thermal
from autohaptics.layout import ACTUATOR_IDS, FAN_COLS, FAN_ROWS

SIZES = [(1, 1), (9, 1), (1, 16), (16, 16), (37, 53), (72, 128)]
A5 = np.eye(9)[ACTUATOR_IDS.index("A5")]


def _frames(h: int, w: int, seed: int = 0) -> tuple[np.ndarray, np.ndarray]:
    """Two RGB frames with structure and a small motion between them."""
    rng = np.random.default_rng(seed)
    base = rng.integers(0, 256, (h + 2, w + 2, 3), dtype=np.uint8)
    return np.ascontiguousarray(base[1:-1, 1:-1]), np.ascontiguousarray(base[1:-1, 2:])


def _gray(rgb: np.ndarray) -> np.ndarray:
    return (rgb.astype(np.float64) @ [0.299, 0.587, 0.114]).round().astype(np.uint8)


@dataclass(frozen=True)
class Stage:
    name: str
    run: Callable[[np.ndarray, np.ndarray], object]  # (rgb0, rgb1) -> output
    shape: Callable[[int, int], tuple]
    dtype: type
    lo: float
    hi: float


def _flow(a, b):
    return airflow.optical_flow(_gray(a), _gray(b))


STAGES = [
    Stage("saliency spectral", lambda a, b: saliency.saliency_map(a), lambda h, w: (h, w), np.float32, 0, 1),
    Stage("saliency fine_grained", lambda a, b: saliency.saliency_map(
        a, params=saliency.SaliencyParams(backend="fine_grained")), lambda h, w: (h, w), np.float32, 0, 1),
    Stage("saliency with motion", lambda a, b: saliency.saliency_map(
        b, params=saliency.SaliencyParams(motion_weight=0.5), prev_gray=_gray(a)), lambda h, w: (h, w), np.float32, 0, 1),
    Stage("salient shape", lambda a, b: fusion.salient_shape(saliency.saliency_map(a)), lambda h, w: (h, w), np.bool_, 0, 1),
    Stage("triangle map", lambda a, b: fusion.triangle_index_map(*a.shape[:2]), lambda h, w: (h, w), np.int8, 0, 13),
    Stage("actuator weights paper", lambda a, b: fusion.actuator_weights(saliency.saliency_map(a)),
          lambda h, w: (9,), np.float64, 0, 1),
    Stage("actuator weights mass", lambda a, b: fusion.actuator_weights(
        saliency.saliency_map(a), params=fusion.FusionParams(variant="mass")), lambda h, w: (9,), np.float64, 0, 1),
    Stage("mean colour", lambda a, b: thermal.mean_colour(a), lambda h, w: (3,), np.float64, 0, 255),
    Stage("temperature", lambda a, b: thermal.temperature_target(thermal.mean_colour(a)[None]),
          lambda h, w: (1,), np.float64, 30, 55),
    Stage("temperature neutral-aware", lambda a, b: thermal.temperature_target(
        thermal.mean_colour(a)[None], params=thermal.ThermalParams(neutral_aware=True)),
          lambda h, w: (1,), np.float64, 30, 55),
    Stage("flow dis", _flow, lambda h, w: (h, w, 2), np.float32, -np.inf, np.inf),
    Stage("flow farneback", lambda a, b: airflow.optical_flow(
        _gray(a), _gray(b), params=airflow.FlowParams(method="farneback")), lambda h, w: (h, w, 2), np.float32,
          -np.inf, np.inf),
    Stage("motion magnitude", lambda a, b: airflow.motion_magnitude(_flow(a, b), dt_s=1 / 24, width_px=a.shape[1]),
          lambda h, w: (h, w), np.float32, 0, np.inf),
    Stage("cell motion", lambda a, b: airflow.cell_motion(
        airflow.motion_magnitude(_flow(a, b), dt_s=1 / 24, width_px=a.shape[1])),
          lambda h, w: (FAN_ROWS, FAN_COLS), np.float32, 0, np.inf),
    Stage("nearness embedded", lambda a, b: depth.nearness_map(a, flow=_flow(a, b)), lambda h, w: (h, w),
          np.float32, 0, 1),
    Stage("nearness grid", lambda a, b: airflow.grid_means(depth.nearness_map(a)),
          lambda h, w: (FAN_ROWS, FAN_COLS), np.float32, 0, 1),
    Stage("fan levels", lambda a, b: airflow.fan_levels(
        airflow.cell_motion(airflow.motion_magnitude(_flow(a, b), dt_s=1 / 24, width_px=a.shape[1])),
        airflow.grid_means(depth.nearness_map(a, flow=_flow(a, b)))), lambda h, w: (FAN_ROWS, FAN_COLS),
          np.float32, 0, 1),
    Stage("signature", lambda a, b: cuts.frame_signature(a), lambda h, w: (cuts.frame_signature(
        np.zeros((2, 2, 3), np.uint8)).size,), np.float32, 0, 255),
    Stage("cut score", lambda a, b: np.float64(cuts.cut_score(cuts.frame_signature(a), cuts.frame_signature(b))),
          lambda h, w: (), np.float64, 0, 1),
]


@pytest.mark.parametrize("size", SIZES, ids=[f"{h}x{w}" for h, w in SIZES])
@pytest.mark.parametrize("stage", STAGES, ids=[s.name for s in STAGES])
def test_stage_contract(stage, size):
    h, w = size
    a, b = _frames(h, w)
    out = np.asarray(stage.run(a, b))
    assert out.shape == stage.shape(h, w)
    assert out.dtype == stage.dtype
    if out.dtype != np.bool_:
        assert np.isfinite(out).all()
        assert out.min() >= stage.lo and out.max() <= stage.hi
    again = np.asarray(stage.run(a.copy(), b.copy()))
    np.testing.assert_array_equal(out, again)  # deterministic, no hidden state


def test_static_check_contract():
    for h, w in SIZES:
        a, b = _frames(h, w)
        assert airflow.is_static(_gray(a), _gray(a)) is True
        assert isinstance(airflow.is_static(_gray(a), _gray(b)), bool)


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
    # More red in any colour (the plain formula: DisR falls, DisG rises).
    if not neutral_aware:
        c0 = np.array([[r, g, b]], float)
        c1 = np.array([[min(255, r + dr), g, b]], float)
        assert thermal.temperature_target(c1)[0] >= thermal.temperature_target(c0)[0] - 1e-12


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
