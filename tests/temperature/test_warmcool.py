"""The default colour -> temperature mapping (warm-cool around a skin-neutral temperature, in the
device's range), the curve a chair plays, and the exports that carry it."""

from __future__ import annotations

import io

import hypothesis.extra.numpy as hnp
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from autohaptics import temperature as thermal
from autohaptics.bench.export import synthetic_timeline
from autohaptics.chair.messages import Hello
from autohaptics.errors import ParameterError
from autohaptics.formats import export_timeline
from autohaptics.formats.importing import parse_timeline

DEFAULT = thermal.ThermalParams()
STEP = DEFAULT.device_rate_c_per_s * 0.1  # most the chair's curve moves per 100 ms tick


def test_cielab_of_srgb_primaries_matches_the_published_values():
    # sRGB red, green, blue, white in CIELAB (D65), e.g. Lindbloom's calculator
    lab = thermal.cielab(np.array([[255.0, 0, 0], [0, 255, 0], [0, 0, 255], [255, 255, 255]]))
    np.testing.assert_allclose(lab, [[53.2408, 80.0925, 67.2032], [87.7347, -86.1827, 83.1793],
                                     [32.2970, 79.1875, -107.8602], [100.0, 0.0, 0.0]], atol=0.01)


def test_warmth_is_ou_et_al_with_a_hue_offset():
    red = np.array([255.0, 0, 0])
    c, h = np.hypot(80.0925, 67.2032), np.arctan2(67.2032, 80.0925)
    ou = 0.02 * c ** 1.07 * np.cos(h - np.deg2rad(50))  # WC + 0.5 (Ou, Luo, Woodcock, Wright 2004)
    assert float(thermal.warmth(red, hue_offset=0.0)) == pytest.approx(ou, rel=1e-4)
    assert float(thermal.warmth(red)) == pytest.approx(0.02 * c ** 1.07 * (np.cos(h - np.deg2rad(50)) - 0.25), rel=1e-4)
    greys = np.array([[g, g, g] for g in (0.0, 1.0, 64.0, 128.0, 200.0, 255.0)])
    np.testing.assert_allclose(thermal.warmth(greys), 0.0, atol=1e-6)


def test_warm_hues_are_warm_and_cool_hues_cool():
    names = ["red", "orange", "yellow", "fire", "grey", "snow", "night", "green", "cyan", "blue"]
    rgb = np.array([[255, 0, 0], [255, 140, 0], [250, 220, 40], [200, 90, 20], [128, 128, 128],
                    [215, 228, 245], [20, 30, 60], [30, 200, 40], [0, 220, 230], [20, 40, 230]], float)
    w = dict(zip(names, thermal.warmth(rgb)))
    assert min(w["red"], w["orange"], w["yellow"], w["fire"]) > 0.5
    assert max(w["snow"], w["night"], w["green"], w["cyan"], w["blue"]) < -0.1
    assert w["grey"] == pytest.approx(0.0, abs=1e-9)


def test_warmcool_target_by_hand():
    w = np.array([0.0, 1.0, 2.0, -1.0, -0.25, np.nan])
    t, stats = thermal.warmcool_target(w, neutral_c=33.0, min_c=18.0, max_c=40.0, fill=0.85, quantile=1.0,
                                       min_scale=0.5)
    assert stats == {"warm_scale": 2.0, "cool_scale": 1.0}
    g = np.arctanh(0.85)
    np.testing.assert_allclose(t, [33.0, 33 + 7 * np.tanh(g / 2), 33 + 7 * 0.85, 33 - 15 * 0.85,
                                   33 - 15 * np.tanh(g / 4), 33.0])
    # a pale film: its scale is min_scale, so its tint stays near neutral
    t, stats = thermal.warmcool_target(np.full(5, 0.02), neutral_c=33.0, min_c=18.0, max_c=40.0, fill=0.85,
                                       quantile=0.95, min_scale=0.5)
    assert stats["warm_scale"] == 0.5 and np.all(t - 33.0 < 0.5)


def test_played_curve_clamps_and_slews_from_neutral():
    out = thermal.played_curve(np.array([50.0, 50, 50, 10, 10]),
                               thermal.DeviceProfile(30.0, 34.0, 33.0, temp_rate_c_per_s=5.0))
    np.testing.assert_allclose(out, [33.5, 34.0, 34.0, 33.5, 33.0])
    once = thermal.played_curve(np.random.default_rng(0).uniform(10, 60, 500))
    again = thermal.played_curve(np.round(once, 4).astype(np.float32))
    np.testing.assert_allclose(again, np.round(once, 4).astype(np.float32), rtol=0, atol=0)  # idempotent


def test_device_profile_comes_from_the_hello_and_from_the_timeline():
    p = thermal.DeviceProfile.from_hello(Hello(temp_min_cc=2500, temp_max_cc=3600, temp_neutral_cc=3200,
                                               temp_rate_cc_per_s=50))
    assert (p.temp_min_c, p.temp_max_c, p.temp_neutral_c, p.temp_rate_c_per_s) == (25.0, 36.0, 32.0, 0.5)
    assert thermal.profile_of({}) == thermal.DeviceProfile()
    assert thermal.profile_of({"thermal": {"device_max_c": 38.0}}).temp_max_c == 38.0
    with pytest.raises(ParameterError, match="not numbers"):
        thermal.profile_of({"thermal": {"device_max_c": "hot"}})
    with pytest.raises(ParameterError, match="rate"):
        thermal.DeviceProfile(temp_rate_c_per_s=0.0)


@pytest.mark.parametrize("kwargs, match", [
    ({"mapping": "ou"}, "mapping"),
    ({"neutral_c": 45.0}, "neutral_c"),
    ({"device_min_c": 41.0}, "device_min_c"),
    ({"fill": 1.0}, "fill"),
    ({"min_scale": 0.0}, "min_scale"),
    ({"hue_offset": float("nan")}, "finite"),
    ({"device_rate_c_per_s": -1.0}, "device_rate"),
])
def test_params_are_checked(kwargs, match):
    with pytest.raises(ParameterError, match=match):
        thermal.ThermalParams(**kwargs)


any_float = st.floats(allow_nan=True, allow_infinity=True, width=64)
colours = hnp.arrays(np.float64, st.tuples(st.integers(1, 60), st.just(3)), elements=any_float)
profiles = st.builds(
    lambda lo, span, at, rate, fill, q, scale, offset: thermal.ThermalParams(
        device_min_c=lo, device_max_c=lo + span, neutral_c=lo + at * span, device_rate_c_per_s=rate, fill=fill,
        quantile=q, min_scale=scale, hue_offset=offset),
    st.floats(-20.0, 30.0), st.floats(1.0, 50.0), st.floats(0.0, 1.0), st.floats(0.01, 100.0),
    st.floats(0.01, 0.99), st.floats(0.5, 1.0), st.floats(1e-3, 5.0), st.floats(-0.99, 0.99))


@settings(max_examples=150, deadline=None)
@given(rgb=colours, params=profiles)
def test_the_chairs_curve_is_finite_in_range_and_slew_limited_for_any_frame_colours(rgb, params):
    curve, target, stats = thermal.temperature_track(rgb, params=params)
    lo, hi = params.range_c
    assert curve.shape == target.shape == (rgb.shape[0],)
    assert np.isfinite(curve).all() and np.isfinite(target).all()
    assert (curve >= lo).all() and (curve <= hi).all() and (target >= lo).all() and (target <= hi).all()
    steps = np.abs(np.diff(np.concatenate([[params.neutral_c], curve])))
    assert (steps <= params.device_rate_c_per_s * 0.1 + thermal.device.CURVE_SLACK_C + 1e-9).all()
    np.testing.assert_array_equal(thermal.played_curve(curve, params.device), curve)


def test_exports_carry_the_curve_the_chair_plays():
    """A timeline whose curve the chair cannot play (the thesis's 42.5 C, a jump) is exported as
    the chair plays it; a default timeline's curve is exported as it is."""
    tl = synthetic_timeline(400, seed=5)
    own = tl.temperature_c.copy()
    back = parse_timeline(_csv(tl))
    np.testing.assert_allclose(back.temperature_c, own, atol=5e-5)  # already what the chair plays
    tl.temperature_c[:200], tl.temperature_c[200:] = 42.5, 31.0
    played = thermal.played_curve(tl.temperature_c)
    for text in (_csv(tl), _export(tl, "json")):
        back = parse_timeline(text)
        np.testing.assert_allclose(back.temperature_c, played, atol=5e-5)
        assert back.temperature_c.max() <= 40.0 and np.abs(np.diff(back.temperature_c)).max() <= STEP + 1e-4


def _csv(tl) -> bytes:
    return _export(tl, "csv")


def _export(tl, fmt: str) -> bytes:
    buf = io.BytesIO()
    export_timeline(tl, fmt, buf)
    return buf.getvalue()
