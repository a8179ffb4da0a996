"""ONNX map models: a single-input image network that outputs one map (saliency or depth), and the
parameter fields that describe one (shared by ``saliency.*`` and ``depth.*``).

Outputs (1, C, H, W) and (1, H, W, C) are both read as maps, the channel axis being the smaller of
axes 1 and 3 (the input's layout breaks a tie); the map is resized back to the frame (bilinear).
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import cv2
import numpy as np

from autohaptics.errors import ParameterError
from autohaptics.records import Record, param

CHANNEL_ORDERS = ("rgb", "bgr")


@dataclass(frozen=True)
class OnnxFields(Record):
    """The ONNX model of a stage whose backend is "onnx".

    onnx_model : path of the ONNX file.
    onnx_input_size : (width, height) the network expects, px (a fixed-size model decides its own).
    onnx_mean, onnx_std : per-channel normalisation on the 0..1 scale, in ``onnx_channel_order``.
    onnx_channel_order : "rgb" | "bgr".
    """

    onnx_model: str | None = None
    onnx_input_size: tuple[int, int] = (224, 224)
    onnx_mean: tuple[float, float, float] = (0.485, 0.456, 0.406)
    onnx_std: tuple[float, float, float] = (0.229, 0.224, 0.225)
    onnx_channel_order: str = param("rgb", choices=CHANNEL_ORDERS)

    def check_onnx(self, wanted: bool) -> None:
        """ParameterError when no model is given where one is ``wanted``."""
        if wanted and not self.onnx_model:
            raise ParameterError(f"{self.GROUP}.backend 'onnx' needs {self.GROUP}.onnx_model (path of an .onnx file)")

    def onnx_map_model(self, what: str) -> "OnnxMapModel":
        """The model these fields describe, loaded once (``what`` names it in errors)."""
        return OnnxMapModel(self.onnx_model, input_size=self.onnx_input_size, mean=self.onnx_mean,
                            std=self.onnx_std, channel_order=self.onnx_channel_order, what=what)


class OnnxMapModel:
    """A single-input image network (ONNX) that outputs one map: saliency or depth.

    The input is resized to ``input_size`` (w, h), scaled to 0..1, normalised with ``mean``/``std``
    and laid out NCHW or NHWC as the model's input shape says. The first output is squeezed to
    2-D (first channel of a multi-channel output) and resized back to the frame.
    """

    def __init__(self, path: str | Path | None, *, input_size=(224, 224), mean=(0.0, 0.0, 0.0), std=(1.0, 1.0, 1.0),
                 channel_order: str = "rgb", what: str = "map"):
        import onnxruntime as ort

        if not path:
            raise ParameterError(f"the ONNX {what} backend needs a model file")
        p = Path(path)
        if not p.is_file():
            raise ParameterError(f"{p}: no such ONNX {what} model file")
        opts = ort.SessionOptions()
        opts.intra_op_num_threads = 1
        opts.log_severity_level = 3
        try:
            self.session = ort.InferenceSession(str(p), sess_options=opts, providers=["CPUExecutionProvider"])
        except Exception as exc:  # onnxruntime raises its own exception types for bad files
            raise ParameterError(f"{p}: not a loadable ONNX model ({type(exc).__name__}: {exc})") from None
        inputs = self.session.get_inputs()
        if len(inputs) != 1:
            raise ParameterError(f"{p}: the {what} model must have exactly one input, it has {len(inputs)}")
        self.input = inputs[0]
        shape = list(self.input.shape)
        if len(shape) != 4:
            raise ParameterError(f"{p}: the {what} model's input must be 4-D (NCHW or NHWC), got {shape}")
        self.nhwc = shape[3] == 3 and shape[1] != 3
        self.size = (int(input_size[0]), int(input_size[1]))
        fixed_h, fixed_w = (shape[1], shape[2]) if self.nhwc else (shape[2], shape[3])
        if isinstance(fixed_h, int) and isinstance(fixed_w, int) and fixed_h > 0 and fixed_w > 0:
            self.size = (fixed_w, fixed_h)  # a fixed-size model decides its own input size
        self.mean = np.asarray(mean, np.float32)
        self.std = np.maximum(np.asarray(std, np.float32), 1e-6)
        self.bgr = channel_order == "bgr"
        self.what = what

    def __call__(self, rgb: np.ndarray) -> np.ndarray:
        h, w = rgb.shape[:2]
        x = cv2.resize(rgb, self.size, interpolation=cv2.INTER_AREA if w > self.size[0] else cv2.INTER_LINEAR)
        if self.bgr:
            x = x[..., ::-1]
        x = (x.astype(np.float32) / 255.0 - self.mean) / self.std
        x = x[None] if self.nhwc else np.transpose(x, (2, 0, 1))[None]
        out = self.session.run(None, {self.input.name: np.ascontiguousarray(x, dtype=np.float32)})[0]
        out = _first_map(np.asarray(out, dtype=np.float32), channels_last=self.nhwc, what=self.what)
        out = np.where(np.isfinite(out), out, 0.0).astype(np.float32)
        return cv2.resize(out, (w, h), interpolation=cv2.INTER_LINEAR)


def _first_map(out: np.ndarray, *, channels_last: bool, what: str) -> np.ndarray:
    """The first channel of a network's output as a 2-D map.

    4-D outputs are (N, C, H, W) or (N, H, W, C): the smaller of axes 1 and 3 is the channel axis
    (a tie follows the input's layout), so (1, 1, H, W) and (1, H, W, 1) both give the H x W map.
    3-D outputs drop a leading or trailing axis of size 1, else take the first channel.
    """
    if out.ndim == 4:
        last = out.shape[3] < out.shape[1] or (out.shape[3] == out.shape[1] and channels_last)
        out = out[0, :, :, 0] if last else out[0, 0]
    elif out.ndim == 3:
        if out.shape[0] == 1 or (out.shape[2] != 1 and not channels_last):
            out = out[0]
        else:
            out = out[:, :, 0]
    if out.ndim != 2 or out.size == 0:
        raise ParameterError(f"the ONNX {what} model's output has shape {np.shape(out)}, expected a map "
                             "(H, W), (1, H, W), (1, C, H, W) or (1, H, W, C)")
    return out
