"""Low-frequency energy: mean square below the cutoff per 20 ms frame, streaming, errors."""

from __future__ import annotations

import numpy as np
import pytest

from autohaptics.intensity import low_energy as LE
from autohaptics.errors import ParameterError

FS = 48_000


def tone(f_hz: float, rms_pa: float, dur_s: float = 1.0) -> np.ndarray:
    t = np.arange(int(dur_s * FS)) / FS
    return np.sqrt(2.0) * rms_pa * np.sin(2 * np.pi * f_hz * t)


def test_low_tone_carries_its_mean_square_high_tone_almost_nothing():
    e100 = LE.low_energy(tone(100, 1.0))
    e2k = LE.low_energy(tone(2000, 1.0))
    assert np.median(e100[10:]) == pytest.approx(1.0, rel=0.05)  # 100 Hz: 5 whole periods per frame
    assert np.median(e2k[10:]) < 1e-6
    assert np.median(e100[10:]) > 1e5 * np.median(e2k[10:])


def test_frame_count_and_partial_last_frame():
    for n in (1, 959, 960, 961, 4800, 4801):
        assert LE.low_energy(np.full(n, 0.1)).shape == (-(-n // 960),)
    x = np.full(961, 0.5)
    e = LE.low_energy(x)
    assert e[1] > 0  # one sample in the last frame, averaged over itself


def test_silence_is_zero():
    np.testing.assert_array_equal(LE.low_energy(np.zeros(5000)), 0.0)


def test_dc_is_low_frequency():
    e = LE.low_energy(np.full(FS, 2.0))
    assert e[-1] == pytest.approx(4.0, rel=1e-3)


def test_cutoff_parameter():
    x = tone(300, 1.0)
    at_215 = np.median(LE.low_energy(x)[10:])
    at_600 = np.median(LE.low_energy(x, params=LE.LowEnergyParams(cutoff_hz=600))[10:])
    assert at_600 > 0.9 and at_215 < 0.3


def test_chunked_equals_whole():
    x = np.random.default_rng(2).standard_normal(3 * FS + 17)
    whole = LE.low_energy(x)
    state = LE.init_state()
    parts, i = [], 0
    for n in [0, 1, 959, 960, 961, 5, 40000] + [30000] * 10:
        out, state = LE.low_energy_update(x[i:i + n], state)
        parts.append(out)
        i += n
        if i >= x.size:
            break
    parts.append(LE.low_energy_finish(state))
    np.testing.assert_array_equal(np.concatenate(parts), whole)


def test_errors():
    with pytest.raises(ParameterError, match="3 non-finite"):
        LE.low_energy(np.array([0.0, np.nan, np.inf, -np.inf]))
    with pytest.raises(ParameterError, match="cutoff_hz"):
        LE.LowEnergyParams(cutoff_hz=30000)
    with pytest.raises(ParameterError, match="order"):
        LE.LowEnergyParams(order=0)
    with pytest.raises(ParameterError, match="other parameters"):
        LE.low_energy_update(np.zeros(10), LE.init_state(), params=LE.LowEnergyParams(cutoff_hz=100))
