"""ISO 532-1 step 1, the third-octave filter bank: its design per method and the filtering itself.

``"iso"`` runs the standard's 28 band filters (Table A.1/A.2) at 48 kHz. ``"fast"`` runs each band at
the lowest rate of a multirate chain 48 -> 24 -> 12 -> 6 -> 2 kHz that keeps at least 6 samples per
period of its centre frequency, behind elliptic anti-alias decimators; the bands below 48 kHz are
6th-order filters fitted to the ISO filter's complex response (:func:`rediscretise`). Output: band
mean squares in Pa^2 on the 2 kHz level grid (:mod:`autohaptics.intensity.loudness` composes it).
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass

import numpy as np

from autohaptics.cachedir import cached_arrays, digest, source_bytes
from autohaptics.errors import ParameterError
from autohaptics.intensity import iso532_tables as T
from autohaptics.intensity import compiled as K

SAMPLE_RATE_HZ = T.SAMPLE_RATE_HZ
LEVEL_STEP = SAMPLE_RATE_HZ // T.LEVEL_RATE_HZ  # 24 input samples per 0.5 ms level sample


def ceil_div(a: int, b: int) -> int:
    """ceil(a / b) for integers."""
    return -(-a // b)

@dataclass(frozen=True)
class BandGroup:
    rate_hz: int
    bands: np.ndarray  # indices into the 28 third-octave bands
    sos: np.ndarray  # [shape=(n_bands, 3, 6)]
    gain: np.ndarray  # [shape=(n_bands,)]
    smooth_a: np.ndarray  # [shape=(n_bands,)]

    @property
    def step(self) -> int:
        return self.rate_hz // T.LEVEL_RATE_HZ


@dataclass(frozen=True)
class Decimator:
    factor: int
    sos: np.ndarray  # [shape=(n_sections, 6)]


@dataclass(frozen=True)
class Plan:
    groups: tuple  # groups[0] runs at 48 kHz; groups[i + 1] after stages[i]
    stages: tuple
    nl_iterations: int
    nl_coef: np.ndarray  # [shape=(6,)]


def filter_bank(p: np.ndarray, n_in: int, bank: tuple, smooth: tuple, stages: tuple, plan: Plan):
    """Band mean squares [shape=(28, m)], Pa^2, at the 2 kHz samples completed by a chunk ``p``
    (Pa, 48 kHz) that follows ``n_in`` samples, and the new (bank, smooth, stages) states."""
    g0 = n_in
    m = ceil_div(g0 + p.shape[0], LEVEL_STEP) - ceil_div(g0, LEVEL_STEP)
    ms = np.empty((T.N_THIRD_OCTAVE_BANDS, m))
    bank = [z.copy() for z in bank]
    smooth = [z.copy() for z in smooth]
    stages = [z.copy() for z in stages]
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
            n_q = max(0, ceil_div(sig.shape[0] - first_q, q))
            dec = np.empty(n_q)
            K.sos_decimate(sig, plan.stages[gi].sos, stages[gi], first_q, q, dec)
            sig, start = dec, ceil_div(start, q)
    return ms, tuple(bank), tuple(smooth), tuple(stages)


@functools.lru_cache(maxsize=None)
def iso_sos() -> tuple[np.ndarray, np.ndarray]:
    """ISO 532-1 Table A.1/A.2 band filters: sos [shape=(28, 3, 6)] and gains [shape=(28,)]."""
    sos = np.empty((T.N_THIRD_OCTAVE_BANDS, 3, 6))
    sos[:, :, 0:4] = T.FILTER_REFERENCE_SOS[None, :, 0:4]
    sos[:, :, 4] = T.FILTER_REFERENCE_SOS[None, :, 4] - T.FILTER_A_DIFFERENCES[:, :, 0]
    sos[:, :, 5] = T.FILTER_REFERENCE_SOS[None, :, 5] - T.FILTER_A_DIFFERENCES[:, :, 1]
    return sos, T.FILTER_GAINS.copy()


def smoothing_pole(bands: np.ndarray, rate_hz: float) -> np.ndarray:
    fc = T.CENTRE_FREQUENCIES_HZ[bands]
    tau = 2.0 / (3.0 * np.minimum(fc, T.SMOOTHING_CORNER_HZ))
    return np.exp(-1.0 / (rate_hz * tau))


def nl_coefficients(n_iter: int) -> np.ndarray:
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
# rediscretise); the rates must be multiples of 2 kHz (the level grid).
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
def plan(method: str) -> Plan:
    """The filter bank of ``method`` ("iso" or "fast"); the fast bank's designs come from the
    cache folder after the first process designed them (:func:`fast_design`)."""
    sos, gain = iso_sos()
    if method == "iso":
        bands = np.arange(T.N_THIRD_OCTAVE_BANDS)
        grp = BandGroup(SAMPLE_RATE_HZ, bands, sos, gain, smoothing_pole(bands, SAMPLE_RATE_HZ))
        return Plan((grp,), (), T.NL_ITERATIONS, nl_coefficients(T.NL_ITERATIONS))
    key = "fast-bank-" + digest(source_bytes(__file__), source_bytes(T.__file__), np.__version__)
    design = cached_arrays("filters", key, fast_design)
    stages = tuple(Decimator(q, design[f"stage{i}"]) for i, (q, _, _) in enumerate(_FAST_STAGES))
    groups = []
    for gi, (rate, _) in enumerate(_FAST_GROUPS):
        bands = _group_bands(gi)
        groups.append(BandGroup(rate, bands, design[f"group{gi}_sos"], design[f"group{gi}_gain"],
                                smoothing_pole(bands, rate)))
    return Plan(tuple(groups), stages, _FAST_NL_ITERATIONS, nl_coefficients(_FAST_NL_ITERATIONS))


def fast_design() -> dict[str, np.ndarray]:
    """The fast bank's designed filters: ``stage<i>`` (decimator sos) and ``group<i>_sos`` /
    ``group<i>_gain`` (the band filters of each rate, ISO's own at 48 kHz)."""
    sos, gain = iso_sos()
    design, rate = {}, SAMPLE_RATE_HZ
    for i, (q, f_pass, f_stop) in enumerate(_FAST_STAGES):
        design[f"stage{i}"] = _decimator(rate, q, f_pass, f_stop)
        rate //= q
    for gi, (rate, _) in enumerate(_FAST_GROUPS):
        bands = _group_bands(gi)
        if rate == SAMPLE_RATE_HZ:
            g_sos, g_gain = sos[bands], gain[bands]
        else:
            designed = [rediscretise(sos[b], gain[b], T.CENTRE_FREQUENCIES_HZ[b], rate) for b in bands]
            g_sos = np.stack([d[0] for d in designed])
            g_gain = np.array([d[1] for d in designed])
        design[f"group{gi}_sos"], design[f"group{gi}_gain"] = g_sos, g_gain
    return design


def _group_bands(gi: int) -> np.ndarray:
    lo = _FAST_GROUPS[gi + 1][1] + 1 if gi + 1 < len(_FAST_GROUPS) else 0
    return np.arange(lo, _FAST_GROUPS[gi][1] + 1)


def rediscretise(sos48: np.ndarray, gain48: float, fc: float, rate: int) -> tuple[np.ndarray, float]:
    """A 6th-order band filter at ``rate`` whose complex response matches the ISO filter's.

    Fit (Sanathanan-Koerner iterations of the linearised equation error, i.e. what
    ``invfreqz`` does) of B(z) / A(z) with B(z) = (1 - z^-1)^3 C(z) (the ISO filter's triple zero
    at DC kept exactly, three free zeros) and six poles, to the ISO filter's response at
    :data:`_FIT_POINTS` log-spaced frequencies from fc / 16 to 0.45 ``rate``, each weighted by
    1 / max(|H|, -60 dB) so the relative error counts equally in the pass band and on the skirts.
    Above 0.45 ``rate`` the decimators have removed the signal. Matching the phase too keeps the
    filter's group delay, hence the timing of the band envelopes. Returns (sos [shape=(3, 6)], 1.0).
    """
    import scipy.signal as ss  # only while designing: importing it takes 0.7-1.1 s

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
    import scipy.signal as ss

    order, wn = ss.ellipord(f_pass, f_stop, _DECIMATOR_RIPPLE_DB, _DECIMATOR_STOP_DB, fs=rate)
    return ss.ellip(order, _DECIMATOR_RIPPLE_DB, _DECIMATOR_STOP_DB, wn, btype="low", output="sos", fs=rate)
