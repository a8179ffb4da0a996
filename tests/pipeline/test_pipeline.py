"""The pipeline's composition: modes, tracks, skipping, the feature cache, missing streams."""

import copy
import json

import numpy as np
import pytest

from autohaptics import testing as synth
from autohaptics.errors import MediaError, ParameterError
from autohaptics.layout import ACTUATOR_IDS
from autohaptics.params import THESIS_RULES, GenerateParams, resolve_params
from autohaptics.pipeline import Analysis, analyse, derive, generate
from autohaptics.pipeline import reusable as analysis_compatible
from autohaptics.records import apply_overrides

A5 = ACTUATOR_IDS.index("A5")


@pytest.fixture(scope="module")
def clips(tmp_path_factory):
    d = tmp_path_factory.mktemp("pipeline")
    scene = synth.sample_scene()
    return {
        "av": synth.write_scene(d / "av.mp4", scene, width=320, height=180, fps=24),
        "audio_only": synth.write_scene(d / "audio.wav", scene),
        "video_only": synth.write_scene(d / "video.mp4", scene, width=320, height=180, fps=24, audio=False),
    }


@pytest.fixture(scope="module")
def av_analysis(clips):
    return analyse(clips["av"], GenerateParams())


def test_multimodal_spreads_the_audio_intensity_over_the_salient_area(av_analysis):
    tl = derive(av_analysis, GenerateParams())
    intensity = tl.features["intensity"]
    peak = tl.vibration.max(axis=1)
    np.testing.assert_allclose(peak, intensity, atol=1e-4)  # beta peaks at 1 where it vibrates
    assert tl.stats["fusion"]["ticks_estimated"] == 0
    assert (tl.stats["video"]["saliency"]["ticks_computed"] == int((intensity > 0).sum()))


def test_every_mode_produces_all_tracks_in_range(av_analysis):
    for mode in ("multimodal", "audio", "visual", "random"):
        tl = derive(av_analysis, GenerateParams(mode=mode))
        assert tl.vibration.shape == (100, 9) and tl.fans.shape == (100, 9, 17)
        assert np.isfinite(tl.vibration).all() and tl.vibration.min() >= 0 and tl.vibration.max() <= 1
        assert tl.generator["mode"] == mode
    audio = derive(av_analysis, GenerateParams(mode="audio"))
    on = np.flatnonzero(audio.vibration.max(axis=0) > 0)
    assert set(on) <= {ACTUATOR_IDS.index(a) for a in ("A1", "A2", "A5")}


def test_visual_mode_needs_saliency_on_every_tick(clips):
    a = analyse(clips["av"], GenerateParams(mode="visual"))
    assert a.video.saliency_mask.all()
    tl = derive(a, GenerateParams(mode="visual"))
    assert (tl.vibration.max(axis=1) > 0).sum() > 50  # the textured scenes always have a salient area


def test_random_mode_is_seeded(av_analysis):
    a = derive(av_analysis, GenerateParams(mode="random", seed=3)).vibration
    b = derive(av_analysis, GenerateParams(mode="random", seed=3)).vibration
    c = derive(av_analysis, GenerateParams(mode="random", seed=4)).vibration
    np.testing.assert_array_equal(a, b)
    assert not np.array_equal(a, c)
    assert (a.max(axis=1) > 0).any()


def test_lower_thresholds_borrow_saliency_and_ask_for_a_new_analysis(av_analysis):
    # the thesis's vibration rule: with it, thresholds this low wake ticks without saliency
    rule = {key: value for key, value in THESIS_RULES.items() if key.startswith("intensity.")}
    params, _ = resolve_params(overrides=rule,
                               thresholds={"loudness": 0.05, "sharpness": 0.05, "booming": 0.05, "low_energy": 0.05})
    assert analysis_compatible(av_analysis, params)  # thresholds are derive-time
    for key, value in (("airflow.cell_rel", 0.3), ("airflow.cell_sigma_ticks", 0.0), ("airflow.threshold", 0.1)):
        assert analysis_compatible(av_analysis, resolve_params(overrides={key: value})[0]), key  # the fan rule too
    for key, value in (("airflow.static_level", 30.0), ("airflow.fade_min_step", 5.0), ("airflow.floor", 0.05)):
        assert not analysis_compatible(av_analysis, resolve_params(overrides={key: value})[0]), key  # the video pass reads these
    tl = derive(av_analysis, params)
    assert tl.stats["fusion"]["ticks_estimated"] > 0
    assert tl.stats["needs_analysis"] is True
    np.testing.assert_allclose(tl.vibration.max(axis=1), tl.features["intensity"], atol=1e-4)


def test_analysis_parameters_change_compatibility(av_analysis):
    params = apply_overrides(GenerateParams(), {"flow.method": "farneback"})
    assert not analysis_compatible(av_analysis, params)


def test_an_analysis_from_before_a_field_existed_serves_what_it_was_analysed_with(av_analysis):
    """A cache written before an analysis-time field was added lacks it: it was analysed as the
    field's default does, or where the default analyses otherwise, as ``ABSENT_AS`` says; it serves
    that value and not another."""
    old = copy.deepcopy(av_analysis)
    del old.params["video"]["decode"]
    assert analysis_compatible(old, GenerateParams())
    assert not analysis_compatible(old, apply_overrides(GenerateParams(), {"video.decode": "full"}))
    del old.params["flow"]["min_span_frames"], old.params["flow"]["cadence_ratio"]
    before = {"flow.min_span_frames": 0.0, "flow.cadence_ratio": 0.0}
    assert analysis_compatible(old, apply_overrides(GenerateParams(), before))
    assert not analysis_compatible(old, GenerateParams())  # pairs two frames apart, timed by the cadence
    del old.params["depth"]["expansion_grain"]
    before["depth.expansion_grain"] = 0.0
    assert analysis_compatible(old, apply_overrides(GenerateParams(), before))
    assert not analysis_compatible(old, apply_overrides(GenerateParams(), {**before, "depth.expansion_grain": 0.015}))
    del old.params["cuts"]["in_one_step"]
    before["cuts.in_one_step"] = False
    assert analysis_compatible(old, apply_overrides(GenerateParams(), before))
    assert not analysis_compatible(old, apply_overrides(GenerateParams(), {**before, "cuts.in_one_step": True}))


def test_an_analysis_of_another_revision_is_analysed_again(av_analysis, tmp_path):
    """A cache written before the analysis changed a rule without a parameter (no revision in its
    header: 0) never serves, whatever its parameters; one of this revision does, after a round trip."""
    av_analysis.save(tmp_path / "a.npz")
    assert analysis_compatible(Analysis.load(tmp_path / "a.npz"), GenerateParams())
    with np.load(tmp_path / "a.npz") as z:
        arrays = {k: z[k] for k in z.files}
    header = json.loads(bytes(arrays["header"]).decode())
    del header["revision"]
    arrays["header"] = np.frombuffer(json.dumps(header).encode(), dtype=np.uint8)
    np.savez(tmp_path / "old.npz", **arrays)
    old = Analysis.load(tmp_path / "old.npz")
    assert old.revision == 0 and old.params == av_analysis.params
    assert not analysis_compatible(old, GenerateParams())


def test_feature_cache_round_trip_gives_the_same_timeline(av_analysis, tmp_path):
    av_analysis.save(tmp_path / "a.npz")
    back = Analysis.load(tmp_path / "a.npz")
    t1, t2 = derive(av_analysis, GenerateParams()), derive(back, GenerateParams())
    np.testing.assert_array_equal(t1.vibration, t2.vibration)
    np.testing.assert_array_equal(t1.temperature_c, t2.temperature_c)
    np.testing.assert_array_equal(t1.fans, t2.fans)


def test_audio_only_file_vibrates_on_a5_and_keeps_neutral_picture_tracks(clips):
    tl = generate(clips["audio_only"])
    assert tl.source["video"] is None
    on = tl.vibration.max(axis=0) > 0
    assert on[A5] and on.sum() == 1
    np.testing.assert_allclose(tl.temperature_c, 33.0)
    assert not tl.fans.any()
    with pytest.raises(MediaError, match="no video stream"):
        generate(clips["audio_only"], GenerateParams(mode="visual"))


def test_video_only_file_has_picture_tracks_and_no_vibration(clips):
    tl = generate(clips["video_only"])
    assert tl.source["audio"] is None
    assert not tl.vibration.any()
    assert tl.temperature_c.max() > tl.temperature_c.min()  # red and green segments
    with pytest.raises(MediaError, match="no audio stream"):
        generate(clips["video_only"], GenerateParams(mode="audio"))


def test_tracks_left_out_are_present_but_off(clips):
    tl = generate(clips["av"], GenerateParams(tracks=("vibration",)))
    np.testing.assert_allclose(tl.temperature_c, 33.0)
    assert not tl.fans.any()
    assert tl.stats["video"]["flow"]["ticks_computed"] == 0
    with pytest.raises(ParameterError, match="unknown track"):
        GenerateParams(tracks=("smell",))


def test_skipping_off_computes_everything_and_changes_little(clips, av_analysis):
    params = apply_overrides(GenerateParams(), {"video.skip": False})
    full = analyse(clips["av"], params)
    assert full.video.saliency_mask.all()
    assert full.stats["video"]["flow"]["ticks_skipped"] < av_analysis.stats["video"]["flow"]["ticks_skipped"]
    a, b = derive(av_analysis, GenerateParams()), derive(full, params)
    assert np.abs(a.vibration - b.vibration).mean() <= 0.02
    assert np.abs(a.temperature_c - b.temperature_c).mean() <= 0.3
