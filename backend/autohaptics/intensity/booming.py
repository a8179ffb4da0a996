"""Booming index from specific loudness (ALGORITHM.md section 2; definition and its sources in
../shared/reference/psychoacoustics/README.txt).

Variant ``"hatano"`` (default), the linear Hatano & Hashimoto-type index::

    BI = (sum_z w(z) N'(z) dz) * N_LF / N

- w(z) = 2.13 exp(-0.151 i(z)): the third-octave-index weight evaluated on the Bark grid with
  f(z) = 600 sinh(z / 6) Hz and i(z) = 10 log10(f / 25 Hz) + 1 (25 Hz -> i = 1, w = 1.83;
  250 Hz -> 0.40; 1 kHz -> 0.16; 12.5 kHz -> 0.03). Below 25 Hz the same formula goes on rising.
- N_LF = sum of N'(z) dz over the grid points with f(z) < ``lf_cutoff_hz`` (280 Hz: z < 2.7 Bark).
- N = sum of N'(z) dz (the same unsmoothed loudness as the numerator, as for sharpness).
The index is in sone (dimensionless after the clip normalisation the pipeline applies). It is
not the AudioCommons regression (no dB sum, no low-frequency weight overrides, no listening-test
fit): those peculiarities are listed in the README and deliberately not copied.

Variant ``"paper"``: the seed thesis's eq. 3.3 read literally,
``B = sum_{z >= 0.3} N'(z) z / (0.49529 z + 0.14176) dz / N``. It is ~2 for ANY sound (the
integrand's factor is ~2.0 above 3 Bark) and rises with frequency, so it does NOT measure
booming; it is kept only to reproduce the thesis.

Both variants: BI = 0 when N < ``min_loudness_sone`` (silence gives exactly 0, never 0/0).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar

import numpy as np

from autohaptics.intensity import iso532_tables as T
from autohaptics.intensity.loudness import Z_BARK, check_specific
from autohaptics.records import Record, param

BOOMING_VARIANTS = ("hatano", "paper")

_W_A = 2.13  # weight at band index 0
_W_B = 0.151  # decay per third-octave band
_PAPER_A = 0.49529
_PAPER_B = 0.14176
_PAPER_Z_MIN = 0.3  # Bark, lower integration limit of eq. 3.3


@dataclass(frozen=True)
class BoomingParams(Record):
    """Parameters of the booming stage.

    variant : "hatano" (default, linear Hatano-type index) or "paper" (thesis eq. 3.3).
    lf_cutoff_hz : float, Hz; upper frequency of the low-frequency loudness N_LF (default 280).
    min_loudness_sone : float, sone; below this loudness the index is 0 (default 0.1).
    """

    GROUP: ClassVar[str] = "booming"

    variant: str = param("hatano", choices=BOOMING_VARIANTS)
    lf_cutoff_hz: float = param(280.0, hi=24_000.0, gt=0.0, unit="Hz")
    min_loudness_sone: float = param(0.1, 0.0, 1e6, unit="sone")


def bark_to_hz(z_bark: np.ndarray) -> np.ndarray:
    """f = 600 sinh(z / 6), Hz (the Bark-to-frequency map the booming weight is defined on)."""
    return 600.0 * np.sinh(np.asarray(z_bark, dtype=np.float64) / 6.0)


def booming_weight(z_bark: np.ndarray) -> np.ndarray:
    """w(z) = 2.13 exp(-0.151 (10 log10(f(z) / 25 Hz) + 1)), dimensionless."""
    index = 10.0 * np.log10(bark_to_hz(z_bark) / 25.0) + 1.0
    return _W_A * np.exp(-_W_B * index)


_HATANO_W = booming_weight(Z_BARK)
_PAPER_W = np.where(Z_BARK >= _PAPER_Z_MIN - 1e-9, Z_BARK / (_PAPER_A * Z_BARK + _PAPER_B), 0.0)


def booming(*, specific: np.ndarray, params: BoomingParams = BoomingParams()) -> np.ndarray:
    """Booming index of each specific-loudness pattern.

    specific : np.ndarray [shape=(n, 240)] (or [shape=(240,)]), sone/Bark on z = 0.1 .. 24 Bark.
    Returns np.ndarray [shape=(n,)] (or 0-d), finite and >= 0: sone for "hatano",
    dimensionless for "paper".
    """
    n_spec = check_specific(specific)
    area = n_spec.sum(axis=-1) * T.BARK_STEP  # N, sone
    loud = area >= max(float(params.min_loudness_sone), np.finfo(float).tiny)
    out = np.zeros_like(area)
    if params.variant == "hatano":
        low = (bark_to_hz(Z_BARK) < params.lf_cutoff_hz).astype(np.float64)
        weighted = (n_spec * _HATANO_W).sum(axis=-1) * T.BARK_STEP
        n_lf = (n_spec * low).sum(axis=-1) * T.BARK_STEP  # row by row: the same result whatever the batch
        ratio = np.zeros_like(area)
        np.divide(n_lf, area, out=ratio, where=loud)
        out = np.where(loud, weighted * ratio, 0.0)
    else:
        np.divide((n_spec * _PAPER_W).sum(axis=-1) * T.BARK_STEP, area, out=out, where=loud)
    return out
