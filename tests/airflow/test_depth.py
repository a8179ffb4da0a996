"""Nearness maps: the embedded cues with known answers, and tiny generated ONNX depth models."""

from __future__ import annotations

import cv2
import numpy as np
import pytest

from autohaptics.airflow import depth
from autohaptics.errors import ParameterError
from onnx_models import map_model

H, W = 72, 128


def noise_frame(shape=(H, W), seed=0) -> np.ndarray:
    return np.random.default_rng(seed).integers(0, 256, shape + (3,), dtype=np.uint8)


def expansion_flow(h: int, w: int, cx: float, cy: float, radius: float, rate: float) -> np.ndarray:
    """Flow (px/frame) of a disc of ``radius`` (frame widths) around (cx, cy) growing by ``rate``
    per frame: v = rate * (p - c) inside, 0 outside."""
    ys, xs = np.mgrid[0:h, 0:w].astype(np.float32)
    dx, dy = xs + 0.5 - cx * w, ys + 0.5 - cy * h
    inside = np.hypot(dx / w, dy / w) < radius
    return np.stack([rate * dx * inside, rate * dy * inside], axis=-1).astype(np.float32)


def test_position_cue_alone_is_the_row_height():
    """Ground-plane prior: nearness = (row + 0.5) / h, the same in every column."""
    p = depth.DepthParams(w_detail=0.0, w_expansion=0.0)
    near = depth.nearness_map(noise_frame(), params=p)
    np.testing.assert_allclose(near[:, 7], (np.arange(H) + 0.5) / H, rtol=1e-6)
    np.testing.assert_array_equal(near, np.repeat(near[:, :1], W, axis=1))


def test_expansion_cue_finds_what_comes_toward_the_camera():
    flow = expansion_flow(H, W, cx=0.75, cy=0.4, radius=0.12, rate=0.05)
    p = depth.DepthParams(w_position=0.0, w_detail=0.0, w_expansion=1.0)
    near = depth.nearness_map(noise_frame(), params=p, flow=flow)
    # divergence 2 * 0.05 per frame = 2.4 /s at 24 fps: beyond expansion_full (1 /s), saturated
    rows, cols = np.nonzero(near >= 0.99)
    assert rows.size > 50
    assert abs((cols.mean() + 0.5) / W - 0.75) < 0.03 and abs((rows.mean() + 0.5) / H - 0.4) < 0.05
    assert near[:, : W // 2].max() < 0.05  # nothing expands on the left
    # the default blend still puts the approaching region above the ground-plane prior
    default = depth.nearness_map(noise_frame(), flow=flow)
    assert default[int(0.4 * H), int(0.75 * W)] > default[int(0.4 * H), int(0.25 * W)] + 0.3


def test_expansion_cue_is_a_rate():
    """The cue is min(1, divergence / dt / expansion_full): a slow approach (divergence 0.01 per
    frame = 0.24 /s at 24 fps, 0.3 /s at 30 fps) reads 0.24 and 0.3 in the middle of the disc, and
    the same growth per second reads the same at any frame rate."""
    p = depth.DepthParams(w_position=0.0, w_detail=0.0, w_expansion=1.0, expansion_full=1.0, expansion_reach=0.0)
    flow24 = expansion_flow(H, W, cx=0.5, cy=0.5, radius=0.3, rate=0.005)  # div = 2 * 0.005 per frame
    mid = (H // 2, W // 2)
    assert depth.nearness_map(noise_frame(), params=p, flow=flow24)[mid] == pytest.approx(0.24, abs=0.01)
    assert depth.nearness_map(noise_frame(), params=p, flow=flow24, dt_s=1 / 30)[mid] == pytest.approx(0.3, abs=0.01)
    flow30 = expansion_flow(H, W, cx=0.5, cy=0.5, radius=0.3, rate=0.005 * 24 / 30)  # same growth per second
    assert depth.nearness_map(noise_frame(), params=p, flow=flow30, dt_s=1 / 30)[mid] == pytest.approx(0.24, abs=0.01)
    with pytest.raises(ParameterError, match="dt_s"):
        depth.nearness_map(noise_frame(), flow=flow24, dt_s=0.0)


def test_expansion_reaches_the_boundary_of_the_expanding_object():
    """The divergence lies inside an expanding disc; its image motion peaks at the boundary. With
    the default reach (0.05 frame widths) the cue at the boundary keeps 80 % of its value at the
    centre; without it, about half. (A slow approach, 0.24 /s: the cue is not saturated.)"""
    flow = expansion_flow(H, W, cx=0.6, cy=0.5, radius=0.15, rate=0.005)
    centre, edge = (H // 2, int(0.6 * W)), (H // 2, int(0.75 * W) - 1)
    outside = (H // 2, int(0.85 * W))  # 0.1 frame widths beyond the boundary
    cues = {}
    for reach in (0.05, 0.0):
        p = depth.DepthParams(w_position=0.0, w_detail=0.0, w_expansion=1.0, expansion_reach=reach)
        cues[reach] = depth.nearness_map(noise_frame(), params=p, flow=flow)
    assert cues[0.05][centre] == pytest.approx(0.48, abs=0.01)  # 0.24 /s over expansion_full 0.5 /s
    assert cues[0.05][edge] >= 0.8 * cues[0.05][centre]
    assert cues[0.0][edge] < 0.6 * cues[0.0][centre]
    assert cues[0.05][outside] < 0.3 * cues[0.05][centre]  # it does not spread much further


def flow_noise(h: int, w: int, sd_px: float, seed: int) -> np.ndarray:
    """Flow noise (px/frame) in specks about 2 px wide, as a lossy encode's blocks give the flow."""
    n = cv2.GaussianBlur(np.random.default_rng(seed).normal(size=(h, w, 2)).astype(np.float32), (0, 0), 1.0)
    return n / n.std() * sd_px


@pytest.mark.parametrize("seed", range(4))
def test_block_noise_is_not_an_approach_and_an_approach_still_is(seed):
    """A pan under flow noise whose divergence spreads 0.22 /s (robust std; a 240p screener's reads
    0.18 /s, an approach 0.5-1.1 /s): every speck's positive part, dilated, reads the whole frame as
    coming at the camera; opened by the default grain it reads next to nothing. A disc coming at the
    camera (divergence 0.48 /s, 0.12 frame widths in radius) under the same noise still reads near."""
    noise = flow_noise(H, W, 0.012, seed)
    pan = noise + np.array([2.0, 0.0], np.float32)
    specks = depth.DepthParams(w_position=0.0, w_detail=0.0, w_expansion=1.0, expansion_grain=0.0)
    opened = depth.DepthParams(w_position=0.0, w_detail=0.0, w_expansion=1.0)
    assert depth.nearness_map(noise_frame(), params=specks, flow=pan).mean() > 0.95
    assert depth.nearness_map(noise_frame(), params=opened, flow=pan).mean() < 0.1
    near = depth.nearness_map(noise_frame(), params=opened,
                              flow=expansion_flow(H, W, cx=0.7, cy=0.5, radius=0.12, rate=0.01) + noise)
    assert near[H // 2, int(0.7 * W)] > 0.8 and near[:, : W // 2].mean() < 0.1


def test_flow_of_another_size_is_rescaled():
    """Flow from a 160 px gray proxy used on a 128 px RGB proxy: same answer as native-size flow."""
    native = expansion_flow(H, W, 0.7, 0.5, 0.15, 0.04)
    big = expansion_flow(90, 160, 0.7, 0.5, 0.15, 0.04)  # same rate: px scale with the size
    p = depth.DepthParams(w_position=0.0, w_detail=0.0, w_expansion=1.0)
    a = depth.nearness_map(noise_frame(), params=p, flow=native)
    b = depth.nearness_map(noise_frame(), params=p, flow=big)
    assert np.abs(a - b).mean() < 0.03


def test_detail_cue_prefers_the_textured_region():
    frame = np.full((H, W, 3), 120, np.uint8)
    frame[20:50, 80:120] = noise_frame((30, 40), seed=3)
    p = depth.DepthParams(w_position=0.0, w_detail=1.0, w_expansion=0.0)
    near = depth.nearness_map(frame, params=p)
    assert near[30:40, 90:110].mean() > 0.5 and near[:, :40].max() < 0.1


def test_no_cue_available_gives_a_neutral_map():
    """Expansion without flow and detail on a frame too small for a Laplacian: nothing to rank."""
    p = depth.DepthParams(w_position=0.0, w_detail=1.0, w_expansion=1.0)
    np.testing.assert_array_equal(depth.nearness_map(noise_frame((2, 2)), params=p), np.full((2, 2), 0.5, np.float32))


@pytest.mark.parametrize("shape", [(1, 1), (1, 40), (40, 1), (16, 16), (H, W)])
def test_any_size_any_flow(shape):
    flow = np.random.default_rng(1).normal(size=shape + (2,)).astype(np.float32)
    for f in (None, flow, flow[:1, :1], np.full(shape + (2,), np.nan, np.float32)):
        near = depth.nearness_map(noise_frame(shape), flow=f)
        assert near.shape == shape and near.dtype == np.float32
        assert np.isfinite(near).all() and near.min() >= 0.0 and near.max() <= 1.0


# ---------------------------------------------------------------- ONNX backend
@pytest.mark.parametrize("layout", ["nchw", "nhwc"])
@pytest.mark.parametrize("kind", ["disparity", "depth"])
def test_onnx_depth_model(tmp_path, layout, kind):
    """A model that outputs brightness: as disparity, the bright half is near; as depth, far."""
    path = map_model(tmp_path / "bright.onnx", kind="mean", layout=layout)
    frame = np.zeros((H, W, 3), np.uint8)
    frame[:, W // 2:] = 220
    p = depth.DepthParams(backend="onnx", onnx_model=str(path), onnx_input_size=(64, 36), output_kind=kind,
                          onnx_mean=(0.0, 0.0, 0.0), onnx_std=(1.0, 1.0, 1.0))
    near = depth.nearness_map(frame, params=p, backend=depth.make_depth_backend(p))
    assert near.shape == (H, W) and near.dtype == np.float32
    bright, dark = near[:, -10:].mean(), near[:, :10].mean()
    if kind == "disparity":
        assert bright == pytest.approx(1.0) and dark == pytest.approx(0.0)
    else:
        assert bright == pytest.approx(0.0) and dark == pytest.approx(1.0)


@pytest.mark.parametrize("kind", ["disparity", "depth"])
def test_onnx_flat_output_is_all_far(tmp_path, kind):
    """A flat frame through the brightness model gives a constant map: no region is nearer than
    another, so nothing is near (a 'depth' output must not turn into 'everything near')."""
    path = map_model(tmp_path / "bright.onnx", kind="mean")
    p = depth.DepthParams(backend="onnx", onnx_model=str(path), onnx_input_size=(64, 36), output_kind=kind)
    near = depth.nearness_map(np.full((H, W, 3), 90, np.uint8), params=p, backend=depth.make_depth_backend(p))
    assert near.shape == (H, W) and near.dtype == np.float32
    assert not near.any()


def test_embedded_backend_needs_no_model():
    assert depth.make_depth_backend(depth.DepthParams()) is None


def test_onnx_errors_are_parameter_errors(tmp_path):
    with pytest.raises(ParameterError, match="needs depth.onnx_model"):
        depth.DepthParams(backend="onnx")
    with pytest.raises(ParameterError, match="no such ONNX depth model file"):
        depth.make_depth_backend(depth.DepthParams(backend="onnx", onnx_model=str(tmp_path / "missing.onnx")))
    bad = tmp_path / "bad.onnx"
    bad.write_bytes(b"\x00\x01 definitely not onnx")
    with pytest.raises(ParameterError, match=f"{bad}: not a loadable ONNX model"):
        depth.make_depth_backend(depth.DepthParams(backend="onnx", onnx_model=str(bad)))


@pytest.mark.parametrize("kwargs", [{"backend": "midas"}, {"output_kind": "inverse"}, {"w_position": -1.0},
                                    {"expansion_full": 0.0}, {"expansion_reach": 0.6},
                                    {"w_position": 0.0, "w_detail": 0.0, "w_expansion": 0.0}, {"proxy_width": 2}])
def test_params_are_checked(kwargs):
    with pytest.raises(ParameterError):
        depth.DepthParams(**kwargs)
