"""Applying a style's numbers: to the parameters before a derive (:func:`scaled_params`) and to
the derived tracks after it (:func:`shape_levels`, :func:`shape_vibration`,
:func:`shape_temperature`). Pure functions; identity numbers leave their input exactly as it was
(the same numbers, bit for bit). :class:`~autohaptics.style.model.Style` calls them.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from autohaptics.params import GenerateParams
from autohaptics.records import apply_overrides

MAX_SCALED_THRESHOLD = 0.999  # a scaled threshold stays below 1, which would switch its feature off
_CHUNK = 1 << 20  # levels shaped per step (bounds the temporaries of a 2-hour fan track)


def scaled_params(params: GenerateParams, *, threshold_scale: float, overrides: dict) -> GenerateParams:
    """``params`` with dotted derive-time ``overrides``, then every threshold below 1 times
    ``threshold_scale`` (at most :data:`MAX_SCALED_THRESHOLD`; a threshold of 1 or more, a feature
    switched off, stays off). With ``intensity.density`` set the density rescales the thresholds
    again, so the scale has no effect there."""
    params = apply_overrides(params, overrides)
    if threshold_scale == 1.0:
        return params
    th = {name: value if value >= 1.0 else min(value * threshold_scale, MAX_SCALED_THRESHOLD)
          for name, value in params.intensity.thresholds.items()}
    return dataclasses.replace(params, intensity=dataclasses.replace(params.intensity, thresholds=th))


def shape_levels(levels: np.ndarray, knots: tuple[float, ...], curve: tuple[float, ...],
                 floor: float = 0.0) -> np.ndarray:
    """A tone curve over levels 0..1 (any shape, float32 or float64): 0 below ``floor`` (0..1, a
    taste for clearing weak effects), else ``x + d(x)`` with ``d`` the curve's distance from the
    diagonal, interpolated linearly between knots; clipped to 0..1. Returns a new array of
    ``levels``' dtype; an identity curve with floor 0 returns an exact copy."""
    out = np.array(levels, copy=True)
    if tuple(curve) == tuple(knots) and floor <= 0.0:
        return out
    xp = np.asarray(knots, np.float64)
    delta = np.asarray(curve, np.float64) - xp
    flat = out.reshape(-1)
    for start in range(0, flat.size, _CHUNK):
        part = flat[start:start + _CHUNK]
        part[:] = np.where(part < floor, 0.0, np.clip(part + np.interp(part, xp, delta), 0.0, 1.0))
    return out


def shape_vibration(vibration: np.ndarray, knots: tuple[float, ...], curves: tuple[tuple[float, ...], ...],
                    floors: tuple[float, ...] | None = None) -> np.ndarray:
    """The vibration track [shape=(n, 9)], 0..1, through each actuator's floor and tone curve (a new
    array; ``floors`` None: none)."""
    out = np.array(vibration, copy=True)
    for a, curve in enumerate(curves):
        out[:, a] = shape_levels(vibration[:, a], knots, curve, 0.0 if floors is None else floors[a])
    return out


def shape_temperature(temperature_c: np.ndarray, *, scale: float, offset_c: float, neutral_c: float,
                      range_c: tuple[float, float]) -> np.ndarray:
    """Temperatures (C) moved away from ``neutral_c`` by ``scale`` (1 = unchanged, 0 = all neutral)
    and shifted by ``offset_c``, clipped to ``range_c`` (the device's safe range). A new array;
    scale 1 and offset 0 give an exact copy."""
    out = np.array(temperature_c, copy=True)
    if scale == 1.0 and offset_c == 0.0:
        return out
    t = out.astype(np.float64)
    shifted = t + offset_c + (scale - 1.0) * (t - neutral_c)
    out[:] = np.clip(shifted, *range_c)
    return out
