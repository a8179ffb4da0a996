"""ISO 532-1 loudness: known answers on synthetic signals, the 2 ms grid, streaming, errors, and
the agreement of the fast multirate method with the standard's filter bank."""

from __future__ import annotations

import numpy as np
import pytest
import scipy.signal as ss

from autohaptics.intensity import filterbank as FB
from autohaptics.intensity import loudness as L
from autohaptics.errors import ParameterError

FS = 48_000
P_REF = 2e-5


def tone(f_hz: float, db_spl: float, dur_s: float = 1.0) -> np.ndarray:
    t = np.arange(int(round(dur_s * FS))) / FS
    return np.sqrt(2.0) * P_REF * 10 ** (db_spl / 20) * np.sin(2 * np.pi * f_hz * t)


def steady(result: L.LoudnessResult, after_s: float = 0.5) -> float:
    return float(np.median(result.loudness[result.t_s >= after_s]))


@pytest.fixture(params=L.LOUDNESS_METHODS)
def params(request) -> L.LoudnessParams:
    return L.LoudnessParams(method=request.param)


def test_1khz_tone_at_40_db_is_one_sone(params):
    n_stat, _ = L.loudness_stationary(tone(1000, 40), skip_s=0.2)
    assert n_stat == pytest.approx(1.0, rel=0.05)
    assert steady(L.loudness_zwtv(tone(1000, 40), params=params)) == pytest.approx(1.0, rel=0.05)


@pytest.mark.parametrize("level", [40.0, 60.0, 70.0])
def test_ten_db_more_roughly_doubles_loudness(params, level):
    quiet = steady(L.loudness_zwtv(tone(1000, level), params=params))
    loud = steady(L.loudness_zwtv(tone(1000, level + 10), params=params))
    assert loud / quiet == pytest.approx(2.0, rel=0.1)


def test_silence_is_exactly_zero(params):
    r = L.loudness_zwtv(np.zeros(FS // 2), params=params)
    assert r.loudness.shape == (250,)
    assert np.all(r.loudness == 0.0)
    assert np.all(r.specific == 0.0)


@pytest.mark.parametrize("n", [1, 95, 96, 97, 4800, 4801])
def test_output_grid_and_axes(n):
    r = L.loudness_zwtv(np.full(n, 0.01))
    m = -(-n // 96)
    assert L.n_steps(n) == m
    assert r.loudness.shape == (m,) and r.specific.shape == (m, 240) and r.t_s.shape == (m,)
    np.testing.assert_allclose(r.t_s, np.arange(m) * 0.002)
    np.testing.assert_allclose(r.z_bark, np.arange(1, 241) / 10)
    assert np.isfinite(r.loudness).all() and (r.loudness >= 0).all() and (r.specific >= 0).all()


def test_empty_input_gives_empty_result():
    r = L.loudness_zwtv(np.zeros(0))
    assert r.loudness.shape == (0,) and r.specific.shape == (0, 240)


def test_chunked_equals_whole(params):
    rng = np.random.default_rng(7)
    x = rng.standard_normal(FS + 1234) * 0.2 * np.repeat(rng.random(30), (FS + 1234) // 30 + 1)[: FS + 1234]
    whole = L.loudness_zwtv(x, params=params)
    state = L.init_state(params=params)
    parts, i = [], 0
    for n in [0, 1, 23, 24, 25, 95, 96, 97, 960, 0, 7777] + [5000] * 20:
        r, state = L.loudness_update(x[i:i + n], state, params=params)
        parts.append(r)
        i += n
        if i >= x.size:
            break
    np.testing.assert_array_equal(np.concatenate([p.loudness for p in parts]), whole.loudness)
    np.testing.assert_array_equal(np.concatenate([p.specific for p in parts]), whole.specific)
    np.testing.assert_array_equal(np.concatenate([p.t_s for p in parts]), whole.t_s)


def test_update_does_not_modify_the_state_passed_in():
    x = tone(500, 70, 0.3)
    state = L.init_state()
    r1, s1 = L.loudness_update(x, state)
    r2, _ = L.loudness_update(x, state)
    np.testing.assert_array_equal(r1.loudness, r2.loudness)
    r3, _ = L.loudness_update(x, s1)
    assert r3.t_s[0] == pytest.approx(r1.t_s[-1] + 0.002)


@pytest.mark.parametrize("bad, count", [(np.nan, 1), (np.inf, 1), (-np.inf, 1)])
def test_non_finite_input_raises_with_count(bad, count):
    x = np.zeros(1000)
    x[10] = bad
    with pytest.raises(ParameterError, match=f"{count} non-finite"):
        L.loudness_zwtv(x)
    x[20:23] = np.nan
    with pytest.raises(ParameterError, match="4 non-finite"):
        L.loudness_update(x, L.init_state())


def test_bad_shapes_and_absurd_pressure_raise():
    with pytest.raises(ParameterError, match="1-D"):
        L.loudness_zwtv(np.zeros((2, 100)))
    with pytest.raises(ParameterError, match="pa_per_unit|calibration"):
        L.loudness_zwtv(np.full(10, 1e12))
    with pytest.raises(ParameterError, match="real numbers"):
        L.loudness_zwtv(np.array(["a"]))


def test_params_are_validated():
    with pytest.raises(ParameterError, match="method"):
        L.LoudnessParams(method="exact")
    with pytest.raises(ParameterError, match="field"):
        L.LoudnessParams(field="near")
    state = L.init_state(params=L.LoudnessParams(method="iso"))
    with pytest.raises(ParameterError, match="state was made"):
        L.loudness_update(np.zeros(10), state, params=L.LoudnessParams(method="fast"))


def test_low_bands_above_120_db_are_clamped():
    levels = np.zeros(28)
    levels[:11] = 130.0
    at_130 = L.loudness_from_levels(levels)
    levels[:11] = 120.0
    at_120 = L.loudness_from_levels(levels)
    assert at_130[0] == at_120[0] > 0
    np.testing.assert_array_equal(at_130[1], at_120[1])
    r = L.loudness_zwtv(tone(60, 140, 0.5))  # 140 dB at 60 Hz: undefined by ISO, clamped here
    assert np.isfinite(r.loudness).all() and r.loudness.max() > 0


def test_loudness_from_levels_validates():
    with pytest.raises(ParameterError, match="shape"):
        L.loudness_from_levels(np.zeros(27))
    with pytest.raises(ParameterError, match="non-finite"):
        L.loudness_from_levels(np.full(28, np.nan))
    with pytest.raises(ParameterError, match="not sound levels"):
        L.loudness_from_levels(np.full(28, 4000.0))
    with pytest.raises(ParameterError, match="field"):
        L.loudness_from_levels(np.zeros(28), field="near")
    with pytest.raises(ParameterError, match="field"):
        L.loudness_stationary(np.zeros(100), field="near")
    n, spec = L.loudness_from_levels(np.full(28, -10.0))
    assert n == 0.0 and not spec.any()


@pytest.mark.parametrize("f_hz, louder", [(10000, True), (2500, False)])
def test_diffuse_field_correction(f_hz, louder):
    # ISO Table A.5: diffuse minus free is +4.3 dB around 10 kHz and -2 dB around 2.5 kHz.
    x = tone(f_hz, 60)
    free = steady(L.loudness_zwtv(x, params=L.LoudnessParams(field="free")))
    diffuse = steady(L.loudness_zwtv(x, params=L.LoudnessParams(field="diffuse")))
    assert (diffuse > free * 1.1) if louder else (diffuse < free * 0.95)


def test_specific_loudness_peaks_at_the_tone():
    r = L.loudness_zwtv(tone(1000, 60))
    pattern = r.specific[r.t_s >= 0.5].mean(axis=0)
    assert 8.0 <= r.z_bark[np.argmax(pattern)] <= 9.2  # 1 kHz ~ 8.5 Bark
    assert L.total_from_specific(pattern) == pytest.approx(steady(r), rel=0.05)


def _test_signals() -> dict[str, np.ndarray]:
    rng = np.random.default_rng(3)
    t = np.arange(2 * FS) / FS
    sweep = ss.chirp(t, 30, t[-1], 15000, method="logarithmic") * 0.2
    bursts = rng.standard_normal(2 * FS) * np.repeat(rng.random(40) ** 3, FS // 20) * 0.5
    pulses = np.where((t % 0.25) < 0.02, np.sin(2 * np.pi * 3000 * t), 0.0) * 0.3
    bass = 2.0 * np.sin(2 * np.pi * 45 * t) + 0.05 * rng.standard_normal(2 * FS)
    return {"sweep": sweep, "bursts": bursts, "pulses": pulses, "bass": bass}


@pytest.mark.parametrize("name", ["sweep", "bursts", "pulses", "bass"])
def test_fast_method_agrees_with_iso(name):
    x = _test_signals()[name]
    ref = L.loudness_zwtv(x, params=L.LoudnessParams(method="iso")).loudness
    fast = L.loudness_zwtv(x, params=L.LoudnessParams(method="fast")).loudness
    # Distance of each ISO sample to the range of the fast values within +-2 ms (the standard's
    # time tolerance), relative to max(N, 0.1 sone).
    pad = np.pad(fast, 1, mode="edge")
    window = np.stack([pad[:-2], pad[1:-1], pad[2:]])
    dist = np.maximum(0.0, np.maximum(window.min(axis=0) - ref, ref - window.max(axis=0)))
    rel = dist / np.maximum(ref, 0.1)
    assert np.median(np.abs(fast - ref) / np.maximum(ref, 0.1)) < 0.01
    assert rel.max() < 0.05


def test_fast_filter_bank_design_is_stable_and_matches_iso_at_band_centres():
    plan = FB.plan("fast")
    sos48, gain48 = FB.iso_sos()
    covered = np.concatenate([g.bands for g in plan.groups])
    assert sorted(covered.tolist()) == list(range(28))
    for group in plan.groups:
        for sos, gain, band in zip(group.sos, group.gain, group.bands):
            poles = ss.sos2zpk(sos)[1]
            assert np.abs(poles).max() < 1.0
            fc = 1000 * 10 ** ((band - 16) / 10)
            h = abs(ss.sosfreqz(sos, worN=[fc], fs=group.rate_hz)[1][0]) * gain
            h_iso = abs(ss.sosfreqz(sos48[band], worN=[fc], fs=FS)[1][0]) * gain48[band]
            assert 20 * np.log10(h / h_iso) == pytest.approx(0.0, abs=0.1)
    for stage in plan.stages:
        assert np.abs(ss.sos2zpk(stage.sos)[1]).max() < 1.0
