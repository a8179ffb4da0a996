"""Saliency maps: classical backends on synthetic frames, tiny generated ONNX models, errors."""

from __future__ import annotations

import cv2
import numpy as np
import pytest

from autohaptics import testing as synth
from autohaptics.fusion import saliency
from autohaptics.fusion.onnx import OnnxMapModel
from autohaptics.errors import ParameterError
from onnx_models import flat_input_model, map_model, two_input_model

W, H = 128, 72


def disc_frame(x: float = 0.2, y: float = 0.5) -> tuple[np.ndarray, np.ndarray]:
    """A bright disc on a dim textured background, and the disc's pixel mask."""
    scene = synth.Scene(1, background=(synth.Segment(0, 1, (40, 45, 60), texture=synth.Texture("noise", 0.08, 0.3, seed=1)),),
                        shapes=(synth.Shape("circle", (255, 255, 245), xy0=(x, y), size0=(0.15, 0.27)),))
    ys, xs = np.mgrid[0:H, 0:W]
    inside = ((xs + 0.5) / W - x) ** 2 / 0.075 ** 2 + ((ys + 0.5) / H - y) ** 2 / 0.135 ** 2 < 1
    return synth.render_frame(scene, 0.5, width=W, height=H), inside


@pytest.mark.parametrize("backend", ["spectral", "fine_grained"])
def test_bright_object_is_salient(backend):
    frame, inside = disc_frame()
    smap = saliency.saliency_map(frame, params=saliency.SaliencyParams(backend=backend))
    assert smap.shape == (H, W) and smap.dtype == np.float32
    assert smap.min() == 0.0 and smap.max() == 1.0
    assert smap[inside].mean() > 3 * smap[~inside].mean()
    peak = np.unravel_index(np.argmax(smap), smap.shape)
    assert (peak[1] + 0.5) / W < 1 / 3  # the peak is in the left third, with the disc


@pytest.mark.parametrize("rgb", [(0, 0, 0), (255, 255, 255), (255, 0, 0), (0, 255, 0), (0, 0, 255), (90, 90, 90)])
@pytest.mark.parametrize("shape", [(H, W), (1, W), (H, 1), (16, 16)])
def test_flat_frame_has_no_salient_region(rgb, shape):
    frame = np.broadcast_to(np.asarray(rgb, np.uint8), shape + (3,)).copy()
    np.testing.assert_array_equal(saliency.saliency_map(frame), np.zeros(shape, np.float32))


def test_motion_cue_points_at_what_moved():
    """A static bright disc on the left and a dim square that moved on the right: with the motion
    cue alone (weight 1) the map peaks at the square."""
    frame, _ = disc_frame()
    prev = frame.copy()
    frame = frame.copy()
    frame[30:40, 100:110] = (90, 90, 100)
    prev[30:40, 95:105] = (90, 90, 100)
    prev_gray = cv2.cvtColor(prev, cv2.COLOR_RGB2GRAY)
    smap = saliency.saliency_map(frame, params=saliency.SaliencyParams(motion_weight=1.0, blur=0.0), prev_gray=prev_gray)
    peak = np.unravel_index(np.argmax(smap), smap.shape)
    assert 28 <= peak[0] <= 42 and 93 <= peak[1] <= 112
    # without a previous frame the cue is not computed
    still = saliency.saliency_map(frame, params=saliency.SaliencyParams(motion_weight=1.0))
    np.testing.assert_array_equal(still, saliency.saliency_map(frame))


def test_backend_is_reusable_and_deterministic():
    frame, _ = disc_frame()
    params = saliency.SaliencyParams()
    backend = saliency.make_saliency_backend(params)
    a = saliency.saliency_map(frame, params=params, backend=backend)
    b = saliency.saliency_map(frame, params=params, backend=backend)
    np.testing.assert_array_equal(a, b)
    np.testing.assert_array_equal(a, saliency.saliency_map(frame, params=params))


def test_non_uint8_input_is_clipped():
    frame, _ = disc_frame()
    f = frame.astype(np.float64)
    f[0, 0] = np.nan
    f[1, 1] = 1e6
    smap = saliency.saliency_map(f)
    assert np.isfinite(smap).all() and smap.max() <= 1.0
    with pytest.raises(ParameterError, match=r"\(h, w, 3\)"):
        saliency.saliency_map(np.zeros((4, 4)))


# ---------------------------------------------------------------- ONNX backend
@pytest.mark.parametrize("layout", ["nchw", "nhwc"])
def test_onnx_brightness_model_maps_the_bright_object(tmp_path, layout):
    """A model whose output is the mean of its input channels: its saliency is the brightness,
    whatever the layout; the map comes back at the proxy size."""
    path = map_model(tmp_path / f"mean_{layout}.onnx", kind="mean", layout=layout)
    frame, inside = disc_frame(x=0.8)
    params = saliency.SaliencyParams(backend="onnx", onnx_model=str(path), onnx_input_size=(64, 48), blur=0.0)
    smap = saliency.saliency_map(frame, params=params)
    assert smap.shape == (H, W)
    assert smap[inside].mean() > 0.9 and smap[~inside].mean() < 0.3
    assert (np.unravel_index(np.argmax(smap), smap.shape)[1] + 0.5) / W > 2 / 3


@pytest.mark.parametrize("order, channel", [("rgb", 0), ("bgr", 2)])
@pytest.mark.parametrize("layout", ["nchw", "nhwc"])
def test_onnx_input_normalisation_and_channel_order(tmp_path, order, channel, layout):
    """A model that returns its first input channel shows what the network was fed:
    (value / 255 - mean) / std of R (rgb) or B (bgr)."""
    path = map_model(tmp_path / "c0.onnx", kind="channel0", layout=layout)
    mean, std = (0.5, 0.25, 0.125), (0.5, 0.2, 0.1)
    model = OnnxMapModel(path, input_size=(40, 30), mean=mean, std=std, channel_order=order)
    frame = np.zeros((30, 40, 3), np.uint8)
    frame[..., 0], frame[..., 1], frame[..., 2] = 255, 51, 102
    out = model(frame)
    first = frame[0, 0, channel] / 255.0
    np.testing.assert_allclose(out, (first - mean[0]) / std[0], rtol=1e-5)


def test_onnx_fixed_size_model_decides_its_input_size(tmp_path):
    path = map_model(tmp_path / "fixed.onnx", kind="mean", size=(32, 24))
    model = OnnxMapModel(path, input_size=(224, 224))
    assert model.size == (32, 24) and not model.nhwc
    frame, _ = disc_frame()
    assert model(frame).shape == (H, W)
    dyn = OnnxMapModel(map_model(tmp_path / "dyn.onnx", layout="nhwc"), input_size=(50, 40))
    assert dyn.size == (50, 40) and dyn.nhwc


@pytest.mark.parametrize("shape", [(1, 1), (1, 30), (30, 1), (16, 16)])
def test_onnx_output_is_resized_to_any_proxy(tmp_path, shape):
    path = map_model(tmp_path / "m.onnx")
    model = OnnxMapModel(path, input_size=(16, 16))
    out = model(np.random.default_rng(0).integers(0, 256, shape + (3,), dtype=np.uint8))
    assert out.shape == shape and out.dtype == np.float32 and np.isfinite(out).all()


def test_onnx_errors_are_parameter_errors(tmp_path):
    with pytest.raises(ParameterError, match="needs saliency.onnx_model"):
        saliency.SaliencyParams(backend="onnx")
    missing = tmp_path / "nope.onnx"
    with pytest.raises(ParameterError, match="no such ONNX saliency model file") as exc:
        saliency.make_saliency_backend(saliency.SaliencyParams(backend="onnx", onnx_model=str(missing)))
    assert str(missing) in str(exc.value)
    garbage = tmp_path / "garbage.onnx"
    garbage.write_bytes(b"this is not a protobuf")
    with pytest.raises(ParameterError, match="not a loadable ONNX model"):
        saliency.make_saliency_backend(saliency.SaliencyParams(backend="onnx", onnx_model=str(garbage)))
    with pytest.raises(ParameterError, match="exactly one input"):
        OnnxMapModel(two_input_model(tmp_path / "two.onnx"))
    with pytest.raises(ParameterError, match="4-D"):
        OnnxMapModel(flat_input_model(tmp_path / "flat.onnx"))
    with pytest.raises(ParameterError, match="a model file"):
        OnnxMapModel(None)


@pytest.mark.parametrize("kwargs", [{"backend": "cnn"}, {"proxy_width": 4}, {"motion_weight": 2.0}, {"blur": 0.9},
                                    {"onnx_channel_order": "rbg"}])
def test_params_are_checked(kwargs):
    with pytest.raises(ParameterError):
        saliency.SaliencyParams(**kwargs)


@pytest.mark.parametrize("backend", ["spectral", "fine_grained"])
def test_backend_callable_returns_a_normalised_map(backend):
    frame, _ = disc_frame()
    fn = saliency.make_saliency_backend(saliency.SaliencyParams(backend=backend))
    smap = fn(frame)
    assert smap.shape == (H, W) and smap.dtype == np.float32
    assert smap.min() == 0.0 and smap.max() == 1.0


def test_backend_callable_gives_zeros_for_a_flat_network_output(tmp_path):
    """A flat frame through the brightness model: a constant output, normalised to all zeros."""
    path = map_model(tmp_path / "bright.onnx", kind="mean")
    fn = saliency.make_saliency_backend(saliency.SaliencyParams(backend="onnx", onnx_model=str(path),
                                                                onnx_input_size=(32, 18)))
    out = fn(np.full((H, W, 3), 77, np.uint8))
    assert out.shape == (H, W) and out.dtype == np.float32 and not out.any()


@pytest.mark.parametrize("backend", ["spectral", "fine_grained"])
@pytest.mark.parametrize("variant", ["paper", "mass"])
def test_bright_object_on_the_left_drives_the_left_actuators(backend, variant):
    """Saliency -> fusion end to end: a bright disc in the left third; A1/A3/A4/A8 lead and every
    right actuator (A2/A6/A7/A9) stays below 0.3 of the strongest. A black frame: A5 only."""
    from autohaptics import fusion
    from autohaptics.layout import ACTUATOR_IDS

    idx = {a: i for i, a in enumerate(ACTUATOR_IDS)}
    frame, _ = disc_frame(x=0.17)
    params = saliency.SaliencyParams(backend=backend)
    fparams = fusion.FusionParams(variant=variant)
    beta = fusion.actuator_weights(saliency.saliency_map(frame, params=params), params=fparams)
    left = beta[[idx[a] for a in ("A1", "A3", "A4", "A8")]]
    right = beta[[idx[a] for a in ("A2", "A6", "A7", "A9")]]
    assert left.max() == 1.0
    assert right.max() < 0.3, dict(zip(ACTUATOR_IDS, beta.round(3)))
    black = saliency.saliency_map(np.zeros((H, W, 3), np.uint8), params=params)
    np.testing.assert_array_equal(fusion.actuator_weights(black, params=fparams), np.eye(9)[idx["A5"]])


# ------------------------------------------------------- the spectral map and the proxy's size
def striped_disc_frame(width: int = 1280, height: int = 720) -> np.ndarray:
    """A bright disc right of centre on one-pixel stripes (fine detail that a bilinear
    decimation folds into coarse false patterns), at ``width`` x ``height``."""
    frame = np.empty((height, width, 3), np.uint8)
    frame[:] = np.where((np.arange(width) % 2 == 0)[None, :, None], 110, 40).astype(np.uint8)
    cv2.circle(frame, (int(0.62 * width), int(0.4 * height)), int(0.1 * height), (250, 250, 240), -1)
    return frame


def _proxy(frame: np.ndarray, width: int) -> np.ndarray:
    h = round(width * frame.shape[0] / frame.shape[1])
    return cv2.resize(frame, (width, h), interpolation=cv2.INTER_AREA)


def _on_grid(smap: np.ndarray) -> np.ndarray:
    return cv2.resize(smap, (64, 36), interpolation=cv2.INTER_AREA)


def test_spectral_map_is_the_same_from_any_proxy_width():
    """OpenCV scales its input to 64 x 64 bilinearly, reading one pixel in five of a 320 px proxy:
    one-pixel stripes then fold into full-contrast false stripes and the map depended on the
    proxy's width. Area-averaged first, a 320 px proxy and the 128 px proxy made from it give
    one map (compared on a common grid)."""
    p320 = striped_disc_frame(320, 180)
    p128 = _proxy(p320, 128)
    a, b = _on_grid(saliency.saliency_map(p320)), _on_grid(saliency.saliency_map(p128))
    assert np.abs(a - b).mean() < 0.03, np.abs(a - b).mean()
    for m in (a, b):  # both peak on the disc
        ys, xs = np.unravel_index(np.argmax(m), m.shape)
        assert abs((xs + 0.5) / 64 - 0.62) < 0.1 and abs((ys + 0.5) / 36 - 0.4) < 0.15, (xs, ys)


def test_spectral_map_from_the_full_frame_luma():
    """With the frame's own 64 x 64 luma the proxy only sets the map's size: the map is the same
    whatever proxy comes with it; a luma of the wrong size is an error."""
    frame = striped_disc_frame()
    luma = cv2.resize(cv2.cvtColor(frame, cv2.COLOR_RGB2GRAY), saliency.SPECTRAL_SIZE, interpolation=cv2.INTER_AREA)
    assert saliency.working_size(saliency.SaliencyParams()) == saliency.SPECTRAL_SIZE
    assert saliency.working_size(saliency.SaliencyParams(backend="fine_grained")) is None
    a = saliency.saliency_map(_proxy(frame, 320), luma=luma)
    b = saliency.saliency_map(_proxy(frame, 128), luma=luma)
    assert a.shape == (180, 320) and b.shape == (72, 128)
    assert np.abs(_on_grid(a) - _on_grid(b)).max() < 0.02
    # the luma decides, not the proxy: a proxy of faint stripes with the disc's luma finds the disc
    faint_texture = _proxy(frame, 128)
    faint_texture[:, :, :] = faint_texture.mean(axis=(0, 1), keepdims=True).astype(np.uint8) + \
        (np.arange(128) % 3 * 6).astype(np.uint8)[None, :, None]
    c = saliency.saliency_map(faint_texture, luma=luma)
    assert np.abs(_on_grid(c) - _on_grid(b)).max() < 0.02
    with pytest.raises(ParameterError, match="luma"):
        saliency.saliency_map(_proxy(frame, 128), luma=luma[:32])
