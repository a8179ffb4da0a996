"""Incremental refinement on generated films with known answers: after lowering the thresholds,
refining the cache gives the timeline a fresh generate at those thresholds gives, and computes
saliency only for the ticks that newly vibrate.

The analysis computes saliency up front for every tick the threshold sliders could wake (all four
at 0), so what a derive can lack is what a lowered loudness GATE wakes: the coarse analysis here is
made with a gate that only the boom passes.

The film (64 x 36, written at several frame rates): a loud 50 Hz boom at 3-4 s while a bright disc
sits on the LEFT, a quiet 60 Hz hum at 9-11 s while a bright square sits on the RIGHT. At high
thresholds only the boom vibrates; at low ones the hum wakes too, and must go to the right. That
holds for the thesis's intensity rule (features against the film's maximum), which these tests pin:
under the "events" rule both sounds are events at any threshold. The refinement itself reads only
which ticks vibrate after the derive, whatever the rule.
"""

from __future__ import annotations

import numpy as np
import pytest

from autohaptics import pipeline
from autohaptics import testing as synth
from autohaptics.layout import ACTUATOR_IDS
from autohaptics.params import params_from_doc, resolve_doc

IDX = {a: i for i, a in enumerate(ACTUATOR_IDS)}
RIGHT = [IDX[a] for a in ("A2", "A6", "A7", "A9")]
HIGH = {"sharpness": 0.95, "booming": 0.95, "low_energy": 0.95, "loudness": 0.95}
LOW = {"sharpness": 0.3, "booming": 0.3, "low_energy": 0.3, "loudness": 0.3}
HUM = range(91, 109)  # ticks well inside the hum (9-11 s)

SCENE = synth.left_boom_right_hum_scene()


GATE_HIGH = 0.6  # the boom passes it, the hum does not


def params(thresholds: dict, preset: str = "balanced", gate: float | None = None):
    overrides = {"intensity.rule": "thesis"} | ({} if gate is None else {"intensity.loudness_gate": gate})
    doc, _ = resolve_doc({"preset": preset, "mode": "multimodal", "thresholds": {}, "overrides": overrides},
                         thresholds=thresholds)
    return params_from_doc(doc)[0]


@pytest.mark.parametrize("fps, preset", [(5, "balanced"), (24, "balanced"), (30, "fast")])
def test_refined_timeline_equals_a_fresh_generate(tmp_path, fps, preset):
    path = synth.write_scene(tmp_path / f"film{fps}.mp4", SCENE, width=64, height=36, fps=fps)
    coarse = pipeline.analyse(path, params(HIGH, preset, gate=GATE_HIGH))
    estimated = pipeline.derive(coarse, params(LOW, preset))
    wanted = estimated.features["intensity"] > 0
    assert estimated.stats.get("needs_analysis") and wanted[HUM].all()
    assert not coarse.video.saliency_mask[HUM].any()

    refined = pipeline.refine(path, coarse, params(LOW, preset), wanted)
    assert refined.video is not coarse.video and not coarse.video.saliency_mask[HUM].any()  # a new cache
    tl = pipeline.derive(refined, params(LOW, preset))
    assert not tl.stats.get("needs_analysis") and tl.stats["fusion"]["ticks_estimated"] == 0
    fresh_analysis = pipeline.analyse(path, params(LOW, preset))
    fresh = pipeline.derive(fresh_analysis, params(LOW, preset))
    for track in ("vibration", "temperature_c", "fans"):
        np.testing.assert_array_equal(getattr(tl, track), getattr(fresh, track), err_msg=track)
    # the same weights wherever both computed them (the fresh analysis also covers ticks only a
    # lower threshold could wake)
    both = refined.video.saliency_mask & fresh_analysis.video.saliency_mask
    assert not (refined.video.saliency_mask & ~fresh_analysis.video.saliency_mask).any() and both[HUM].all()
    np.testing.assert_array_equal(refined.video.beta[both], fresh_analysis.video.beta[both])

    # Only the newly vibrating ticks' frames were analysed: the hum's (its frames and no other).
    done = refined.stats["refine"]
    lacking = wanted & ~coarse.video.saliency_mask
    gained = refined.video.saliency_mask & ~coarse.video.saliency_mask
    assert done["runs"] == 1 and done["ticks"] == int(gained.sum()) and (gained | ~lacking).all()
    sources = pipeline.frame_sources(coarse.video.frame_mask)  # the frame each tick holds
    assert 0 < done["frames"] <= lacking.sum() and set(sources[gained]) <= set(sources[lacking])
    # The known answer: the hum goes to the right, where the square is.
    vib = tl.vibration[list(HUM)]
    assert (vib[:, RIGHT].max(axis=1) == vib.max(axis=1)).all(), vib.round(2)
    # Nothing is left to do: a second refinement returns the cache as it is.
    assert pipeline.refine(path, refined, params(LOW, preset), wanted) is refined


def test_a_lowered_threshold_finds_its_weights_in_the_cache(tmp_path):
    """Saliency up front: analysed at high thresholds, the film derives at any lower ones with
    weights of its own for every tick that vibrates, and they are those a fresh analysis gives."""
    path = synth.write_scene(tmp_path / "film.mp4", SCENE, width=64, height=36, fps=5)
    analysis = pipeline.analyse(path, params(HIGH))
    for low in (LOW, {name: 0.0 for name in LOW}):
        tl = pipeline.derive(analysis, params(low))
        assert not tl.stats.get("needs_analysis") and tl.stats["fusion"]["ticks_estimated"] == 0
        assert (tl.vibration[list(HUM)].max(axis=1) > 0).all()
    fresh = pipeline.derive(pipeline.analyse(path, params(LOW)), params(LOW))
    np.testing.assert_array_equal(pipeline.derive(analysis, params(LOW)).vibration, fresh.vibration)


def test_raising_the_thresholds_leaves_nothing_to_refine(tmp_path):
    path = synth.write_scene(tmp_path / "film.mp4", SCENE, width=64, height=36, fps=5)
    analysis = pipeline.analyse(path, params(LOW))
    tl = pipeline.derive(analysis, params(HIGH))
    assert (tl.vibration.max(axis=1) > 0).any() and not tl.stats.get("needs_analysis")
    assert not pipeline.lacking_saliency(analysis.video, tl.features["intensity"] > 0).any()


def test_a_rederive_that_keeps_the_picture_rules_gives_the_tracks_a_fresh_derive_gives(tmp_path):
    """The picture's tracks (fans, temperature, motion curves) are kept from an earlier derive of
    the same cache when only the thresholds changed, and computed again when their rule changed:
    either way as a fresh derive has them."""
    import copy
    import dataclasses

    path = synth.write_scene(tmp_path / "film.mp4", synth.sample_scene(8.0), width=96, height=54, fps=12)
    analysis = pipeline.analyse(path, params(HIGH))
    first = pipeline.derive(analysis, params(HIGH))
    assert first.fans.max() > 0  # the scene's moving shapes blow
    again = pipeline.derive(analysis, params(LOW))  # kept from the first derive: shared, read-only
    assert first.fans.flags.writeable and not again.fans.flags.writeable
    other = dataclasses.replace(analysis, video=copy.deepcopy(analysis.video),
                                audio=copy.deepcopy(analysis.audio))  # a cache never derived
    fresh = pipeline.derive(other, params(LOW))
    assert not again.temperature_c.flags.writeable and np.ptp(fresh.temperature_c) > 0
    for track in ("fans", "temperature_c", "vibration"):
        np.testing.assert_array_equal(getattr(again, track), getattr(fresh, track), err_msg=track)
    assert list(again.features) == list(fresh.features)
    for name, values in fresh.features.items():
        np.testing.assert_array_equal(again.features[name], values, err_msg=name)
    assert again.stats["airflow"] == first.stats["airflow"] and again.stats["temperature"] == fresh.stats["temperature"]
    for rule in ("events", "thesis"):  # the intensity rule's curves kept across thresholds and densities
        for density in (None, 0.2):
            intensity = dataclasses.replace(params(HIGH).intensity, rule=rule, density=density)
            pipeline.derive(analysis, dataclasses.replace(params(HIGH), intensity=intensity))
            lower = dataclasses.replace(params(LOW), intensity=dataclasses.replace(intensity, thresholds=LOW))
            kept, new = pipeline.derive(analysis, lower), pipeline.derive(copy.deepcopy(other), lower)
            np.testing.assert_array_equal(kept.vibration, new.vibration, err_msg=f"{rule} {density}")
            np.testing.assert_array_equal(kept.features["intensity"], new.features["intensity"])
    warmer = dataclasses.replace(params(LOW), thermal=dataclasses.replace(params(LOW).thermal, neutral_c=35.0))
    np.testing.assert_array_equal(pipeline.derive(analysis, warmer).temperature_c,
                                  pipeline.derive(other, warmer).temperature_c)
    assert not np.array_equal(pipeline.derive(analysis, warmer).temperature_c, again.temperature_c)
    stricter = dataclasses.replace(params(LOW), airflow=dataclasses.replace(params(LOW).airflow, strong_rel=0.9))
    changed = pipeline.derive(analysis, stricter)  # another fan rule: computed again
    np.testing.assert_array_equal(changed.fans, pipeline.derive(other, stricter).fans)
    assert not np.array_equal(changed.fans, again.fans)
