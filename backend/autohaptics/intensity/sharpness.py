"""Sharpness after DIN 45692:2009, from specific loudness.

    S = k * sum_z N'(z) g(z) z dz / sum_z N'(z) dz,   k = 0.11 acum,

on the 0.1 Bark grid z = 0.1 .. 24 Bark of :mod:`autohaptics.intensity.loudness`, with the DIN weighting
g(z) = 1 for z <= 15.8 Bark and 0.15 exp(0.42 (z - 15.8)) + 0.85 above (:func:`din_weighting`).

Decisions (ALGORITHM.md section 2):

- Numerator and denominator use the SAME loudness: the unsmoothed area of the N'(z) being
  weighted, never the temporally weighted N(t) of ISO 532-1 (mixing the two makes the onset of a
  short burst read as ~16 acum).
- Below ``min_loudness_sone`` (default 0.1 sone) sharpness is 0, so silence and near-silence give
  0 acum, never 0/0 or a value dominated by rounding.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar

import numpy as np

from autohaptics.intensity import iso532_tables as T
from autohaptics.intensity.loudness import Z_BARK, check_specific
from autohaptics.records import Record, param


@dataclass(frozen=True)
class SharpnessParams(Record):
    """Parameters of the sharpness stage.

    min_loudness_sone : float, sone; frames whose loudness (area of N'(z)) is below this have
        sharpness 0 (default 0.1).
    """

    GROUP: ClassVar[str] = "sharpness"

    min_loudness_sone: float = param(0.1, 0.0, 1e6, unit="sone")


def din_weighting(z_bark: np.ndarray) -> np.ndarray:
    """DIN 45692 weighting g(z) (dimensionless) for critical-band rates ``z_bark`` (Bark)."""
    z = np.asarray(z_bark, dtype=np.float64)
    return np.where(z > T.DIN_G_KNEE_BARK, T.DIN_G_A * np.exp(T.DIN_G_B * (z - T.DIN_G_KNEE_BARK)) + T.DIN_G_C, 1.0)


_MOMENT = T.DIN_SHARPNESS_K * din_weighting(Z_BARK) * Z_BARK  # acum per sone, per grid point


def sharpness(*, specific: np.ndarray, params: SharpnessParams = SharpnessParams()) -> np.ndarray:
    """DIN 45692 sharpness of each specific-loudness pattern.

    specific : np.ndarray [shape=(n, 240)] (or [shape=(240,)]), sone/Bark on z = 0.1 .. 24 Bark.
    Returns np.ndarray [shape=(n,)] (or a 0-d array), acum, finite and >= 0.
    """
    n_spec = check_specific(specific)
    area = n_spec.sum(axis=-1)  # sone / 0.1 Bark: the dz factors cancel in the ratio
    moment = (n_spec * _MOMENT).sum(axis=-1)  # row by row: the same result whatever the batch
    out = np.zeros_like(area)
    loud = area * T.BARK_STEP >= max(float(params.min_loudness_sone), np.finfo(float).tiny)
    np.divide(moment, area, out=out, where=loud)
    return out
