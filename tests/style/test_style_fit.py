"""Known answers for what a style can express and how it is fitted: a floor that clears weak
levels, the threshold scale read off the analysis's own decision curves, per-zone curves that
one-off edits on a few actuators do not drag, version 1 documents; the threshold scales' one-pass
depths against one evaluation of the rule per scale."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from hypothesis import given, settings, strategies as st
from hypothesis.extra import numpy as hnp

from autohaptics import intensity as it, pipeline
from autohaptics.intensity.rule import LEVEL_FEATURES, trigger_depths
from autohaptics.layout import ACTUATORS
from autohaptics.metrics import compare_tracks
from autohaptics.style import KNOTS, Style, from_dict, learn
from autohaptics.style.apply import shape_levels
from autohaptics.style.fit import fit_floor
from autohaptics.testing import scenes, write_scene
from autohaptics.testing.designers import Designer, edit
from autohaptics.timebase import FRAMES_PER_TICK

from shared_data import shared_clip


@pytest.fixture(scope="module")
def films(tmp_path_factory) -> dict[str, pipeline.Analysis]:
    """Analyses of the material scene (24 s), the Sintel trailer clip (52 s) and the BBB opening (30 s)."""
    folder = tmp_path_factory.mktemp("style-fit-films")
    return {"material": pipeline.analyse(write_scene(folder / "material.mp4", scenes.material_scene(),
                                                     width=160, height=90)),
            "sintel": pipeline.analyse(shared_clip("sintel_trailer_480x204_h264_aac.mp4")),
            "bbb": pipeline.analyse(shared_clip("bbb_opening_30s_1280x720_vp8_vorbis.webm"))}


def _vibration_mae(analysis, style, wanted) -> float:
    tl = pipeline.derive(analysis, style=style)
    return compare_tracks(wanted.vibration, tl.vibration, wanted.temperature_c, tl.temperature_c,
                          wanted.fans, tl.fans)["vibration"]["mae"]


def test_a_floor_clears_levels_below_it_and_nothing_else():
    levels = np.array([0.0, 0.1, 0.24, 0.25, 0.6], np.float32)
    np.testing.assert_array_equal(shape_levels(levels, KNOTS, KNOTS, 0.25), np.array([0, 0, 0, 0.25, 0.6], np.float32))
    np.testing.assert_array_equal(shape_levels(levels, KNOTS, KNOTS, 0.0), levels)


def test_a_floor_is_fitted_between_cleared_and_kept_levels_and_scattered_clears_make_none():
    x = np.linspace(0.01, 1.0, 400)
    y = np.where(x < 0.3, 0.0, x)
    y[350:360] = 0.0  # a one-off clear among strong levels
    assert fit_floor(x, y) == pytest.approx(0.3, abs=0.005)
    assert fit_floor(x, x) == 0.0
    assert fit_floor(x, np.where(np.arange(400) % 7 == 3, 0.0, x)) == 0.0


def test_a_designer_who_clears_weak_vibration_is_reproduced_on_another_film(films):
    clears = Designer("clears", "", floor=0.25)
    style = learn([(films["sintel"], edit(clears, films["sintel"], seed=5))])
    assert all(f == pytest.approx(0.25, abs=0.03) for f in style.vibration_floor)
    wanted = edit(clears, films["material"], one_offs=0)
    plain = _vibration_mae(films["material"], None, wanted)
    assert plain > 0.002
    assert _vibration_mae(films["material"], style, wanted) <= 0.3 * plain


def test_a_threshold_taste_is_read_off_the_decision_curves(films):
    for wanted_scale in (0.7, 1.4):
        designer = Designer("events", "", threshold_scale=wanted_scale)
        style = learn([(films["sintel"], edit(designer, films["sintel"], seed=2))])
        assert style.threshold_scale == pytest.approx(wanted_scale, rel=0.15), wanted_scale


def test_per_zone_tastes_survive_one_off_edits_on_a_few_actuators(films):
    gains = tuple({"back": 1.3, "armrests": 1.0, "seat": 0.6}[a.zone] for a in ACTUATORS)
    designer = Designer("zones", "", actuator_gain=gains)
    style = learn([(films["sintel"], edit(designer, films["sintel"], seed=7))])
    for a, gain in enumerate(gains):
        np.testing.assert_allclose(style.vibration[a][:6], np.minimum(1.0, gain * np.asarray(KNOTS[:6])), atol=0.05,
                                   err_msg=ACTUATORS[a].id)


def test_a_version_1_document_still_loads_and_has_no_floors():
    style = from_dict({"format": "autohaptics.style", "version": 1, "threshold_scale": 0.8})
    assert style.threshold_scale == 0.8 and not any(style.vibration_floor) and style.fans_floor == 0.0
    assert Style(vibration_floor=(0.2,) * 9).to_dict()["version"] == 2
    assert not Style(fans_floor=0.1).is_identity


def test_a_drawn_burst_over_ticks_only_low_thresholds_wake_does_not_move_the_threshold_scale(films):
    from autohaptics.params import GenerateParams
    from autohaptics.style.fit import SCALE_GRID, _scale_evidence

    film = films["bbb"]  # few events: a 2 s burst holds most of the ticks a step below 0.7 wakes
    edited = edit(Designer("events", "", threshold_scale=0.7), film, one_offs=0)
    on = _scale_evidence([(film, edited)], GenerateParams(), [np.arange(film.n_ticks)])[0]
    woken_low = on[:, np.argmin(np.abs(SCALE_GRID - 0.45))] & ~on[:, np.argmin(np.abs(SCALE_GRID - 0.69))]
    start = int(np.argmax(np.convolve(woken_low, np.ones(20), "valid")))
    assert woken_low[start:start + 20].sum() >= 5
    edited.vibration[start:start + 20, [1, 2, 6]] = 0.6  # a one-off burst on three actuators for 2 s
    assert learn([(film, edited)]).threshold_scale == pytest.approx(0.7, rel=0.05)


def test_a_zone_whose_levels_all_lie_below_the_floor_takes_the_pooled_floor():
    from autohaptics.style.fit import _zone_floors

    rng = np.random.default_rng(3)
    x = rng.uniform(0.01, 1.0, (600, 9))
    seat = [i for i, a in enumerate(ACTUATORS) if a.zone == "seat"]
    x[:, seat] = rng.uniform(0.01, 0.18, (600, len(seat)))
    floors = _zone_floors(x, np.where(x < 0.25, 0.0, x))
    assert floors == pytest.approx(0.25, abs=0.01)


def test_trigger_depths_bridge_a_pause_that_ends_near_the_films_end():
    """A pause whose far side lies within the bridging reach of the film's end (found by the
    property test below: the one-pass depths read frames past the end as silent)."""
    spikes = np.zeros(40)
    spikes[[25, 35]] = 1.0  # two low-energy hits, a 9-frame pause between, 5 frames before the end
    feats = dict(zip(it.FEATURES, [np.zeros(40), np.zeros(40), spikes, np.ones(40)]))
    params = it.IntensityParams(rule="events", loudness_gate=0.0, smoothing_s=0.3)
    inputs = it.decision_inputs(feats, params=params)
    depth = trigger_depths(*inputs, np.zeros((1, 4)), 8, params=params, value_features=LEVEL_FEATURES)
    one = dataclasses.replace(params, thresholds=dict.fromkeys(it.FEATURES, 0.0))
    on = it.audio_intensity(feats, 8, params=one, inputs=inputs)[0] > 0
    assert on[5:].all() and np.array_equal(on, depth > 0), (on, depth)


@settings(max_examples=60, deadline=None)
@given(st.data(), st.sampled_from(it.RULES), st.sampled_from([0.0, 0.2, 0.5]), st.sampled_from([0.0, 0.04, 0.1, 0.3]))
def test_trigger_depths_give_what_one_evaluation_per_threshold_set_gives(data, rule, gate, smoothing_s):
    """The one-pass depths (a style's threshold scales) against the rule run once per threshold set:
    the tick vibrates with exactly the first ``depth`` sets, pauses bridged as each set bridges them."""
    n = data.draw(st.integers(1, 60))
    feats = {f: data.draw(hnp.arrays(np.float64, n * FRAMES_PER_TICK, elements=st.floats(0, 10) | st.just(0.0)))
             for f in it.FEATURES}
    first = data.draw(st.lists(st.floats(0, 1.2), min_size=4, max_size=4))
    steps = data.draw(hnp.arrays(np.float64, (data.draw(st.integers(1, 12)), 4), elements=st.floats(0, 0.3)))
    thresholds = np.asarray(first) + np.cumsum(steps, axis=0) - steps[0]  # rising down each column
    params = it.IntensityParams(rule=rule, loudness_gate=gate, smoothing_s=smoothing_s)
    inputs = it.decision_inputs(feats, params=params)
    value_features = it.FEATURES if rule == "thesis" else LEVEL_FEATURES
    depth = trigger_depths(*inputs, thresholds, n, params=params, value_features=value_features)
    for k, row in enumerate(thresholds):
        one = dataclasses.replace(params, thresholds=dict(zip(it.FEATURES, row.tolist())))
        on = it.audio_intensity(feats, n, params=one, inputs=inputs)[0] > 0
        assert np.array_equal(on, depth > k), (k, row)
