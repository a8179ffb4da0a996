"""Properties of the audio features for every input (hypothesis): finite and non-negative,
silence gives exact zeros (never 0/0), non-finite input is a ParameterError naming the count,
more gain never gives less loudness, and chunked processing equals whole processing."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from autohaptics.intensity import features as af
from autohaptics.intensity import booming as B
from autohaptics.intensity import loudness as L
from autohaptics.intensity import sharpness as S
from autohaptics.errors import ParameterError

FS = 48_000
KINDS = ("silence", "dc", "square", "clipped", "noise", "tone", "impulse", "bursts")
SETTINGS = settings(max_examples=30, deadline=None, suppress_health_check=[HealthCheck.too_slow])


@st.composite
def signals(draw, max_len: int = 12_000) -> np.ndarray:
    """Digital full-scale float32 signals: silence, DC, full-scale square, clipped, white noise
    and tones at -120 .. +20 dBFS, single impulses, noise bursts; 1 .. max_len samples."""
    kind = draw(st.sampled_from(KINDS))
    n = draw(st.integers(1, max_len))
    level = 10 ** (draw(st.floats(-120.0, 20.0)) / 20)
    rng = np.random.default_rng(draw(st.integers(0, 2 ** 32 - 1)))
    t = np.arange(n) / FS
    f = draw(st.floats(20.0, 20_000.0))
    if kind == "silence":
        x = np.zeros(n)
    elif kind == "dc":
        x = np.full(n, min(level, 1.0) * draw(st.sampled_from([-1.0, 1.0])))
    elif kind == "square":
        x = np.where(np.sin(2 * np.pi * f * t) >= 0, 1.0, -1.0)
    elif kind == "clipped":
        x = np.clip(10.0 * (np.sin(2 * np.pi * f * t) + rng.standard_normal(n)), -1.0, 1.0)
    elif kind == "noise":
        x = level * rng.standard_normal(n)
    elif kind == "tone":
        x = level * np.sqrt(2) * np.sin(2 * np.pi * f * t)
    elif kind == "impulse":
        x = np.zeros(n)
        x[rng.integers(n)] = min(level, 1.0)
    else:
        env = np.repeat(rng.random(n // 480 + 1) ** 4, 480)[:n]
        x = level * env * rng.standard_normal(n)
    return x.astype(np.float32)


@SETTINGS
@given(x=signals(), method=st.sampled_from(L.LOUDNESS_METHODS), variant=st.sampled_from(B.BOOMING_VARIANTS))
def test_every_output_is_finite_and_non_negative(x, method, variant):
    params = af.AudioFeatureParams(loudness_method=method, booming_variant=variant)
    f = af.compute_audio_features([x], params=params, step_ms=2)
    n_frames = -(-x.size // 960)
    assert f.n_frames == n_frames
    for name in af.FEATURE_NAMES:
        v = getattr(f, name)
        assert v.shape == (n_frames,)
        assert np.isfinite(v).all() and (v >= 0).all(), name
    assert np.isfinite(f.loudness_iso).all() and (f.loudness_iso >= 0).all()
    assert (f.sharpness <= 0.11 * 24 * S.din_weighting(24.0) + 1e-9).all()  # the largest possible moment


@SETTINGS
@given(n=st.integers(1, 20_000), method=st.sampled_from(L.LOUDNESS_METHODS),
       variant=st.sampled_from(B.BOOMING_VARIANTS))
def test_silence_gives_exact_zeros(n, method, variant):
    params = af.AudioFeatureParams(loudness_method=method, booming_variant=variant)
    f = af.compute_audio_features([np.zeros(n, np.float32)], params=params, step_ms=2)
    for name in af.FEATURE_NAMES:
        assert np.all(getattr(f, name) == 0.0), name
    assert np.all(f.loudness_iso == 0.0)


@SETTINGS
@given(x=signals(max_len=4000), data=st.data())
def test_non_finite_samples_raise_a_parameter_error_naming_the_count(x, data):
    k = data.draw(st.integers(1, min(5, x.size)))
    where = data.draw(st.lists(st.integers(0, x.size - 1), min_size=k, max_size=k, unique=True))
    x = x.copy()
    x[where] = data.draw(st.sampled_from([np.nan, np.inf, -np.inf]))
    with pytest.raises(ParameterError, match=f"{k} non-finite"):
        af.compute_audio_features([x])
    with pytest.raises(ParameterError, match=f"{k} non-finite"):
        L.loudness_zwtv(x.astype(np.float64))


@SETTINGS
@given(x=signals(), gain_db=st.floats(0.0, 40.0), method=st.sampled_from(L.LOUDNESS_METHODS))
def test_more_gain_never_gives_less_loudness(x, gain_db, method):
    params = L.LoudnessParams(method=method)
    p = x.astype(np.float64) * 3.5566
    quiet = L.loudness_zwtv(p, params=params).loudness
    loud = L.loudness_zwtv(p * 10 ** (gain_db / 20), params=params).loudness
    assert (loud >= quiet - 1e-9).all()


@SETTINGS
@given(x=signals(max_len=20_000), cuts=st.lists(st.integers(0, 20_000), max_size=6),
       method=st.sampled_from(L.LOUDNESS_METHODS))
def test_chunked_processing_equals_whole_processing(x, cuts, method):
    params = af.AudioFeatureParams(loudness_method=method)
    bounds = sorted({0, x.size, *[c for c in cuts if c <= x.size]})
    chunks = [x[a:b] for a, b in zip(bounds[:-1], bounds[1:])]
    whole = af.compute_audio_features([x], params=params, step_ms=2)
    parts = af.compute_audio_features(chunks, params=params, step_ms=2)
    for name in af.FEATURE_NAMES + ("t_s", "loudness_iso"):
        np.testing.assert_array_equal(getattr(parts, name), getattr(whole, name))


@SETTINGS
@given(spec=st.lists(st.floats(0.0, 1e6, allow_subnormal=True), min_size=240, max_size=240),
       scale=st.floats(0.0, 1.0))
def test_sharpness_and_booming_of_any_pattern_are_finite_and_non_negative(spec, scale):
    pattern = np.array(spec) * scale
    for value in (S.sharpness(specific=pattern), *(B.booming(specific=pattern, params=B.BoomingParams(variant=v))
                                                  for v in B.BOOMING_VARIANTS)):
        assert np.isfinite(value) and value >= 0
