"""Low-frequency energy: the mean square of the sound pressure below a cutoff (default 215 Hz,
the vibration motors' upper frequency), one value per 20 ms frame, Pa^2.

Recipe: ``_lowpass`` (Butterworth low-pass, ``order`` poles at ``cutoff_hz``, run continuously
across frames so that a 20 ms frame still sees the full low-frequency resolution of the filter,
unlike a 20 ms FFT with ~4 bins below 215 Hz) -> ``_frame_mean_square`` (mean of the squared
output over each frame's 960 samples at 48 kHz; the last, partial frame over the samples it has).

A 20 ms frame spans less than one period below 50 Hz, so the per-frame value of a steady tone
below 50 Hz ripples around its mean square (a property of 20 ms frames, not of the filter).

Streaming: :func:`init_state` -> :func:`low_energy_update` per chunk (complete frames) ->
:func:`low_energy_finish` (the trailing partial frame, if any). Chunked equals whole exactly.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass

import numpy as np

from autohaptics.cachedir import cached_arrays, digest
from autohaptics.intensity import compiled as K
from autohaptics.errors import ParameterError
from autohaptics.intensity.loudness import check_pressure
from autohaptics.timebase import ANALYSIS_SAMPLE_RATE, SAMPLES_PER_FRAME


@dataclass(frozen=True)
class LowEnergyParams:
    """Parameters of the low-frequency energy stage.

    cutoff_hz : float, Hz; -3 dB corner of the low-pass (default 215, the motors' upper limit).
    order : int; Butterworth order, 6 dB/octave per pole (default 4: -24 dB at 2 x cutoff).
    """

    cutoff_hz: float = 215.0
    order: int = 4

    def __post_init__(self):
        f = self.cutoff_hz
        if not isinstance(f, (int, float)) or not math.isfinite(f) or not 0 < f < ANALYSIS_SAMPLE_RATE / 2:
            raise ParameterError(f"low-energy cutoff_hz must lie in (0, {ANALYSIS_SAMPLE_RATE // 2}) Hz, got {f!r}")
        if not isinstance(self.order, int) or not 1 <= self.order <= 12:
            raise ParameterError(f"low-energy order must be an integer in 1..12, got {self.order!r}")


@dataclass(frozen=True)
class LowEnergyState:
    """Filter state and the squared samples of the frame in progress (never mutated).

    zi : [shape=(n_sections, 2)] low-pass state; tail : [shape=(k,)], k < 960, Pa^2.
    """

    cutoff_hz: float
    order: int
    zi: np.ndarray
    tail: np.ndarray


def init_state(*, params: LowEnergyParams = LowEnergyParams()) -> LowEnergyState:
    """A fresh state: silence before t = 0."""
    sos = _lowpass_sos(float(params.cutoff_hz), params.order)
    return LowEnergyState(float(params.cutoff_hz), params.order, np.zeros((sos.shape[0], 2)), np.zeros(0))


def low_energy_update(p: np.ndarray, state: LowEnergyState, *,
                      params: LowEnergyParams = LowEnergyParams()) -> tuple[np.ndarray, LowEnergyState]:
    """Mean square below the cutoff of every 20 ms frame completed by this chunk.

    p : np.ndarray [shape=(n,)], Pa at 48 kHz.
    Returns (np.ndarray [shape=(k,)] in Pa^2, new state).
    """
    p = check_pressure(p)
    if (state.cutoff_hz, state.order) != (float(params.cutoff_hz), params.order):
        raise ParameterError("low-energy state was made with other parameters "
                             f"(cutoff {state.cutoff_hz} Hz, order {state.order})")
    squared, zi = _lowpass(p, state.zi, params)
    buf = np.concatenate([state.tail, squared]) if state.tail.size else squared
    n_full = buf.shape[0] // SAMPLES_PER_FRAME
    frames = _frame_mean_square(buf[: n_full * SAMPLES_PER_FRAME])
    tail = buf[n_full * SAMPLES_PER_FRAME:].copy()
    return frames, LowEnergyState(state.cutoff_hz, state.order, zi, tail)


def low_energy_finish(state: LowEnergyState) -> np.ndarray:
    """The trailing partial frame's mean square: [shape=(1,)] Pa^2, or [shape=(0,)] if none."""
    if state.tail.size == 0:
        return np.zeros(0)
    return np.array([float(np.mean(state.tail))])


def low_energy(p: np.ndarray, *, params: LowEnergyParams = LowEnergyParams()) -> np.ndarray:
    """Low-frequency mean square of a whole signal, [shape=(ceil(n / 960),)], Pa^2.

    p : np.ndarray [shape=(n,)], Pa at 48 kHz.
    """
    frames, state = low_energy_update(p, init_state(params=params), params=params)
    return np.concatenate([frames, low_energy_finish(state)])


@functools.lru_cache(maxsize=None)
def _lowpass_sos(cutoff_hz: float, order: int) -> np.ndarray:
    """The Butterworth low-pass (sos), designed once per machine (scipy.signal takes ~1 s to import)."""
    def build() -> dict:
        import scipy.signal as ss

        return {"sos": ss.butter(order, cutoff_hz, btype="low", output="sos", fs=ANALYSIS_SAMPLE_RATE)}

    key = "lowpass-" + digest(cutoff_hz, order, ANALYSIS_SAMPLE_RATE, np.__version__)
    return cached_arrays("filters", key, build)["sos"]


def _lowpass(p: np.ndarray, zi: np.ndarray, params: LowEnergyParams) -> tuple[np.ndarray, np.ndarray]:
    """Squared low-pass output [shape=(n,)], Pa^2, and the new filter state."""
    zi = zi.copy()
    y = np.empty_like(p)
    K.sos_decimate(p, _lowpass_sos(float(params.cutoff_hz), params.order), zi, 0, 1, y)
    np.multiply(y, y, out=y)
    return y, zi


def _frame_mean_square(squared: np.ndarray) -> np.ndarray:
    return squared.reshape(-1, SAMPLES_PER_FRAME).mean(axis=1)
