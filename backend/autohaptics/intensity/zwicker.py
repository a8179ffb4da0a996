"""ISO 532-1 steps 2-5: core loudness, the non-linear decay, the upper slopes and the temporal
weighting, each a function over arrays (:mod:`autohaptics.intensity.loudness` composes them).

Core loudness is computed on intensities (every dB comparison of the standard is exact in that
domain); the bands up to 250 Hz are clamped to 120 dB, the limit of Table A.3.
"""

from __future__ import annotations

import functools
import math

import numpy as np

from autohaptics.intensity import iso532_tables as T
from autohaptics.intensity import compiled as K
from autohaptics.intensity.filterbank import Plan

TW_STEP = T.LEVEL_RATE_HZ // T.LOUDNESS_RATE_HZ  # 4 level samples per 2 ms output


# ------------------------------------------------------------------ step 2: core loudness
@functools.lru_cache(maxsize=None)
def _core_tables(diffuse: bool) -> tuple:
    """ISO 532-1 Tables A.3-A.7 in the intensity domain (see K.core_loudness)."""
    thresholds = 10.0 ** ((T.RAP[:, None] - T.DLL)[:-1] / 10.0)
    factors = 10.0 ** (T.DLL / 10.0)
    band_db = -T.A0 + (T.DDF if diffuse else 0.0)
    i_ltq = 10.0 ** (T.LTQ / 10.0)
    return (thresholds, factors, np.array(T.LOW_CRITICAL_BAND_EDGES, dtype=np.int64), T.FIRST_HIGH_BAND,
            10.0 ** (band_db / 10.0), i_ltq, 10.0 ** (-T.DCB / 10.0) / i_ltq,
            T.CORE_FACTOR * 10.0 ** (0.025 * T.LTQ))


def core_loudness(ms: np.ndarray, *, diffuse: bool) -> np.ndarray:
    """Core loudness [shape=(21, m)], sone/Bark, from band mean squares [shape=(28, m)], Pa^2.

    The 11 bands up to 250 Hz are clamped to 120 dB (the limit of ISO 532-1 Table A.3).
    """
    out = np.empty((len(T.ZUP), ms.shape[1]))
    K.core_loudness(np.ascontiguousarray(ms), T.TINY_INTENSITY, T.INTENSITY_REF,
                    10.0 ** (T.MAX_LOW_FREQUENCY_LEVEL_DB / 10.0), *_core_tables(bool(diffuse)), out)
    return out


# ------------------------------------------------------------------ step 3: decay
def nonlinear_decay(core: np.ndarray, decay: np.ndarray, plan: Plan, *, started: bool):
    decay = decay.copy()
    out = np.empty_like(core)
    flag = np.array([1 if started else 0], dtype=np.int64)
    uo, u2, prev = decay[0].copy(), decay[1].copy(), decay[2].copy()
    K.nonlinear_decay(np.ascontiguousarray(core), plan.nl_coef, plan.nl_iterations, T.NL_EQUAL_TOLERANCE,
                      uo, u2, prev, flag, out)
    return out, np.stack([uo, u2, prev])


# ------------------------------------------------------------------ step 4: slopes
ZUP = T.ZUP + T.ZUP_EPS
USL = np.ascontiguousarray(T.USL)
RNS = T.RNS.astype(np.float64)


def output_rows(k_start: int, m: int) -> np.ndarray:
    """Row in the 2 ms output of each 2 kHz sample k_start .. k_start + m - 1 (or -1)."""
    k = k_start + np.arange(m, dtype=np.int64)
    on_grid = k % TW_STEP == 0
    rows = np.full(m, -1, dtype=np.int64)
    rows[on_grid] = np.arange(int(on_grid.sum()), dtype=np.int64)
    return rows


def slopes(core: np.ndarray, rows: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Total loudness [shape=(m,)] (sone) and N'(z) [shape=(n_rows, 240)] (sone/Bark)."""
    m = core.shape[1]
    total = np.empty(m)
    specific = np.empty((int((rows >= 0).sum()), T.N_BARK))
    K.slopes(np.ascontiguousarray(core), ZUP, RNS, USL, rows, total, specific)
    np.maximum(specific, 0.0, out=specific)
    return total, specific


# ------------------------------------------------------------------ step 5: temporal weighting
@functools.lru_cache(maxsize=None)
def _tw_filter(tau: float) -> tuple[float, float, float, float]:
    """(b_first, b_now, b_prev, pole) of a first-order low-pass run on 24 sub-steps per sample
    with the input interpolated linearly, written as an exact recursion at 2 kHz:
    y[i] = pole * y[i-1] + b_now * x[i] + b_prev * x[i-1]; the first sample ever is b_first * x[0]."""
    n = T.TW_ITERATIONS
    a = math.exp(-1.0 / (T.LEVEL_RATE_HZ * n * tau))
    b = 1.0 - a
    m = np.arange(1, n)
    w = b * a ** (n - m)
    c_prev = float(np.sum(w * (1.0 - m / n)))
    c_now = float(np.sum(w * (m / n)))
    return b, b + c_now, c_prev, a ** n


def temporal_weighting(total: np.ndarray, weighting: np.ndarray, *, started: bool):
    """N(t) = 0.47 LP(3.5 ms) + 0.53 LP(70 ms) of the total loudness, at 2 kHz."""
    new = weighting.copy()
    out = np.zeros_like(total)
    if total.size == 0:
        return out, new
    for idx, (tau, wgt) in enumerate(((T.TW_TAU_SHORT_S, T.TW_WEIGHT_SHORT), (T.TW_TAU_LONG_S, T.TW_WEIGHT_LONG))):
        b_first, b_now, b_prev, pole = _tw_filter(tau)
        x = total
        zi = new[idx]
        y = np.empty_like(x)
        i0 = 0
        if not started:
            y[0] = b_first * x[0]
            zi = b_prev * x[0] + pole * y[0]
            i0 = 1
        if x.size > i0:
            state = np.array([zi], dtype=np.float64)
            K.first_order(np.ascontiguousarray(x[i0:], dtype=np.float64), b_now, b_prev, pole, state, y[i0:])
            zi = float(state[0])
        new[idx] = zi
        out += wgt * y
    return out, new
