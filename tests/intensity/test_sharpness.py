"""DIN 45692 sharpness from specific loudness: weighting, known answers, the 0/0 guard, errors."""

from __future__ import annotations

import numpy as np
import pytest
import scipy.signal as ss

from autohaptics.intensity import loudness as L
from autohaptics.intensity import sharpness as S
from autohaptics.errors import ParameterError

FS = 48_000
Z = L.Z_BARK


def band_noise(lo_hz: float, hi_hz: float, db_spl: float, dur_s: float = 1.5, seed: int = 0) -> np.ndarray:
    x = np.random.default_rng(seed).standard_normal(int(dur_s * FS))
    x = ss.sosfilt(ss.butter(8, [lo_hz, hi_hz], btype="band", output="sos", fs=FS), x)
    return x / np.sqrt(np.mean(x ** 2)) * 2e-5 * 10 ** (db_spl / 20)


def stationary_sharpness(x: np.ndarray) -> float:
    return float(S.sharpness(specific=L.loudness_stationary(x, skip_s=0.3)[1]))


def test_din_weighting_values():
    g = S.din_weighting(np.array([0.1, 10.0, 15.8, 20.0, 24.0]))
    np.testing.assert_allclose(g[:3], 1.0)
    np.testing.assert_allclose(g[3], 0.15 * np.exp(0.42 * 4.2) + 0.85)
    assert g[4] == pytest.approx(0.15 * np.exp(0.42 * 8.2) + 0.85)


def test_critical_band_noise_at_1khz_60db_is_one_acum():
    # The definition of the acum: a critical-band-wide noise at 1 kHz and 60 dB.
    assert stationary_sharpness(band_noise(920, 1080, 60)) == pytest.approx(1.0, abs=0.05)


def test_higher_bands_are_sharper_and_level_barely_matters():
    s1 = stationary_sharpness(band_noise(920, 1080, 60))
    s4 = stationary_sharpness(band_noise(3700, 4300, 60))
    s10 = stationary_sharpness(band_noise(9500, 11500, 60))
    assert s1 < s4 < s10
    # Nearly level independent over a few dB (a louder band spreads its upper slope: +20 dB reads
    # ~12 % sharper); 4 dB is the spread of the two DIN calibration conventions.
    assert stationary_sharpness(band_noise(3700, 4300, 64)) == pytest.approx(s4, rel=0.05)
    assert stationary_sharpness(band_noise(3700, 4300, 80)) > s4


def test_single_bark_patterns_give_the_first_moment():
    spec = np.zeros((3, 240))
    spec[0, 84] = 1.0  # z = 8.5 Bark, g = 1
    spec[1, 199] = 2.0  # z = 20.0 Bark, g > 1
    s = S.sharpness(specific=spec, params=S.SharpnessParams(min_loudness_sone=0.05))
    assert s[0] == pytest.approx(0.11 * 8.5)
    assert s[1] == pytest.approx(0.11 * 20.0 * S.din_weighting(20.0))
    assert s[2] == 0.0


def test_scale_invariance_above_the_threshold():
    rng = np.random.default_rng(1)
    spec = rng.random((5, 240))
    np.testing.assert_allclose(S.sharpness(specific=spec), S.sharpness(specific=spec * 7.3))


def test_below_min_loudness_is_zero_never_nan():
    spec = np.zeros((4, 240))
    spec[1, 100] = 0.5  # area 0.05 sone < 0.1
    spec[2, 100] = 1e-300
    spec[3, 100] = 2.0  # area 0.2 sone
    s = S.sharpness(specific=spec)
    assert s[0] == 0.0 and s[1] == 0.0 and s[2] == 0.0 and s[3] > 0
    assert S.sharpness(specific=spec, params=S.SharpnessParams(min_loudness_sone=0.0))[1] > 0
    assert S.sharpness(specific=spec, params=S.SharpnessParams(min_loudness_sone=0.0))[0] == 0.0


def test_one_pattern_gives_a_scalar():
    spec = np.zeros(240)
    spec[50] = 3.0
    out = S.sharpness(specific=spec)
    assert out.shape == () and float(out) == pytest.approx(0.11 * 5.1)


def test_errors():
    with pytest.raises(ParameterError, match="shape"):
        S.sharpness(specific=np.zeros((3, 24)))
    with pytest.raises(ParameterError, match="2 non-finite"):
        S.sharpness(specific=np.array([[np.nan] * 2 + [0.0] * 238]))
    with pytest.raises(ParameterError, match="min_loudness_sone"):
        S.SharpnessParams(min_loudness_sone=-1)
