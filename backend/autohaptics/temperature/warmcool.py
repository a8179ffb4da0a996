"""The default colour -> temperature mapping: warm-cool around a skin-neutral temperature, scaled
to the film and to the device's range (ALGORITHM.md section 4).

Per tick, the warmth w of the mean colour (:func:`~autohaptics.temperature.colour.warmth`; 0 for
every grey, black and white). Warm and cool ticks are scaled separately, each side by the film's
own scale s: the ``quantile`` of |w| over that side's ticks, at least ``min_scale`` (a film whose
colours are all pale, or a black-and-white film with a faint tint, stays near neutral instead of
having its tint blown up to the limits). Then

    T = neutral + (max - neutral) * tanh(g w / s_warm)     (w >= 0)
    T = neutral - (neutral - min) * tanh(g |w| / s_cool)   (w < 0),   g = atanh(fill),

so the film's strong warm (cool) scenes reach ``fill`` of the warm (cool) headroom, stronger ones
approach the limit without reaching it, and the order of the warmth values is kept. The chair's
slew limit is applied afterwards (:func:`~autohaptics.temperature.device.played_curve`).
"""

from __future__ import annotations

import math

import numpy as np

from autohaptics import quantiles


def film_scales(w: np.ndarray, *, quantile: float, min_scale: float) -> tuple[float, float]:
    """(warm scale, cool scale) of a film's warmth values w [shape=(n,)] (module docstring)."""
    w = np.nan_to_num(np.asarray(w, dtype=np.float64))
    warm, cool = w[w > 0], -w[w < 0]
    s_warm = float(quantiles.quantile(warm, quantile)) if warm.size else 0.0
    s_cool = float(quantiles.quantile(cool, quantile)) if cool.size else 0.0
    return max(s_warm, float(min_scale)), max(s_cool, float(min_scale))


def warmcool_target(w: np.ndarray, *, neutral_c: float, min_c: float, max_c: float, fill: float,
                    quantile: float, min_scale: float) -> tuple[np.ndarray, dict]:
    """Target temperature per tick, C [shape=(n,)], strictly inside (min_c, max_c) unless the
    neutral point is itself a limit; and the film's scales {"warm_scale", "cool_scale"}.

    w : warmth per tick [shape=(n,)]; NaN reads as neutral.
    """
    w = np.nan_to_num(np.asarray(w, dtype=np.float64))
    s_warm, s_cool = film_scales(w, quantile=quantile, min_scale=min_scale)
    gain = math.atanh(float(fill))
    warm = (float(max_c) - neutral_c) * np.tanh(gain * np.maximum(w, 0.0) / s_warm)
    cool = (neutral_c - float(min_c)) * np.tanh(gain * np.maximum(-w, 0.0) / s_cool)
    target = np.clip(neutral_c + warm - cool, min_c, max_c)
    return target, {"warm_scale": round(s_warm, 6), "cool_scale": round(s_cool, 6)}
