"""The learned style (issue 32): the document and its checks, the pure shaping functions, learning
from simulated designers with known tastes (synthetic scenes and a shared clip), the identity, and
the derive/generate integration."""

from __future__ import annotations

import dataclasses
import json

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from autohaptics import pipeline
from autohaptics.errors import ParameterError
from autohaptics.params import resolve_params
from autohaptics.style import KNOTS, Style, fit_curve, from_dict, learn, load, save, to_dict
from autohaptics.style.apply import MAX_SCALED_THRESHOLD, shape_levels, shape_temperature
from autohaptics.testing import Scene, Segment, Tone, scenes, write_scene
from autohaptics.testing.designers import DESIGNERS, Designer, edit
from autohaptics.metrics import compare_tracks

from shared_data import shared_clip

TRACKS = ("vibration", "temperature_c", "fans")


@pytest.fixture(scope="module")
def films(tmp_path_factory) -> dict[str, pipeline.Analysis]:
    """Analyses of the material scene (24 s), the sample scene (10 s) and the Sintel trailer clip."""
    folder = tmp_path_factory.mktemp("style-films")
    out = {}
    for name, scene in (("material", scenes.material_scene()), ("sample", scenes.sample_scene())):
        out[name] = pipeline.analyse(write_scene(folder / f"{name}.mp4", scene, width=160, height=90))
    out["sintel"] = pipeline.analyse(shared_clip("sintel_trailer_480x204_h264_aac.mp4"))
    return out


def _close(tl, ref) -> dict:
    r = compare_tracks(ref.vibration, tl.vibration, ref.temperature_c, tl.temperature_c, ref.fans, tl.fans)
    return {"vibration": r["vibration"]["mae"], "temperature": r["temperature"]["mae_c"], "fans": r["fans"]["mae"]}


@pytest.mark.parametrize("preset, mode", [("balanced", "multimodal"), ("thesis", "multimodal"), ("balanced", "audio")])
def test_unedited_films_learn_the_identity_exactly(films, preset, mode):
    params, _ = resolve_params(preset, {"mode": mode})
    pairs = [(a, pipeline.derive(a, params)) for a in films.values()]
    style = learn(pairs, params)
    assert style.is_identity and style.threshold_scale == 1.0
    assert style.vibration == (KNOTS,) * 9 and style.fans == KNOTS
    assert style.apply_params(params) == params
    for analysis, plain in pairs:
        styled = pipeline.derive(analysis, params, style=style)
        for name in TRACKS:
            np.testing.assert_array_equal(getattr(styled, name), getattr(plain, name))


def test_a_known_taste_is_recovered_despite_one_off_edits(films):
    taste = Designer("known", "", gain=1.5, fan_gain=0.6, temp_offset_c=1.5, temp_scale=0.8)
    style = learn([(films["sintel"], edit(taste, films["sintel"], seed=3, one_offs=3))])
    knot = KNOTS.index(0.2)
    assert style.threshold_scale == 1.0
    assert all(abs(curve[knot] - 0.3) <= 0.03 for curve in style.vibration)
    assert style.fans[KNOTS.index(0.5)] == pytest.approx(0.3, abs=0.03)
    assert style.temperature_offset_c == pytest.approx(1.5, abs=0.1)
    assert style.temperature_scale == pytest.approx(0.8, abs=0.05)


def test_a_taste_for_more_events_lowers_the_thresholds(films):
    busy = Designer("busy", "", threshold_scale=0.7)
    style = learn([(films["sintel"], edit(busy, films["sintel"], seed=1, one_offs=2))])
    assert style.threshold_scale < 1.0
    plain = pipeline.derive(films["sintel"])
    styled = pipeline.derive(films["sintel"], style=style)
    assert (styled.vibration.max(axis=1) > 0).sum() > (plain.vibration.max(axis=1) > 0).sum()


@pytest.mark.parametrize("designer", DESIGNERS, ids=[d.name for d in DESIGNERS])
def test_a_style_learned_on_one_film_brings_another_closer_to_the_designer(films, designer):
    style = learn([(films["sintel"], edit(designer, films["sintel"], seed=7))], name=designer.name)
    target = films["material"]
    wanted = edit(designer, target, one_offs=0)
    plain = _close(pipeline.derive(target), wanted)
    styled = _close(pipeline.derive(target, style=style), wanted)
    for track in ("vibration", "temperature", "fans"):
        assert styled[track] <= plain[track] + 0.002, (track, plain, styled)
    assert sum(styled.values()) < 0.6 * sum(plain.values()), (plain, styled)


def test_the_style_is_recorded_and_generate_takes_it(films, tmp_path):
    style = Style(name="warm", temperature_offset_c=1.0)
    tl = pipeline.derive(films["sample"], style=style)
    assert tl.generator["style"] == to_dict(style)
    scene = Scene(duration_s=1.0, background=(Segment(0.0, 1.0, (150, 60, 40)),),
                  audio=(Tone(0.2, 0.8, 60.0, level_dbfs=-14.0),))
    path = write_scene(tmp_path / "s.mp4", scene, width=64, height=36, fps=5, quality="low", sample_rate=24000)
    made = pipeline.generate(path, style=style)
    assert made.generator["style"]["temperature"]["offset_c"] == 1.0


def test_learning_refuses_pairs_that_do_not_belong_together(films):
    with pytest.raises(ParameterError, match="at least one"):
        learn([])
    with pytest.raises(ParameterError, match="ticks"):
        learn([(films["material"], pipeline.derive(films["sample"]))])
    other = pipeline.derive(films["sample"])
    other.source["sha256"] = "0" * 64
    with pytest.raises(ParameterError, match="another film"):
        learn([(films["sample"], other)])


def test_the_document_round_trips(tmp_path):
    style = Style(name="x", threshold_scale=0.8, overrides={"airflow.near_share": 0.1},
                  vibration=tuple(tuple(min(1.0, 1.2 * k) for k in KNOTS) for _ in range(9)),
                  fans=tuple(0.5 * k for k in KNOTS), temperature_scale=0.9, temperature_offset_c=-1.0,
                  vibration_floor=(0.25,) * 7 + (0.1, 0.1), fans_floor=0.15, learned={"films": 2})
    assert from_dict(json.loads(json.dumps(to_dict(style)))) == style
    assert load(save(style, tmp_path / "x.style.json")) == style
    assert from_dict({"format": "autohaptics.style", "version": 1}).is_identity


def _doc(**changes) -> dict:
    doc = to_dict(Style())
    doc.update(changes)
    return doc


@pytest.mark.parametrize("doc, words", [
    ([], "JSON object"),
    (_doc(format="autohaptics.timeline"), "not a style document"),
    (_doc(version=3), "not a style document"),
    (_doc(version=True), "not a style document"),
    (_doc(version=1), "floors needs version 2"),
    (_doc(floors={"A10": 0.1}), "floors must be an object"),
    (_doc(floors={"fans": 1.5}), "floors.fans must lie in"),
    (_doc(colour=1), "unknown field 'colour'"),
    (_doc(threshold_scale=9.0), "threshold_scale must lie in"),
    (_doc(threshold_scale=float("nan")), "threshold_scale must be a finite number"),
    (_doc(threshold_scale=True), "threshold_scale must be a finite number"),
    (_doc(knots=[0.0, 0.5, 0.4, 1.0]), "knots must rise"),
    (_doc(knots=[0.1, 1.0]), "knots must rise"),
    (_doc(fans=[0.0, 0.5]), "fans must be a list of 12"),
    (_doc(fans=[0.1, *KNOTS[1:]]), "fans must start at 0"),
    (_doc(fans=[0.0, 0.5, *KNOTS[2:]]), "fans must never decrease"),
    (_doc(fans=[0.0, *KNOTS[1:-1], 1.5]), "fans must lie in"),
    (_doc(vibration={"A10": list(KNOTS)}), "vibration must be an object"),
    (_doc(temperature={"scale": 1.0, "gain": 2}), "temperature must be an object"),
    (_doc(temperature={"offset_c": 40}), "temperature.offset_c must lie in"),
    (_doc(overrides={"video.stride": 3}), "needs the film analysed again"),
    (_doc(overrides={"thermal": {}}), "group of parameters"),
    (_doc(overrides={"no.such": 1}), "unknown parameter"),
    (_doc(overrides={"intensity.thresholds.loudness": "loud"}), "expects a number"),
])
def test_a_malformed_document_names_its_field(doc, words):
    with pytest.raises(ParameterError, match=words.replace("(", r"\(")):
        from_dict(doc)


def test_a_style_file_that_is_not_json_is_refused_with_its_path(tmp_path):
    path = tmp_path / "bad.json"
    path.write_text("{not json")
    with pytest.raises(ParameterError, match="bad.json: not a style file"):
        load(path)
    with pytest.raises(ParameterError, match="cannot read"):
        load(tmp_path / "missing.json")


def test_threshold_scaling_keeps_features_switched_off_and_below_one():
    params, _ = resolve_params("balanced", thresholds={"sharpness": 1.0, "loudness": 0.9})
    th = Style(threshold_scale=2.0).apply_params(params).intensity.thresholds
    assert th["sharpness"] == 1.0 and th["loudness"] == MAX_SCALED_THRESHOLD
    assert th["booming"] == pytest.approx(2 * params.intensity.thresholds["booming"]) or th["booming"] == MAX_SCALED_THRESHOLD
    low = Style(threshold_scale=0.5).apply_params(params).intensity.thresholds
    assert low["loudness"] == pytest.approx(0.45) and low["sharpness"] == 1.0


_levels = st.lists(st.floats(0.0, 1.0), min_size=1, max_size=64).map(lambda v: np.asarray(v, np.float32))
_curves = st.lists(st.floats(0.0, 1.0), min_size=len(KNOTS) - 1, max_size=len(KNOTS) - 1).map(
    lambda v: (0.0, *np.maximum.accumulate(np.asarray(v)).tolist()))


@settings(max_examples=60, deadline=None)
@given(levels=_levels, curve=_curves)
def test_a_tone_curve_keeps_levels_in_range_off_stays_off_and_order_is_kept(levels, curve):
    out = shape_levels(levels, KNOTS, curve)
    assert out.dtype == levels.dtype and np.all((out >= 0) & (out <= 1))
    assert np.all(out[levels == 0] == 0)
    order = np.argsort(levels, kind="stable")
    assert np.all(np.diff(out[order].astype(np.float64)) >= -1e-6)
    np.testing.assert_array_equal(shape_levels(levels, KNOTS, KNOTS), levels)


@settings(max_examples=40, deadline=None)
@given(gain=st.floats(0.2, 3.0), gamma=st.floats(0.5, 2.0), seed=st.integers(0, 2**31 - 1))
def test_a_fitted_curve_is_a_valid_curve_close_to_the_taste(gain, gamma, seed):
    x = np.random.default_rng(seed).uniform(0.0, 1.0, 3000)
    y = np.clip(gain * x ** gamma, 0.0, 1.0)
    curve = fit_curve(x, y)
    Style(fans=curve)  # passes the document's checks
    # The curve, applied, reproduces the taste; at a knot a straight-line piece may miss a steep bend
    # (gain 2.75, gamma 0.5 saturates between the knots 0.1 and 0.2) by a little more.
    assert np.mean(np.abs(shape_levels(x.astype(np.float32), KNOTS, curve) - y)) <= 0.02
    np.testing.assert_allclose(curve, np.clip(gain * np.asarray(KNOTS) ** gamma, 0.0, 1.0), atol=0.08)
    assert fit_curve(x, x) == KNOTS


@settings(max_examples=40, deadline=None)
@given(t=st.lists(st.floats(30.0, 55.0), min_size=1, max_size=32), scale=st.floats(0.0, 4.0),
       offset=st.floats(-20.0, 20.0))
def test_shaped_temperatures_stay_in_the_device_range(t, scale, offset):
    temps = np.asarray(t, np.float32)
    out = shape_temperature(temps, scale=scale, offset_c=offset, neutral_c=33.0, range_c=(30.0, 55.0))
    assert np.all((out >= 30.0) & (out <= 55.0))
    np.testing.assert_array_equal(shape_temperature(temps, scale=1.0, offset_c=0.0, neutral_c=33.0,
                                                    range_c=(30.0, 55.0)), temps)


def test_style_is_frozen_and_checked_on_construction():
    with pytest.raises(ParameterError, match="threshold_scale"):
        Style(threshold_scale=0.0)
    with pytest.raises(dataclasses.FrozenInstanceError):
        Style().name = "x"  # type: ignore[misc]
