"""Zwicker loudness, ISO 532-1:2017 (time-varying method, free or diffuse field), streaming.

Recipe (one named private step each, ISO 532-1 clause 6 / Annex A):

1. ``_filter_bank``: 28 third-octave band-pass filters (25 Hz .. 12.5 kHz), squaring and three
   cascaded first-order smoothers, sampled every 0.5 ms (2 kHz) -> band mean squares, Pa^2.
2. ``_core_loudness``: band levels re (20 uPa)^2, equal-loudness corrections of the bands
   <= 250 Hz and their merge into three critical bands, ear transmission (A0), optional
   diffuse-field correction (DDF), threshold in quiet (LTQ), third-octave-to-critical-band
   adaptation (DCB) and Zwicker's power law -> core loudness of 21 critical bands, sone/Bark.
   (Computed on intensities: every dB comparison of the standard is exact in that domain.)
3. ``_nonlinear_decay``: the two-capacitor decay network (time constants 5, 15, 75 ms), run on
   24 virtual sub-steps per 0.5 ms sample ("fast": 2) with the input interpolated linearly.
4. ``_slopes``: the upper slopes (USL/RNS tables) -> specific loudness N'(z) on the 240-point
   grid z = 0.1 .. 24 Bark and its area, the total loudness N, sone.
5. ``_temporal_weighting``: 0.47 x (3.5 ms low-pass) + 0.53 x (70 ms low-pass) of N, again on a
   24x interpolated rate -> N(t), sampled every 2 ms (the ISO output grid).

Input: sound pressure in pascal at 48 kHz (ISO 532-1 defines its filters at 48 kHz only; resample
other rates before, e.g. :func:`autohaptics.media.iter_audio` does). Output: the 2 ms grid,
sample k at t = 0.002 k s, i.e. input sample 96 k; a signal of n samples gives ceil(n / 96)
values. N'(z, t) is sampled at the same instants (before temporal weighting, as in ISO).

Methods (:data:`LOUDNESS_METHODS`):

- ``"iso"`` (the ``reference`` preset): the standard's own filter coefficients (Table A.1/A.2),
  every band at 48 kHz, every stage at 2 kHz with 24 virtual sub-steps. Passes the ISO 532-1
  tolerance on test signals 6-25 (see tests/test_iso532_reference.py).
- ``"fast"`` (default): each band filter runs at the lowest rate of a multirate chain
  48 -> 24 -> 12 -> 6 -> 2 kHz that keeps at least 6 samples per period of its centre frequency
  (12.5-5 kHz at 48 kHz, 4-2.5 kHz at 24, 2-1.25 kHz at 12, 1 kHz-400 Hz at 6, 315 Hz and below
  at 2 kHz), behind elliptic anti-alias decimators (0.01 dB ripple, 90 dB stop band). The
  bands below 48 kHz are 6th-order IIR filters fitted to the complex response of the ISO filter
  (keeping its triple zero at DC; see ``_rediscretise``), and the decay network takes 2 virtual
  sub-steps per 0.5 ms instead of 24 (its constants recomputed exactly for the longer step).
  Everything else is identical. On ISO test signals 6-25 it also keeps 100 % of the 2 ms samples
  in the 5 % band; its deviation from ``"iso"`` is measured by tests/test_loudness.py and printed
  by ``autohaptics bench audio`` (median < 0.5 %, onsets up to ~0.2 ms later).

Out-of-range input: ISO 532-1 Table A.3 is specified only up to 120 dB in the bands up to 250 Hz
and the standard is undefined above. This implementation CLAMPS those band levels to 120 dB
(it does not raise), so a louder low-frequency band reads as a 120 dB band. Sound pressure
magnitudes above :data:`MAX_PRESSURE_PA` and non-finite samples raise ParameterError.

Streaming: :func:`init_state` -> :func:`loudness_update` per chunk (returns the 2 ms samples that
became complete and the new state) -> the concatenation equals :func:`loudness_zwtv` on the whole
signal (same arithmetic in the same order). The state is an immutable record: an update never
modifies the state passed in.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass, field

import numpy as np
import scipy.signal as ss

from autohaptics import _iso532_tables as T
from autohaptics import _loudness_kernels as K
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

_LEVEL_STEP = SAMPLE_RATE_HZ // T.LEVEL_RATE_HZ  # 24 input samples per 0.5 ms level sample
_TW_STEP = T.LEVEL_RATE_HZ // T.LOUDNESS_RATE_HZ  # 4 level samples per 2 ms output


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
    plan = _plan(params.method)
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
    plan = _plan(params.method)
    k_start = _ceil_div(state.n_in, _LEVEL_STEP)
    ms, bank, smooth, stages = _filter_bank(p, state, plan)
    core = _core_loudness(ms, diffuse=params.field == "diffuse")
    decayed, decay = _nonlinear_decay(core, state.decay, plan, started=k_start > 0)
    rows = _output_rows(k_start, core.shape[1])
    total, specific = _slopes(decayed, rows)
    weighted, weighting = _temporal_weighting(total, state.weighting, started=k_start > 0)
    keep = rows >= 0
    j0 = _ceil_div(k_start, _TW_STEP)
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
    sos, gain = _iso_sos()
    ms = np.empty(T.N_THIRD_OCTAVE_BANDS)
    K.bank_mean_square(p, sos, gain, skip, ms)
    core = _core_loudness(ms[:, None], diffuse=field == "diffuse")
    total, specific = _slopes(core, np.zeros(1, dtype=np.int64))
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
    core = _core_loudness(np.maximum(ms, 0.0), diffuse=field == "diffuse")
    total, specific = _slopes(core, np.zeros(1, dtype=np.int64))
    return float(total[0]), specific[0]


def total_from_specific(specific: np.ndarray) -> np.ndarray:
    """Area under N'(z) on the 0.1 Bark grid: sum(N') * 0.1, sone. specific [shape=(..., 240)]."""
    return np.asarray(specific, dtype=np.float64).sum(axis=-1) * BARK_STEP


def n_steps(n_samples: int) -> int:
    """Number of 2 ms values for ``n_samples`` input samples at 48 kHz: ceil(n / 96)."""
    return _ceil_div(int(n_samples), SAMPLES_PER_STEP)


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


# ------------------------------------------------------------------ step 1: filter bank
@dataclass(frozen=True)
class _Group:
    rate_hz: int
    bands: np.ndarray  # indices into the 28 third-octave bands
    sos: np.ndarray  # [shape=(n_bands, 3, 6)]
    gain: np.ndarray  # [shape=(n_bands,)]
    smooth_a: np.ndarray  # [shape=(n_bands,)]

    @property
    def step(self) -> int:
        return self.rate_hz // T.LEVEL_RATE_HZ


@dataclass(frozen=True)
class _Stage:
    factor: int
    sos: np.ndarray  # [shape=(n_sections, 6)]


@dataclass(frozen=True)
class _Plan:
    groups: tuple  # groups[0] runs at 48 kHz; groups[i + 1] after stages[i]
    stages: tuple
    nl_iterations: int
    nl_coef: np.ndarray  # [shape=(6,)]


def _filter_bank(p: np.ndarray, state: LoudnessState, plan: _Plan):
    """Band mean squares [shape=(28, m)], Pa^2, at the 2 kHz samples completed by this chunk."""
    g0 = state.n_in
    m = _ceil_div(g0 + p.shape[0], _LEVEL_STEP) - _ceil_div(g0, _LEVEL_STEP)
    ms = np.empty((T.N_THIRD_OCTAVE_BANDS, m))
    bank = [z.copy() for z in state.bank]
    smooth = [z.copy() for z in state.smooth]
    stages = [z.copy() for z in state.stages]
    sig, start = p, g0
    for gi, grp in enumerate(plan.groups):
        step = grp.step
        first = (-start) % step
        out = np.empty((len(grp.bands), m))
        K.bank_square_smooth(sig, grp.sos, grp.gain, grp.smooth_a, bank[gi], smooth[gi], first, step, out)
        ms[grp.bands] = out
        if gi < len(plan.stages):
            q = plan.stages[gi].factor
            first_q = (-start) % q
            n_q = max(0, _ceil_div(sig.shape[0] - first_q, q))
            dec = np.empty(n_q)
            K.sos_decimate(sig, plan.stages[gi].sos, stages[gi], first_q, q, dec)
            sig, start = dec, _ceil_div(start, q)
    return ms, tuple(bank), tuple(smooth), tuple(stages)


@functools.lru_cache(maxsize=None)
def _iso_sos() -> tuple[np.ndarray, np.ndarray]:
    """ISO 532-1 Table A.1/A.2 band filters: sos [shape=(28, 3, 6)] and gains [shape=(28,)]."""
    sos = np.empty((T.N_THIRD_OCTAVE_BANDS, 3, 6))
    sos[:, :, 0:4] = T.FILTER_REFERENCE_SOS[None, :, 0:4]
    sos[:, :, 4] = T.FILTER_REFERENCE_SOS[None, :, 4] - T.FILTER_A_DIFFERENCES[:, :, 0]
    sos[:, :, 5] = T.FILTER_REFERENCE_SOS[None, :, 5] - T.FILTER_A_DIFFERENCES[:, :, 1]
    return sos, T.FILTER_GAINS.copy()


def _smoothing_pole(bands: np.ndarray, rate_hz: float) -> np.ndarray:
    fc = T.CENTRE_FREQUENCIES_HZ[bands]
    tau = 2.0 / (3.0 * np.minimum(fc, T.SMOOTHING_CORNER_HZ))
    return np.exp(-1.0 / (rate_hz * tau))


def _nl_coefficients(n_iter: int) -> np.ndarray:
    """Constants B0..B5 of the decay network for a sub-step of 1 / (2 kHz * n_iter) s."""
    ts, tl, tv = T.NL_T_SHORT_S, T.NL_T_LONG_S, T.NL_T_VAR_S
    dt = 1.0 / (T.LEVEL_RATE_HZ * n_iter)
    p = (tv + tl) / (tv * ts)
    q = 1.0 / (ts * tv)
    l1 = -p / 2 + math.sqrt(p * p / 4 - q)
    l2 = -p / 2 - math.sqrt(p * p / 4 - q)
    den = tv * (l1 - l2)
    e1, e2 = math.exp(l1 * dt), math.exp(l2 * dt)
    return np.array([
        (e1 - e2) / den,
        ((tv * l2 + 1) * e1 - (tv * l1 + 1) * e2) / den,
        ((tv * l1 + 1) * e1 - (tv * l2 + 1) * e2) / den,
        (tv * l1 + 1) * (tv * l2 + 1) * (e1 - e2) / den,
        math.exp(-dt / tl),
        math.exp(-dt / tv),
    ])


# Multirate layout of the "fast" bank: (rate, highest band index at that rate), from 48 kHz down;
# each group holds the bands below the previous one. A band runs at the lowest rate of the chain
# with rate / fc >= 6 (fitted 6th-order filters match ISO's within ~0.25 dB there, see
# _rediscretise); the rates must be multiples of 2 kHz (the level grid).
_FAST_GROUPS = ((48_000, 27), (24_000, 22), (12_000, 19), (6_000, 16), (2_000, 11))
# Anti-alias decimator before each lower group: (factor, passband edge Hz, stopband edge Hz);
# pass band 0.3 and stop band 0.7 of the output rate, so aliases land only above 0.3 x rate.
_FAST_STAGES = ((2, 7_200.0, 16_800.0), (2, 3_600.0, 8_400.0), (2, 1_800.0, 4_200.0), (3, 600.0, 1_400.0))
_DECIMATOR_RIPPLE_DB = 0.01
_DECIMATOR_STOP_DB = 90.0
_FAST_NL_ITERATIONS = 2
_FIT_POINTS = 600
_FIT_ITERATIONS = 8
_FIT_FLOOR_DB = -60.0


@functools.lru_cache(maxsize=None)
def _plan(method: str) -> _Plan:
    sos, gain = _iso_sos()
    if method == "iso":
        bands = np.arange(T.N_THIRD_OCTAVE_BANDS)
        grp = _Group(SAMPLE_RATE_HZ, bands, sos, gain, _smoothing_pole(bands, SAMPLE_RATE_HZ))
        return _Plan((grp,), (), T.NL_ITERATIONS, _nl_coefficients(T.NL_ITERATIONS))
    groups, stages = [], []
    rate = SAMPLE_RATE_HZ
    for q, f_pass, f_stop in _FAST_STAGES:
        stages.append(_Stage(q, _decimator(rate, q, f_pass, f_stop)))
        rate //= q
    for gi, (rate, hi) in enumerate(_FAST_GROUPS):
        lo = _FAST_GROUPS[gi + 1][1] + 1 if gi + 1 < len(_FAST_GROUPS) else 0
        bands = np.arange(lo, hi + 1)
        if rate == SAMPLE_RATE_HZ:
            g_sos, g_gain = sos[bands], gain[bands]
        else:
            designed = [_rediscretise(sos[b], gain[b], T.CENTRE_FREQUENCIES_HZ[b], rate) for b in bands]
            g_sos = np.stack([d[0] for d in designed])
            g_gain = np.array([d[1] for d in designed])
        groups.append(_Group(rate, bands, g_sos, g_gain, _smoothing_pole(bands, rate)))
    return _Plan(tuple(groups), tuple(stages), _FAST_NL_ITERATIONS, _nl_coefficients(_FAST_NL_ITERATIONS))


def _rediscretise(sos48: np.ndarray, gain48: float, fc: float, rate: int) -> tuple[np.ndarray, float]:
    """A 6th-order band filter at ``rate`` whose complex response matches the ISO filter's.

    Fit (Sanathanan-Koerner iterations of the linearised equation error, i.e. what
    ``invfreqz`` does) of B(z) / A(z) with B(z) = (1 - z^-1)^3 C(z) (the ISO filter's triple zero
    at DC kept exactly, three free zeros) and six poles, to the ISO filter's response at
    :data:`_FIT_POINTS` log-spaced frequencies from fc / 16 to 0.45 ``rate``, each weighted by
    1 / max(|H|, -60 dB) so the relative error counts equally in the pass band and on the skirts.
    Above 0.45 ``rate`` the decimators have removed the signal. Matching the phase too keeps the
    filter's group delay, hence the timing of the band envelopes. Returns (sos [shape=(3, 6)], 1.0).
    """
    f = np.geomspace(max(fc / 16.0, 5.0), 0.45 * rate, _FIT_POINTS)
    target = ss.sosfreqz(sos48, worN=f, fs=SAMPLE_RATE_HZ)[1] * gain48
    zinv = np.exp(-2j * np.pi * f / rate)
    dc_zeros = (1.0 - zinv) ** 3
    weight = 1.0 / np.maximum(np.abs(target), 10.0 ** (_FIT_FLOOR_DB / 20.0))
    basis = np.stack([dc_zeros * zinv ** k for k in range(4)] + [-target * zinv ** k for k in range(1, 7)], axis=1)
    den = np.ones_like(target)
    for _ in range(_FIT_ITERATIONS):
        w = weight / np.abs(den)
        m = basis * w[:, None]
        rhs = target * w
        sol = _least_squares(np.vstack([m.real, m.imag]), np.concatenate([rhs.real, rhs.imag]))
        a = np.concatenate([[1.0], sol[4:]])
        den = np.polynomial.polynomial.polyval(zinv, a)
    b = np.convolve([1.0, -3.0, 3.0, -1.0], sol[:4])
    sos = ss.tf2sos(b, a)
    if np.max(np.abs(np.roots(a))) >= 1.0:
        raise ParameterError(f"band filter design at {fc:.0f} Hz / {rate} Hz is unstable")
    return sos, 1.0


def _least_squares(m: np.ndarray, rhs: np.ndarray) -> np.ndarray:
    """argmin |m x - rhs| by Householder QR (m [shape=(rows, n)], n small).

    The basis is ill-conditioned for the lowest bands (condition ~1e8, so normal equations fail)
    and LAPACK's least-squares drivers cost ~25 ms per call under a multi-threaded OpenBLAS.
    """
    a = m.copy()
    y = rhs.copy()
    n = a.shape[1]
    for k in range(n):
        v = a[k:, k].copy()
        alpha = -math.copysign(float(np.linalg.norm(v)), float(v[0]))
        v[0] -= alpha
        vv = float(v @ v)
        if vv == 0.0:
            continue
        a[k:, k:] -= np.outer(v, (2.0 / vv) * (v @ a[k:, k:]))
        y[k:] -= v * ((2.0 / vv) * float(v @ y[k:]))
    return _back_substitute(a[:n, :n], y[:n])


def _back_substitute(r: np.ndarray, y: np.ndarray) -> np.ndarray:
    n = r.shape[0]
    x = np.zeros(n)
    for i in range(n - 1, -1, -1):
        x[i] = (y[i] - r[i, i + 1:] @ x[i + 1:]) / r[i, i]
    return x


def _decimator(rate: int, q: int, f_pass: float, f_stop: float) -> np.ndarray:
    order, wn = ss.ellipord(f_pass, f_stop, _DECIMATOR_RIPPLE_DB, _DECIMATOR_STOP_DB, fs=rate)
    return ss.ellip(order, _DECIMATOR_RIPPLE_DB, _DECIMATOR_STOP_DB, wn, btype="low", output="sos", fs=rate)


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


def _core_loudness(ms: np.ndarray, *, diffuse: bool) -> np.ndarray:
    """Core loudness [shape=(21, m)], sone/Bark, from band mean squares [shape=(28, m)], Pa^2.

    The 11 bands up to 250 Hz are clamped to 120 dB (the limit of ISO 532-1 Table A.3).
    """
    out = np.empty((len(T.ZUP), ms.shape[1]))
    K.core_loudness(np.ascontiguousarray(ms), T.TINY_INTENSITY, T.INTENSITY_REF,
                    10.0 ** (T.MAX_LOW_FREQUENCY_LEVEL_DB / 10.0), *_core_tables(bool(diffuse)), out)
    return out


# ------------------------------------------------------------------ step 3: decay
def _nonlinear_decay(core: np.ndarray, decay: np.ndarray, plan: _Plan, *, started: bool):
    decay = decay.copy()
    out = np.empty_like(core)
    flag = np.array([1 if started else 0], dtype=np.int64)
    uo, u2, prev = decay[0].copy(), decay[1].copy(), decay[2].copy()
    K.nonlinear_decay(np.ascontiguousarray(core), plan.nl_coef, plan.nl_iterations, T.NL_EQUAL_TOLERANCE,
                      uo, u2, prev, flag, out)
    return out, np.stack([uo, u2, prev])


# ------------------------------------------------------------------ step 4: slopes
_ZUP = T.ZUP + T.ZUP_EPS
_USL = np.ascontiguousarray(T.USL)
_RNS = T.RNS.astype(np.float64)


def _output_rows(k_start: int, m: int) -> np.ndarray:
    """Row in the 2 ms output of each 2 kHz sample k_start .. k_start + m - 1 (or -1)."""
    k = k_start + np.arange(m, dtype=np.int64)
    on_grid = k % _TW_STEP == 0
    rows = np.full(m, -1, dtype=np.int64)
    rows[on_grid] = np.arange(int(on_grid.sum()), dtype=np.int64)
    return rows


def _slopes(core: np.ndarray, rows: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Total loudness [shape=(m,)] (sone) and N'(z) [shape=(n_rows, 240)] (sone/Bark)."""
    m = core.shape[1]
    total = np.empty(m)
    specific = np.empty((int((rows >= 0).sum()), T.N_BARK))
    K.slopes(np.ascontiguousarray(core), _ZUP, _RNS, _USL, rows, total, specific)
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


def _temporal_weighting(total: np.ndarray, weighting: np.ndarray, *, started: bool):
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
            y[i0:], zf = ss.lfilter([b_now, b_prev], [1.0, -pole], x[i0:], zi=[zi])
            zi = float(zf[0])
        new[idx] = zi
        out += wgt * y
    return out, new


# ------------------------------------------------------------------ helpers
def _ceil_div(a: int, b: int) -> int:
    return -(-a // b)
