"""Saliency: where the eye goes in a frame, a map in [0, 1] (ALGORITHM.md section 3, thesis 3.1.2).

Backends (the fusion that uses the map is fixed, the backend is a choice):

- ``"spectral"`` (default): OpenCV contrib's spectral residual (Hou & Zhang 2007), which needs no
  weights; about 0.3 ms per frame.
- ``"fine_grained"``: OpenCV contrib's fine-grained saliency (Montabone & Soto 2010); 300+ ms on a
  1080p frame, so only ever run on the proxy.
- ``"onnx"``: any single-input saliency network exported to ONNX (the thesis used a pyramid
  feature attention network), loaded from a user-supplied file with onnxruntime; input size,
  normalisation and channel order are parameters.

The spectral residual works on a fixed 64 x 64 luma image, area-averaged from the full frame's luma
in the same read as the proxies (:meth:`autohaptics.media.Frame.rgb_and_gray`), not resized by
OpenCV from the proxy (a bilinear decimation aliases, and the salient shape turns small changes of
the map into another actuator split): the map is then the same at every proxy size, and the proxy
width only sets the resolution the salient shape is cut at.

Optionally a motion cue (frame difference with the previous frame) is blended in. A flat frame
(black, one colour) has no salient region: its map is all zeros.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import ClassVar

import cv2
import numpy as np

from autohaptics.errors import ParameterError
from autohaptics.records import ANALYSIS, param
from autohaptics.imaging import as_rgb, finite32
from autohaptics.fusion.onnx import OnnxFields

BACKENDS = ("spectral", "fine_grained", "onnx")
SaliencyBackend = Callable[..., np.ndarray]  # (rgb, luma=None) -> map
SPECTRAL_SIZE = (64, 64)  # (w, h) px: the image the spectral residual works on (OpenCV's default)


@dataclass(frozen=True)
class SaliencyParams(OnnxFields):
    """Saliency backend and its inputs.

    backend : "spectral" | "fine_grained" | "onnx".
    proxy_width : width in px of the RGB proxy the map is computed on and has (default 256; with
        the spectral backend the width the salient shape is cut at: see the module docstring).
    motion_weight : 0..1 share of the motion cue (|frame - previous frame|); 0 = not computed.
    blur : Gaussian smoothing of the map, sigma as a fraction of the proxy width (0 = none).
    flat_std : a frame whose luma standard deviation is below this (grey levels 0..255) is flat:
        no salient region.
    onnx_* : the ONNX model (backend "onnx"; :class:`~autohaptics.fusion.onnx.OnnxFields`).
    """

    STAGE: ClassVar[str] = ANALYSIS
    GROUP: ClassVar[str] = "saliency"

    backend: str = param("spectral", choices=BACKENDS)
    proxy_width: int = param(256, 8, 4096, unit="px", whole=True)
    motion_weight: float = param(0.0, 0.0, 1.0)
    blur: float = param(0.02, 0.0, 0.5)
    flat_std: float = param(2.0, 0.0, 255.0)

    def check(self) -> None:
        self.check_onnx(self.backend == "onnx")


def make_saliency_backend(params: SaliencyParams) -> SaliencyBackend:
    """A callable ``rgb uint8 (h, w, 3) -> map float32 (h, w)`` in [0, 1]; models are loaded once here.

    The map is the backend's output at the frame's size, min-max normalised; a flat or non-finite
    output is all zeros.
    """
    if params.backend == "spectral":
        engine = cv2.saliency.StaticSaliencySpectralResidual_create()
        engine.setImageWidth(SPECTRAL_SIZE[0])
        engine.setImageHeight(SPECTRAL_SIZE[1])
        raw = lambda rgb, luma: _opencv_map(engine, rgb, _checked_luma(luma))  # noqa: E731
    elif params.backend == "fine_grained":
        engine = cv2.saliency.StaticSaliencyFineGrained_create()
        raw = lambda rgb, luma: _opencv_map(engine, rgb)  # noqa: E731
    else:
        model = params.onnx_map_model("saliency")
        raw = lambda rgb, luma: model(rgb)  # noqa: E731

    def backend(rgb: np.ndarray, luma: np.ndarray | None = None) -> np.ndarray:
        rgb = as_rgb(rgb)
        return _normalise(np.asarray(raw(rgb, luma), dtype=np.float32), rgb.shape[:2])

    return backend


def working_size(params: SaliencyParams) -> tuple[int, int] | None:
    """(w, h) px of the luma the backend works on when that size is fixed (spectral: 64 x 64),
    else None: pass the frame's luma at that size as ``saliency_map(..., luma=)``."""
    return SPECTRAL_SIZE if params.backend == "spectral" else None


def saliency_map(rgb: np.ndarray, *, params: SaliencyParams = SaliencyParams(),
                 backend: SaliencyBackend | None = None, prev_gray: np.ndarray | None = None,
                 luma: np.ndarray | None = None) -> np.ndarray:
    """Saliency of one frame.

    rgb : uint8 [shape=(h, w, 3)], the proxy; the map has its size.
    prev_gray : uint8 [shape=(h, w)], the previous frame's luma, for the motion cue (optional).
    luma : uint8 [shape=working_size(params)[::-1]], the frame's luma area-averaged to the
        backend's working size from the full-resolution frame (optional; spectral backend only,
        :meth:`autohaptics.media.Frame.rgb_and_gray`). Without it the proxy is scaled down.
    Returns float32 [shape=(h, w)] in [0, 1]; all zeros for a flat frame or a flat/NaN network output.
    """
    rgb = as_rgb(rgb)
    h, w = rgb.shape[:2]
    gray = cv2.cvtColor(rgb, cv2.COLOR_RGB2GRAY)
    if float(gray.std()) < params.flat_std:
        return np.zeros((h, w), np.float32)
    backend = backend or make_saliency_backend(params)
    smap = _normalise(np.asarray(backend(rgb, luma) if luma is not None else backend(rgb), dtype=np.float32), (h, w))
    if params.motion_weight > 0 and prev_gray is not None and prev_gray.shape == gray.shape:
        diff = cv2.absdiff(gray, prev_gray).astype(np.float32)
        smap = (1.0 - params.motion_weight) * smap + params.motion_weight * _normalise(diff, (h, w))
    if params.blur > 0 and min(h, w) >= 3:
        sigma = max(0.5, params.blur * w)
        smap = cv2.GaussianBlur(smap, (0, 0), sigmaX=sigma, sigmaY=sigma)
    return _normalise(smap, (h, w))


# ----------------------------------------------------------------------- private
def _opencv_map(engine, rgb: np.ndarray, luma: np.ndarray | None = None) -> np.ndarray:
    h, w = rgb.shape[:2]
    if min(h, w) < 4:  # too small for a spectrum: no structure to find
        return np.zeros((h, w), np.float32)
    if luma is not None:
        gray = luma
    else:
        gray = cv2.cvtColor(rgb, cv2.COLOR_RGB2GRAY)
        if isinstance(engine, cv2.saliency.StaticSaliencySpectralResidual):
            gray = cv2.resize(gray, SPECTRAL_SIZE, interpolation=cv2.INTER_AREA)
    ok, smap = engine.computeSaliency(gray)
    if not ok or smap is None:
        return np.zeros((h, w), np.float32)
    smap = np.asarray(smap, dtype=np.float32)
    if smap.shape != (h, w):
        smap = cv2.resize(smap, (w, h), interpolation=cv2.INTER_LINEAR)
    return smap


def _checked_luma(luma: np.ndarray | None) -> np.ndarray | None:
    if luma is None:
        return None
    luma = np.asarray(luma)
    if luma.shape != SPECTRAL_SIZE[::-1]:
        raise ParameterError(f"the spectral backend's luma must have shape {SPECTRAL_SIZE[::-1]}, got {luma.shape}")
    if luma.dtype != np.uint8:
        luma = np.clip(np.nan_to_num(luma.astype(np.float64)), 0, 255).astype(np.uint8)
    return np.ascontiguousarray(luma)


def _normalise(smap: np.ndarray, shape: tuple[int, int]) -> np.ndarray:
    """Min-max to [0, 1]; a flat or non-finite map becomes all zeros."""
    smap = finite32(smap)
    if smap.shape != shape:
        smap = cv2.resize(smap, (shape[1], shape[0]), interpolation=cv2.INTER_LINEAR)
    lo, hi = float(smap.min()), float(smap.max())
    if not hi - lo > 1e-6 * max(1.0, abs(hi)):
        return np.zeros(shape, np.float32)
    return ((smap - lo) / (hi - lo)).astype(np.float32)
