"""Relative depth for airflow ticks: a nearness map in [0, 1], 1 = near (ALGORITHM.md section 5).

Backends:

- ``"embedded"`` (default, no weights): a monocular cue model that ranks regions; it does not
  measure distance. It blends (a) the ground-plane prior: lower in the frame is nearer; (b) local
  detail: in-focus, high-contrast regions are usually the nearer subject; (c) with the flow,
  expansion: positive divergence means a surface growing on screen, coming toward the camera.
  The expansion cue is on an absolute scale: the divergence is a relative growth rate (1/s, the
  same at any proxy size and frame rate) and the cue is ``min(1, rate / expansion_full)``. Its
  positive part is opened by ``expansion_grain`` (eroded, then dilated back), because a lossy
  encode's block noise gives the flow divergence in specks a block or two wide where nothing
  approaches, while an approaching surface's divergence holds over its extent; it is then
  grey-dilated by ``expansion_reach``, because an expanding object's divergence lies inside it
  while its image motion peaks at its boundary.
- ``"onnx"``: any monocular depth network exported to ONNX (e.g. a MiDaS-style model);
  ``output_kind`` says whether it outputs depth (larger = farther) or disparity (larger = nearer).

The cues' known limits and the measurements behind these choices: docs/BENCHMARKS.md, "Why the
stages are as they are".
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import ClassVar

import cv2
import numpy as np

from autohaptics.errors import ParameterError
from autohaptics.records import ANALYSIS, param
from autohaptics.fusion.onnx import OnnxFields
from autohaptics.imaging import finite32

BACKENDS = ("embedded", "onnx")
DepthBackend = Callable[[np.ndarray], np.ndarray]


@dataclass(frozen=True)
class DepthParams(OnnxFields):
    """Depth backend and the embedded cue weights.

    backend : "embedded" | "onnx".
    proxy_width : width of the RGB proxy depth runs on, px (default 128).
    w_position, w_detail, w_expansion : weights of the embedded cues (normalised to sum 1; a zero
        weight skips the cue; expansion needs the flow).
    expansion_full : relative growth rate (1/s) at which the expansion cue reaches 1 (default 0.5:
        an approach with 4 s to contact).
    expansion_reach : the expansion cue reaches this far (frame widths) beyond where it is
        measured, so an expanding object's boundary counts as near too (0 = not at all).
    expansion_grain : the expansion cue counts only where the positive divergence holds over a
        disc this wide in radius (frame widths, default 0.015: a 240p encode's 8 px blocks are 0.019);
        0 = every speck counts (the rule before issue 31).
    onnx_* : the ONNX model (backend "onnx"; :class:`~autohaptics.fusion.onnx.OnnxFields`).
    output_kind : "depth" (larger = farther) | "disparity" (larger = nearer) for the ONNX output.
    """

    STAGE: ClassVar[str] = ANALYSIS
    GROUP: ClassVar[str] = "depth"

    backend: str = param("embedded", choices=BACKENDS)
    proxy_width: int = param(128, 8, 4096, unit="px", whole=True)
    w_position: float = param(0.4, 0.0)
    w_detail: float = param(0.2, 0.0)
    w_expansion: float = param(0.4, 0.0)
    expansion_full: float = param(0.5, hi=1e6, gt=0.0, unit="1/s")
    expansion_reach: float = param(0.05, 0.0, 0.5, unit="frame widths")
    expansion_grain: float = param(0.015, 0.0, 0.5, unit="frame widths")
    onnx_input_size: tuple[int, int] = (256, 256)
    output_kind: str = param("disparity", choices=("depth", "disparity"))

    def check(self) -> None:
        if self.backend == "embedded" and self.w_position + self.w_detail + self.w_expansion <= 0:
            raise ParameterError("the embedded depth backend needs at least one positive cue weight")
        self.check_onnx(self.backend == "onnx")


def make_depth_backend(params: DepthParams) -> DepthBackend | None:
    """The ONNX model (loaded once), or None for the embedded cues."""
    if params.backend == "onnx":
        return params.onnx_map_model("depth")
    return None


DEFAULT_FRAME_S = 1.0 / 24.0  # frame interval assumed for ``flow`` when dt_s is not given


def nearness_map(rgb: np.ndarray, *, params: DepthParams = DepthParams(), backend: DepthBackend | None = None,
                 flow: np.ndarray | None = None, dt_s: float | None = None) -> np.ndarray:
    """Nearness of each pixel, 0 (far) .. 1 (near). rgb uint8 [shape=(h, w, 3)] -> float32 [shape=(h, w)].

    flow : optional float [shape=(h', w', 2)] px/frame of the same frame (any size), for the
    expansion cue of the embedded backend.
    dt_s : the frame interval of ``flow``, s (default 1/24 s); it makes the expansion cue a rate.
    """
    rgb = np.asarray(rgb)
    if rgb.ndim != 3 or rgb.shape[2] != 3 or rgb.size == 0:
        raise ParameterError(f"expected an RGB frame of shape (h, w, 3), got {rgb.shape}")
    h, w = rgb.shape[:2]
    if params.backend == "onnx":
        model = backend or make_depth_backend(params)
        raw = _minmax(np.asarray(model(np.ascontiguousarray(rgb, dtype=np.uint8)), np.float32))
        if not raw.any():  # a flat (or non-finite) output ranks nothing nearer than anything: all far
            return np.zeros(raw.shape, np.float32)
        return (1.0 - raw if params.output_kind == "depth" else raw).astype(np.float32)
    dt = DEFAULT_FRAME_S if dt_s is None else float(dt_s)
    if not (dt > 0 and np.isfinite(dt)):
        raise ParameterError(f"nearness_map needs a positive frame interval dt_s, got {dt_s!r}")
    return _embedded(np.ascontiguousarray(rgb, dtype=np.uint8), params, flow, dt)


def _embedded(rgb: np.ndarray, params: DepthParams, flow: np.ndarray | None, dt: float) -> np.ndarray:
    h, w = rgb.shape[:2]
    cues, weights = [], []
    if params.w_position > 0:
        rows = (np.arange(h, dtype=np.float32) + 0.5) / h
        cues.append(np.repeat(rows[:, None], w, axis=1))
        weights.append(params.w_position)
    if params.w_detail > 0 and min(h, w) >= 3:
        gray = cv2.cvtColor(rgb, cv2.COLOR_RGB2GRAY).astype(np.float32)
        detail = np.abs(cv2.Laplacian(gray, cv2.CV_32F, ksize=3))
        sigma = max(1.0, 0.05 * w)
        cues.append(_minmax(cv2.GaussianBlur(detail, (0, 0), sigma)))
        weights.append(params.w_detail)
    if params.w_expansion > 0 and flow is not None:
        f = np.asarray(flow, dtype=np.float32)
        if f.ndim == 3 and f.shape[2] == 2 and min(f.shape[:2]) >= 3 and min(h, w) >= 3:
            if f.shape[:2] != (h, w):
                sx, sy = w / f.shape[1], h / f.shape[0]
                f = cv2.resize(f, (w, h), interpolation=cv2.INTER_LINEAR) * np.array([sx, sy], np.float32)
            f = finite32(f)
            rate = (np.gradient(f[..., 0], axis=1) + np.gradient(f[..., 1], axis=0)) / dt  # 1/s
            rate = np.maximum(rate, 0.0).astype(np.float32)
            grain = int(round(float(params.expansion_grain) * w))
            if grain >= 1:
                rate = cv2.erode(rate, _disc(grain))
            reach = int(round(float(params.expansion_reach) * w)) + grain
            if reach >= 1:
                rate = cv2.dilate(rate, _disc(reach))  # the opening's dilation and the reach's in one
            rate = cv2.GaussianBlur(rate, (0, 0), max(1.0, 0.04 * w))
            cues.append(np.clip(rate / float(params.expansion_full), 0.0, 1.0))
            weights.append(params.w_expansion)
    if not cues:
        return np.full((h, w), 0.5, np.float32)
    wsum = float(sum(weights))
    near = sum(wt / wsum * c for wt, c in zip(weights, cues))
    return np.clip(np.nan_to_num(near), 0.0, 1.0).astype(np.float32)


def _disc(radius: int) -> np.ndarray:
    """A disc structuring element of ``radius`` px."""
    return cv2.getStructuringElement(cv2.MORPH_ELLIPSE, (2 * radius + 1, 2 * radius + 1))


def _minmax(x: np.ndarray) -> np.ndarray:
    x = finite32(x)
    lo, hi = float(x.min()), float(x.max())
    if not hi - lo > 1e-9:
        return np.zeros_like(x)
    return (x - lo) / (hi - lo)
