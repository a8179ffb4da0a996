"""The colour measures of a frame: its mean RGB (the analysis) and the warm-cool value of a colour
(the default mapping's measure, ALGORITHM.md section 4).

Warm-cool: the colour-emotion model of Ou, Luo, Woodcock and Wright (2004, part I),
WC = -0.5 + 0.02 (C*)^1.07 cos(h - 50 deg) on CIELAB chroma C* and hue angle h. We use the part
that depends on the colour, ``warmth = WC + 0.5``, so every grey (C* = 0) is exactly 0, minus
``hue_offset`` times the same chroma term: 0.02 (C*)^1.07 (cos(h - 50 deg) - hue_offset).
Ou's hue term is zero at 140 deg, on sRGB green (136 deg), so green reads as warm as grey; the
offset (default 0.25) moves the warm/cool boundary to 125 deg (yellow-green) and 335 deg
(magenta), the split of the painters' colour wheel, so green reads cool; 0 is Ou's model exactly.
Values for sRGB primaries with the default offset: red +2.13, orange +1.51, yellow +0.95,
green -0.61, cyan -1.43, blue -1.84.

The measure is taken on the frame's mean colour: warmth is nearly linear in (a*, b*)
((C*)^1.07 cos(h - 50) is a* cos 50 + b* sin 50 up to the exponent), so the warmth of the mean
colour is close to the mean of the pixels' warmth, and the analysis stays one mean per tick.
"""

from __future__ import annotations

import cv2
import numpy as np

from autohaptics.errors import ParameterError

# sRGB (D65) -> CIE XYZ, rows X, Y, Z (IEC 61966-2-1); the white point is its row sums (D65 to
# 7 digits), so every grey has a* = b* = 0 to rounding
_SRGB_TO_XYZ = np.array([[0.4124564, 0.3575761, 0.1804375],
                         [0.2126729, 0.7151522, 0.0721750],
                         [0.0193339, 0.1191920, 0.9503041]])
_D65 = _SRGB_TO_XYZ.sum(axis=1)
_WARM_HUE = np.deg2rad(50.0)


def mean_colour(rgb: np.ndarray) -> np.ndarray:
    """Mean RGB of a frame. rgb uint8 [shape=(h, w, 3)] -> float64 [shape=(3,)], 0..255.

    OpenCV's per-channel mean for uint8 frames (~10 us on a 128 px proxy, 50x numpy's float64
    reduction: it runs once per tick, 72 000 times for a 2-hour film).
    """
    rgb = np.asarray(rgb)
    if rgb.ndim != 3 or rgb.shape[2] != 3 or rgb.size == 0:
        raise ParameterError(f"expected an RGB frame of shape (h, w, 3), got {rgb.shape}")
    if rgb.dtype == np.uint8:
        return np.array(cv2.mean(np.ascontiguousarray(rgb))[:3], dtype=np.float64)
    return rgb.reshape(-1, 3).mean(axis=0, dtype=np.float64)


def cielab(rgb: np.ndarray) -> np.ndarray:
    """CIELAB (D65) of sRGB colours. rgb float [shape=(..., 3)], 0..255 (clipped; NaN reads 0)
    -> float64 [shape=(..., 3)]: L* 0..100, a*, b*."""
    c = np.clip(np.nan_to_num(np.asarray(rgb, dtype=np.float64)), 0.0, 255.0) / 255.0
    linear = np.where(c <= 0.04045, c / 12.92, ((c + 0.055) / 1.055) ** 2.4)
    xyz = linear @ _SRGB_TO_XYZ.T / _D65
    eps = (6.0 / 29.0) ** 3
    f = np.where(xyz > eps, np.cbrt(np.maximum(xyz, eps)), xyz / (3.0 * (6.0 / 29.0) ** 2) + 4.0 / 29.0)
    return np.stack([116.0 * f[..., 1] - 16.0, 500.0 * (f[..., 0] - f[..., 1]), 200.0 * (f[..., 1] - f[..., 2])],
                    axis=-1)


def warmth(rgb: np.ndarray, *, hue_offset: float = 0.25) -> np.ndarray:
    """Warm-cool value of sRGB colours (module docstring): > 0 warm, < 0 cool, 0 for every grey.

    rgb float [shape=(..., 3)], 0..255 -> float64 [shape=(...,)], within about -3.2..+3.0 for
    sRGB colours and the default offset.
    """
    lab = cielab(rgb)
    chroma = np.hypot(lab[..., 1], lab[..., 2])
    hue = np.arctan2(lab[..., 2], lab[..., 1])
    return 0.02 * chroma ** 1.07 * (np.cos(hue - _WARM_HUE) - float(hue_offset))
