"""One contract over every vision stage (PySceneDetect's ALL_DETECTORS idea).

For every stage and every frame size (one pixel, one pixel wide or tall, 16 x 16, odd sizes, a
real proxy): the output's shape, dtype and range, finiteness, determinism (the same input twice
gives an identical output), and the neutral output when there is nothing to see (a flat frame has
no saliency, an empty map puts everything on A5, a too-small proxy has no flow, identical frames
no motion and no cut, no depth cue a neutral 0.5).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import cv2
import numpy as np
import pytest

from autohaptics import airflow, fusion
from autohaptics.airflow import cuts
from autohaptics.airflow import depth
from autohaptics.fusion import saliency
from autohaptics import temperature as thermal
from autohaptics.layout import ACTUATOR_IDS, FAN_COLS, FAN_ROWS
from onnx_models import map_model

SIZES = [(1, 1), (1, 17), (17, 1), (2, 3), (16, 16), (9, 17), (31, 7), (72, 128)]
GRID = (FAN_ROWS, FAN_COLS)
A5 = np.eye(9)[ACTUATOR_IDS.index("A5")]


@dataclass(frozen=True)
class Inputs:
    rgb: np.ndarray       # the analysed frame, uint8 (h, w, 3)
    prev_rgb: np.ndarray  # the frame before it
    models: dict

    @property
    def gray(self) -> np.ndarray:
        return cv2.cvtColor(self.rgb, cv2.COLOR_RGB2GRAY)

    @property
    def prev_gray(self) -> np.ndarray:
        return cv2.cvtColor(self.prev_rgb, cv2.COLOR_RGB2GRAY)


@dataclass(frozen=True)
class Stage:
    name: str
    run: Callable[[Inputs], object]
    shape: Callable[[int, int], tuple]
    dtype: type
    lo: float
    hi: float
    # (inputs builder for the neutral case, check of the neutral output)
    neutral: Callable[[Inputs], Inputs]
    neutral_ok: Callable[[object, tuple], bool]


def same_frame(x: Inputs) -> Inputs:
    """Nothing moved: the previous frame is the frame."""
    return Inputs(x.rgb, x.rgb, x.models)


def flat_frame(x: Inputs) -> Inputs:
    flat = np.full_like(x.rgb, 77)
    return Inputs(flat, flat, x.models)


def zeros_of(shape) -> Callable[[object, tuple], bool]:
    return lambda out, hw: np.array_equal(out, np.zeros(shape(*hw)))


def flow_of(x: Inputs) -> np.ndarray:
    return airflow.optical_flow(x.prev_gray, x.gray)


def fans_of(x: Inputs) -> np.ndarray:
    flow = flow_of(x)
    mag = airflow.motion_magnitude(flow, dt_s=1 / 24, width_px=x.gray.shape[1])
    return airflow.fan_levels(airflow.cell_motion(mag), airflow.grid_means(depth.nearness_map(x.rgb, flow=flow)))


def sal(**kw) -> Callable[[Inputs], np.ndarray]:
    def run(x: Inputs) -> np.ndarray:
        params = saliency.SaliencyParams(**{k: (x.models[v] if k == "onnx_model" else v) for k, v in kw.items()})
        return saliency.saliency_map(x.rgb, params=params, prev_gray=x.prev_gray)
    return run


def near(**kw) -> Callable[[Inputs], np.ndarray]:
    def run(x: Inputs) -> np.ndarray:
        params = depth.DepthParams(**{k: (x.models[v] if k == "onnx_model" else v) for k, v in kw.items()})
        return depth.nearness_map(x.rgb, params=params, flow=flow_of(x))
    return run


HW = lambda h, w: (h, w)  # noqa: E731
INF = float("inf")

STAGES = [
    Stage("saliency-spectral", sal(), HW, np.float32, 0, 1, flat_frame, zeros_of(HW)),
    Stage("saliency-fine-grained", sal(backend="fine_grained"), HW, np.float32, 0, 1, flat_frame, zeros_of(HW)),
    Stage("saliency-motion", sal(motion_weight=0.5), HW, np.float32, 0, 1, flat_frame, zeros_of(HW)),
    Stage("saliency-onnx-nchw", sal(backend="onnx", onnx_model="nchw", onnx_input_size=(32, 24)), HW, np.float32, 0, 1,
          flat_frame, zeros_of(HW)),
    Stage("saliency-onnx-nhwc", sal(backend="onnx", onnx_model="nhwc", onnx_input_size=(32, 24)), HW, np.float32, 0, 1,
          flat_frame, zeros_of(HW)),
    Stage("salient-shape", lambda x: fusion.salient_shape(sal()(x)), HW, np.bool_, 0, 1, flat_frame,
          lambda out, hw: not out.any()),
    Stage("fusion-paper", lambda x: fusion.actuator_weights(sal()(x)), lambda h, w: (9,), np.float64, 0, 1,
          flat_frame, lambda out, hw: np.array_equal(out, A5)),
    Stage("fusion-mass", lambda x: fusion.actuator_weights(sal()(x), params=fusion.FusionParams(variant="mass")),
          lambda h, w: (9,), np.float64, 0, 1, flat_frame, lambda out, hw: np.array_equal(out, A5)),
    Stage("temperature", lambda x: thermal.temperature_target(thermal.mean_colour(x.rgb)), lambda h, w: (),
          np.float64, 30, 55, flat_frame, lambda out, hw: out == 42.5),  # grey: equidistant from red and green
    Stage("temperature-neutral-aware",
          lambda x: thermal.temperature_target(thermal.mean_colour(x.rgb), params=thermal.ThermalParams(neutral_aware=True)),
          lambda h, w: (), np.float64, 30, 55, flat_frame, lambda out, hw: out == 33.0),
    Stage("flow-dis", flow_of, lambda h, w: (h, w, 2), np.float32, -INF, INF, same_frame,
          lambda out, hw: np.abs(out).max() < 0.05 if min(hw) >= 16 else np.array_equal(out, np.zeros(hw + (2,)))),
    # OpenCV's Farneback leaves up to ~0.6 px of flow within 5 px of the border on identical frames
    Stage("flow-farneback", lambda x: airflow.optical_flow(x.prev_gray, x.gray, params=airflow.FlowParams(method="farneback")),
          lambda h, w: (h, w, 2), np.float32, -INF, INF, same_frame,
          lambda out, hw: np.abs(out[5:-5, 5:-5]).max(initial=0) < 0.05 and np.abs(out).mean() < 0.02
          if min(hw) >= 16 else np.array_equal(out, np.zeros(hw + (2,)))),
    Stage("cell-motion", lambda x: airflow.cell_motion(airflow.motion_magnitude(flow_of(x), dt_s=1 / 24,
                                                                                width_px=x.rgb.shape[1])),
          lambda h, w: GRID, np.float32, 0, INF, same_frame, lambda out, hw: out.max() < 0.05),
    Stage("static", lambda x: np.bool_(airflow.is_static(x.prev_gray, x.gray)), lambda h, w: (), np.bool_, 0, 1,
          same_frame, lambda out, hw: bool(out)),
    Stage("fans", fans_of, lambda h, w: GRID, np.float32, 0, 1, flat_frame, zeros_of(lambda h, w: GRID)),
    Stage("cut-score", lambda x: np.float64(cuts.cut_score(cuts.frame_signature(x.prev_rgb), cuts.frame_signature(x.rgb))),
          lambda h, w: (), np.float64, 0, 1, same_frame, lambda out, hw: out == 0.0),
    Stage("cut-score-gray", lambda x: np.float64(cuts.cut_score(cuts.frame_signature(x.prev_gray), cuts.frame_signature(x.gray))),
          lambda h, w: (), np.float64, 0, 1, same_frame, lambda out, hw: out == 0.0),
    Stage("nearness-embedded", near(), HW, np.float32, 0, 1, flat_frame,
          lambda out, hw: np.ptp(out, axis=1).max() < 1e-6 if min(hw) > 0 else True),  # flat: the ground plane alone
    Stage("nearness-expansion", near(w_position=0.0, w_detail=0.0, w_expansion=1.0), HW, np.float32, 0, 1,
          flat_frame,  # nothing moves: nothing approaches; too small for a divergence: no cue, 0.5
          lambda out, hw: out.max() < 0.05 if min(hw) >= 3 else np.array_equal(out, np.full(hw, 0.5, np.float32))),
    Stage("nearness-onnx", near(backend="onnx", onnx_model="nhwc", onnx_input_size=(24, 16), output_kind="depth"), HW,
          np.float32, 0, 1, flat_frame, zeros_of(HW)),
]


@pytest.fixture(scope="module")
def models(tmp_path_factory) -> dict:
    d = tmp_path_factory.mktemp("onnx")
    return {"nchw": str(map_model(d / "nchw.onnx", layout="nchw")), "nhwc": str(map_model(d / "nhwc.onnx", layout="nhwc"))}


def frames(h: int, w: int) -> tuple[np.ndarray, np.ndarray]:
    """A textured frame with a bright block, and the previous frame (the block one pixel left)."""
    rng = np.random.default_rng(h * 1000 + w)
    base = cv2.GaussianBlur(rng.integers(0, 256, (h, w, 3)).astype(np.float32), (0, 0), 1.0) if min(h, w) > 2 \
        else rng.integers(0, 256, (h, w, 3)).astype(np.float32)
    cur = base.copy()
    cur[h // 4: h // 4 + max(1, h // 3), w // 2: w // 2 + max(1, w // 4)] = 250
    prev = np.roll(cur, -1, axis=1) if w > 1 else base
    return np.clip(cur, 0, 255).astype(np.uint8), np.clip(prev, 0, 255).astype(np.uint8)


def check(stage: Stage, out, hw) -> None:
    arr = np.asarray(out)
    assert arr.shape == stage.shape(*hw), f"{stage.name}: shape {arr.shape}"
    assert arr.dtype == stage.dtype, f"{stage.name}: dtype {arr.dtype}"
    if arr.dtype != np.bool_:
        assert np.isfinite(arr).all(), f"{stage.name}: non-finite output"
        assert arr.min(initial=stage.lo) >= stage.lo and arr.max(initial=stage.hi) <= stage.hi, f"{stage.name}: range"


@pytest.mark.parametrize("size", SIZES, ids=[f"{h}x{w}" for h, w in SIZES])
@pytest.mark.parametrize("stage", STAGES, ids=[s.name for s in STAGES])
def test_stage_contract(stage: Stage, size, models):
    rgb, prev = frames(*size)
    x = Inputs(rgb, prev, models)
    with np.errstate(divide="raise", invalid="raise", over="raise"):
        out = stage.run(x)
        check(stage, out, size)
        again = stage.run(Inputs(rgb.copy(), prev.copy(), models))
        np.testing.assert_array_equal(np.asarray(again), np.asarray(out), err_msg=f"{stage.name}: not deterministic")
        neutral = stage.run(stage.neutral(x))
        check(stage, neutral, size)
        assert stage.neutral_ok(neutral, size), f"{stage.name}: neutral output {neutral!r}"
