"""Small image conversions the stages share: checked uint8 frames, finite float maps,
aspect-kept resizing and a picture's noise."""

from __future__ import annotations

import math

import cv2
import numpy as np

from autohaptics.errors import ParameterError


def as_rgb(rgb: np.ndarray) -> np.ndarray:
    """``rgb`` as a contiguous uint8 frame [shape=(h, w, 3)] (values clipped to 0..255, NaN as 0);
    ParameterError naming the shape otherwise."""
    rgb = np.asarray(rgb)
    if rgb.ndim != 3 or rgb.shape[2] != 3 or rgb.shape[0] < 1 or rgb.shape[1] < 1:
        raise ParameterError(f"expected an RGB frame of shape (h, w, 3), got {rgb.shape}")
    if rgb.dtype != np.uint8:
        rgb = np.clip(np.nan_to_num(rgb.astype(np.float64)), 0, 255).astype(np.uint8)
    return np.ascontiguousarray(rgb)


def as_gray(x: np.ndarray) -> np.ndarray:
    """``x`` as a contiguous uint8 gray frame [shape=(h, w)] (RGB converted, values clipped)."""
    x = np.asarray(x)
    if x.ndim == 3 and x.shape[2] == 3:
        x = cv2.cvtColor(np.ascontiguousarray(x, dtype=np.uint8), cv2.COLOR_RGB2GRAY)
    if x.ndim != 2 or x.size == 0:
        raise ParameterError(f"expected a gray frame of shape (h, w), got {x.shape}")
    if x.dtype != np.uint8:
        x = np.clip(np.nan_to_num(x.astype(np.float64)), 0, 255).astype(np.uint8)
    return np.ascontiguousarray(x)


def resized(rgb: np.ndarray, width: int) -> np.ndarray:
    """``rgb`` scaled to ``width`` px, aspect kept (area when shrinking, bilinear when growing);
    the same array when it already has that width."""
    h, w = rgb.shape[:2]
    if w == width:
        return rgb
    height = max(1, int(round(width * h / w)))
    return cv2.resize(rgb, (width, height), interpolation=cv2.INTER_AREA if width < w else cv2.INTER_LINEAR)


def finite32(x: np.ndarray) -> np.ndarray:
    """``x`` as float32 with every non-finite value 0; ``x`` itself when it is already a float32
    array of finite values (the common case, checked without the copy a masked select makes)."""
    x = np.asarray(x)
    if np.isfinite(x).all():
        return x.astype(np.float32, copy=False)
    return np.where(np.isfinite(x), x, 0.0).astype(np.float32)


# Immerkaer's mask (1996): the difference of two Laplacians, which reads 0 on flat areas and linear ramps;
# white noise of standard deviation 1 gives a response of standard deviation 6
_NOISE_MASK = np.array([[1, -2, 1], [-2, 4, -2], [1, -2, 1]], np.float32)


def noise_response(gray: np.ndarray) -> np.ndarray:
    """Immerkaer's mask over a uint8 picture's inner pixels: int16 [shape=(h - 2, w - 2)], |values| <= 4080
    (empty under 3 x 3). Linear: two frames' difference responds with the difference of their responses."""
    gray = as_gray(gray)
    return cv2.filter2D(gray, cv2.CV_16S, _NOISE_MASK)[1:-1, 1:-1]


def noise_sd(response: np.ndarray) -> float:
    """The noise a :func:`noise_response` (or a difference of two) reads, as a Gaussian's standard
    deviation in grey levels, 0..63: the median absolute response x 1.4826 / 6 (0.0 when empty).

    The median, not Immerkaer's mean, so edges and texture over under half the picture do not count;
    a response counts up to 255 (so 63 at most, far past any film's grain). Grain a pixel or more
    across reads under its spread: the mask passes fine detail only.
    """
    response = _checked(response, "noise_sd")
    if response.size == 0:
        return 0.0
    counts = np.cumsum(cv2.calcHist([cv2.convertScaleAbs(response)], [0], None, [256], [0, 256]).ravel())
    return _sd_of(int(np.searchsorted(counts, (counts[-1] + 1) // 2)))  # the median by counting: no sort


def noise_over(response: np.ndarray, sd: float) -> bool:
    """Whether ``noise_sd(response) > sd``, by one count of the responses within the bar (a picture
    read as clean or noisy without the median's histogram)."""
    response = _checked(response, "noise_over")
    if response.size == 0 or not math.isfinite(sd):
        return 0.0 > sd
    bar = int(math.floor(sd / _sd_of(1)))  # the largest median that reads sd or less...
    while _sd_of(bar + 1) <= sd:  # ...as noise_sd rounds it
        bar += 1
    while bar >= 0 and _sd_of(bar) > sd:
        bar -= 1
    if bar < 0 or bar >= 255:
        return bar < 0
    return int(np.count_nonzero(np.abs(response) <= bar)) < (response.size + 1) // 2


def _checked(response: np.ndarray, name: str) -> np.ndarray:
    response = np.asarray(response)
    if response.ndim != 2 or response.dtype != np.int16:
        raise ParameterError(f"{name} needs a 2-D int16 response, got {response.dtype} {response.shape}")
    return response


def _sd_of(median: int) -> float:
    """A median absolute response as a Gaussian's standard deviation, grey levels."""
    return 1.4826 * median / 6.0
