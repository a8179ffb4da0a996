"""Tiny ONNX map models for the saliency and depth backends, built with onnx.helper (no downloads).

Each model has one float input, a batch of one RGB image in NCHW ``(1, 3, H, W)`` or NHWC
``(1, H, W, 3)`` layout, and one output map with a known answer:

- ``"mean"``: the mean of the three (normalised) channels, i.e. a brightness map;
- ``"channel0"``: the first channel as fed to the network (shows normalisation and channel order).

The output keeps the input's layout: ``(1, 1, H, W)`` for NCHW, ``(1, H, W, 1)`` for NHWC.
``size=None`` gives symbolic height and width (the backend's ``input_size`` decides), a
``(w, h)`` pair a fixed-size model (the model decides).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import onnx
from onnx import TensorProto, helper

OPSET = 13
IR_VERSION = 8  # understood by every onnxruntime since 1.10


def _input_shape(layout: str, size: tuple[int, int] | None) -> list:
    h, w = ("H", "W") if size is None else (int(size[1]), int(size[0]))
    return [1, 3, h, w] if layout == "nchw" else [1, h, w, 3]


def _save(graph: onnx.GraphProto, path: Path) -> Path:
    model = helper.make_model(graph, opset_imports=[helper.make_opsetid("", OPSET)],
                              producer_name="autohaptics-tests")
    model.ir_version = IR_VERSION
    onnx.checker.check_model(model)
    path = Path(path)
    onnx.save(model, str(path))
    return path


def map_model(path: str | Path, *, kind: str = "mean", layout: str = "nchw",
              size: tuple[int, int] | None = None) -> Path:
    """Write a one-input, one-output map model to ``path`` and return the path."""
    if layout not in ("nchw", "nhwc") or kind not in ("mean", "channel0"):
        raise ValueError(f"unknown model kind/layout {kind!r}/{layout!r}")
    axis = 1 if layout == "nchw" else 3
    x = helper.make_tensor_value_info("image", TensorProto.FLOAT, _input_shape(layout, size))
    out_shape = _input_shape(layout, size)
    out_shape[axis] = 1
    y = helper.make_tensor_value_info("map", TensorProto.FLOAT, out_shape)
    if kind == "mean":
        nodes = [helper.make_node("ReduceMean", ["image"], ["map"], axes=[axis], keepdims=1)]
        inits = []
    else:
        idx = helper.make_tensor("idx", TensorProto.INT64, [1], np.array([0], np.int64))
        nodes = [helper.make_node("Gather", ["image", "idx"], ["map"], axis=axis)]
        inits = [idx]
    graph = helper.make_graph(nodes, f"{kind}_{layout}", [x], [y], initializer=inits)
    return _save(graph, path)


def two_input_model(path: str | Path) -> Path:
    """A model with two inputs (not a single-image map network)."""
    a = helper.make_tensor_value_info("a", TensorProto.FLOAT, [1, 3, "H", "W"])
    b = helper.make_tensor_value_info("b", TensorProto.FLOAT, [1, 3, "H", "W"])
    y = helper.make_tensor_value_info("y", TensorProto.FLOAT, [1, 3, "H", "W"])
    graph = helper.make_graph([helper.make_node("Add", ["a", "b"], ["y"])], "two_inputs", [a, b], [y])
    return _save(graph, path)


def flat_input_model(path: str | Path) -> Path:
    """A model whose input is 2-D (not an image batch)."""
    x = helper.make_tensor_value_info("x", TensorProto.FLOAT, [1, 12])
    y = helper.make_tensor_value_info("y", TensorProto.FLOAT, [1, 12])
    graph = helper.make_graph([helper.make_node("Identity", ["x"], ["y"])], "flat", [x], [y])
    return _save(graph, path)
