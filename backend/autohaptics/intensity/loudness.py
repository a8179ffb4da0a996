"""Zwicker loudness, ISO 532-1:2017 (time-varying method, free or diffuse field), streaming.

Recipe (ISO 532-1 clause 6 / Annex A): the third-octave filter bank (:mod:`.filterbank`: band
mean squares every 0.5 ms), then core loudness, the non-linear decay, the upper slopes (N'(z) on
z = 0.1 .. 24 Bark and the total N) and the temporal weighting (:mod:`.zwicker`).

Input: sound pressure in pascal at 48 kHz (the standard defines its filters at 48 kHz only;
:func:`autohaptics.media.iter_audio` resamples). Output: the 2 ms grid, sample k at t = 0.002 k s
(input sample 96 k): ceil(n / 96) values for n samples; N'(z, t) at the same instants, before the
temporal weighting, as in ISO.

Methods: ``"iso"`` (the reference preset): the standard's own filters at 48 kHz and 24 decay
sub-steps, within the ISO tolerance on test signals 6-25. ``"fast"`` (default): a multirate filter
bank with fitted 6th-order band filters and 2 decay sub-steps (median deviation from "iso" below
0.5 %, measured by ``autohaptics bench audio``).

Band levels up to 250 Hz above 120 dB (where the standard is undefined) are CLAMPED to 120 dB;
pressures above :data:`MAX_PRESSURE_PA` and non-finite samples raise ParameterError.

Streaming: :func:`init_state`, then :func:`loudness_update` per chunk (the 2 ms samples that became
complete, and a new immutable state); the concatenation equals :func:`loudness_zwtv` on the whole
signal, bit for bit.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from autohaptics.intensity import iso532_tables as T
from autohaptics.intensity import filterbank as fb
from autohaptics.intensity import compiled as K
from autohaptics.intensity import zwicker as zw
from autohaptics.intensity.filterbank import LEVEL_STEP, ceil_div
from autohaptics.intensity.zwicker import TW_STEP
from autohaptics.errors import ParameterError

LOUDNESS_METHODS = ("iso", "fast")
FIELDS = ("free", "diffuse")
SAMPLE_RATE_HZ = T.SAMPLE_RATE_HZ
STEP_S = 1.0 / T.LOUDNESS_RATE_HZ  # 0.002 s, the ISO output grid
SAMPLES_PER_STEP = SAMPLE_RATE_HZ // T.LOUDNESS_RATE_HZ  # 96 input samples per 2 ms value
Z_BARK = T.BARK_AXIS.copy()  # [shape=(240,)], Bark: 0.1, 0.2, ..., 24.0
BARK_STEP = T.BARK_STEP
MAX_PRESSURE_PA = 1.0e9  # sanity bound on |p|: 1e4 atmospheres; beyond that the input is not sound
_MAX_LEVEL_DB = 20.0 * math.log10(MAX_PRESSURE_PA / 2e-5)  # ~274 dB, the same bound for band levels



@dataclass(frozen=True)
class LoudnessParams:
    """Parameters of the loudness stage.

    field : "free" (frontal free field, default) or "diffuse" (diffuse field, ISO Table A.5).
    method : "fast" (default; multirate filter bank, 2 decay sub-steps) or "iso" (the
        standard's filters at 48 kHz, 24 decay sub-steps; the reference preset).
    """

    field: str = "free"
    method: str = "fast"

    def __post_init__(self):
        if self.field not in FIELDS:
            raise ParameterError(f"loudness field must be one of {FIELDS}, got {self.field!r}")
        if self.method not in LOUDNESS_METHODS:
            raise ParameterError(f"loudness method must be one of {LOUDNESS_METHODS}, got {self.method!r}")


@dataclass(frozen=True)
class LoudnessResult:
    """Loudness on the ISO 2 ms grid.

    t_s : np.ndarray [shape=(n,)], s; t = 0.002 k (the instant of input sample 96 k).
    loudness : np.ndarray [shape=(n,)], sone; N(t) after temporal weighting.
    specific : np.ndarray [shape=(n, 240)], sone/Bark; N'(z, t) (before temporal weighting).
    z_bark : np.ndarray [shape=(240,)], Bark; 0.1 .. 24.0.
    """

    t_s: np.ndarray
    loudness: np.ndarray
    specific: np.ndarray
    z_bark: np.ndarray = field(default_factory=lambda: Z_BARK.copy())


@dataclass(frozen=True)
class LoudnessState:
    """Everything the stage remembers between chunks (treat as opaque; never mutated).

    n_in : input samples consumed so far (48 kHz).
    bank, smooth : per filter-bank group, band-filter and smoother states.
    stages : per decimator, its section states.
    decay : [shape=(3, 21)] decay network (output, second capacitor, previous input).
    weighting : [shape=(2,)] states of the 3.5 ms and 70 ms temporal-weighting filters.
    """

    method: str
    field: str
    n_in: int
    bank: tuple
    smooth: tuple
    stages: tuple
    decay: np.ndarray
    weighting: np.ndarray


# ------------------------------------------------------------------ public API
def init_state(*, params: LoudnessParams = LoudnessParams()) -> LoudnessState:
    """A fresh state: silence before t = 0."""
    plan = fb.plan(params.method)
    return LoudnessState(
        method=params.method, field=params.field, n_in=0,
        bank=tuple(np.zeros((len(g.bands), g.sos.shape[1], 2)) for g in plan.groups),
        smooth=tuple(np.zeros((len(g.bands), T.N_SMOOTHING_POLES)) for g in plan.groups),
        stages=tuple(np.zeros((s.sos.shape[0], 2)) for s in plan.stages),
        decay=np.zeros((3, len(T.ZUP))),
        weighting=np.zeros(2),
    )


def loudness_update(p: np.ndarray, state: LoudnessState, *,
                    params: LoudnessParams = LoudnessParams()) -> tuple[LoudnessResult, LoudnessState]:
    """Process one chunk of sound pressure and return the newly complete 2 ms samples.

    p : np.ndarray [shape=(n,)], Pa at 48 kHz (any float dtype; n may be 0).
    state : from :func:`init_state` or the previous call, for the same ``params``.
    Returns (result, new_state); ``result`` holds the 2 ms samples k with 96 k inside the
    input seen so far that were not returned before (their ``t_s`` continues the time axis).
    """
    p = check_pressure(p)
    if state.method != params.method or state.field != params.field:
        raise ParameterError(f"loudness state was made for method={state.method!r}, field={state.field!r}; "
                             f"got params method={params.method!r}, field={params.field!r}")
    plan = fb.plan(params.method)
    k_start = ceil_div(state.n_in, LEVEL_STEP)
    ms, bank, smooth, stages = fb.filter_bank(p, state.n_in, state.bank, state.smooth, state.stages, plan)
    core = zw.core_loudness(ms, diffuse=params.field == "diffuse")
    decayed, decay = zw.nonlinear_decay(core, state.decay, plan, started=k_start > 0)
    rows = zw.output_rows(k_start, core.shape[1])
    total, specific = zw.slopes(decayed, rows)
    weighted, weighting = zw.temporal_weighting(total, state.weighting, started=k_start > 0)
    keep = rows >= 0
    j0 = ceil_div(k_start, TW_STEP)
    t_s = (j0 + np.arange(int(keep.sum()))) * STEP_S
    result = LoudnessResult(t_s=t_s, loudness=weighted[keep], specific=specific)
    new_state = LoudnessState(method=state.method, field=state.field, n_in=state.n_in + p.shape[0],
                              bank=bank, smooth=smooth, stages=stages, decay=decay, weighting=weighting)
    return result, new_state


def loudness_zwtv(p: np.ndarray, *, params: LoudnessParams = LoudnessParams()) -> LoudnessResult:
    """Time-varying loudness of a whole signal (one :func:`loudness_update` from a fresh state).

    p : np.ndarray [shape=(n,)], Pa at 48 kHz.
    Returns :class:`LoudnessResult` with ceil(n / 96) samples on the 2 ms grid.
    """
    result, _ = loudness_update(p, init_state(params=params), params=params)
    return result


def loudness_stationary(p: np.ndarray, *, field: str = "free", skip_s: float = 0.0) -> tuple[float, np.ndarray]:
    """Stationary loudness (ISO 532-1 method for stationary sounds) of a whole signal.

    p : np.ndarray [shape=(n,)], Pa at 48 kHz. The third-octave levels are the mean squares of
    the ISO band filters' outputs over the signal after ``skip_s`` seconds (to skip the filters'
    onset); then core loudness and slopes as in the time-varying method (no decay, no weighting).
    Returns (N in sone, N'(z) [shape=(240,)] in sone/Bark).
    """
    p = check_pressure(p)
    LoudnessParams(field=field)  # validates the field
    skip = int(round(max(0.0, float(skip_s)) * SAMPLE_RATE_HZ))
    if p.shape[0] - skip < 1:
        raise ParameterError(f"stationary loudness needs samples after skip_s={skip_s} s; got {p.shape[0]} samples")
    sos, gain = fb.iso_sos()
    ms = np.empty(T.N_THIRD_OCTAVE_BANDS)
    K.bank_mean_square(p, sos, gain, skip, ms)
    core = zw.core_loudness(ms[:, None], diffuse=field == "diffuse")
    total, specific = zw.slopes(core, np.zeros(1, dtype=np.int64))
    return float(total[0]), specific[0]


def loudness_from_levels(levels_db: np.ndarray, *, field: str = "free") -> tuple[float, np.ndarray]:
    """Stationary loudness from 28 third-octave band levels (25 Hz .. 12.5 kHz), dB SPL.

    Returns (N in sone, N'(z) [shape=(240,)] in sone/Bark). ISO 532-1 test signal 1 uses this path.
    """
    levels = np.asarray(levels_db, dtype=np.float64)
    if levels.shape != (T.N_THIRD_OCTAVE_BANDS,):
        raise ParameterError(f"levels_db must have shape (28,), got {levels.shape}")
    if not np.isfinite(levels).all():
        raise ParameterError(f"levels_db holds {int((~np.isfinite(levels)).sum())} non-finite value(s)")
    if levels.max() > _MAX_LEVEL_DB:
        raise ParameterError(f"levels_db reaches {levels.max():.1f} dB; band levels above {_MAX_LEVEL_DB:.0f} dB "
                             "are not sound levels")
    LoudnessParams(field=field)  # validates the field
    ms = T.INTENSITY_REF * 10.0 ** (levels[:, None] / 10.0) - T.TINY_INTENSITY
    core = zw.core_loudness(np.maximum(ms, 0.0), diffuse=field == "diffuse")
    total, specific = zw.slopes(core, np.zeros(1, dtype=np.int64))
    return float(total[0]), specific[0]


def total_from_specific(specific: np.ndarray) -> np.ndarray:
    """Area under N'(z) on the 0.1 Bark grid: sum(N') * 0.1, sone. specific [shape=(..., 240)]."""
    return np.asarray(specific, dtype=np.float64).sum(axis=-1) * BARK_STEP


def n_steps(n_samples: int) -> int:
    """Number of 2 ms values for ``n_samples`` input samples at 48 kHz: ceil(n / 96)."""
    return ceil_div(int(n_samples), SAMPLES_PER_STEP)


# ------------------------------------------------------------------ input check
def check_pressure(p) -> np.ndarray:
    """``p`` as float64 [shape=(n,)] Pa, or ParameterError naming the shape, dtype or the count of
    non-finite samples; |p| above MAX_PRESSURE_PA (1e9 Pa) is an error (a calibration mistake)."""
    p = np.asarray(p)
    if p.ndim != 1:
        raise ParameterError(f"sound pressure must be a 1-D array [shape=(n,)], got shape {p.shape}")
    if p.dtype.kind not in "fiu":
        raise ParameterError(f"sound pressure must be real numbers, got dtype {p.dtype}")
    p = p.astype(np.float64, copy=False)
    peak = float(np.max(np.abs(p))) if p.size else 0.0  # NaN or inf if any sample is
    if not math.isfinite(peak):
        raise ParameterError(f"sound pressure holds {int((~np.isfinite(p)).sum())} non-finite sample(s) "
                             f"(NaN or inf) in an array of shape {p.shape}")
    if peak > MAX_PRESSURE_PA:
        raise ParameterError(f"sound pressure exceeds {MAX_PRESSURE_PA:g} Pa (max |p| = {peak:.3g} Pa): "
                             "check the calibration (pa_per_unit)")
    return p


def check_specific(specific) -> np.ndarray:
    """``specific`` as float64 [shape=(n, 240)] or [shape=(240,)] sone/Bark, negatives set to 0;
    ParameterError naming the shape or the count of non-finite values."""
    n_spec = np.asarray(specific, dtype=np.float64)
    if n_spec.shape[-1:] != (T.N_BARK,) or n_spec.ndim > 2:
        raise ParameterError(f"specific loudness must have shape (n, {T.N_BARK}) or ({T.N_BARK},), "
                             f"got {n_spec.shape}")
    bad = ~np.isfinite(n_spec)
    if bad.any():
        raise ParameterError(f"specific loudness holds {int(bad.sum())} non-finite value(s) (shape {n_spec.shape})")
    return np.maximum(n_spec, 0.0)
