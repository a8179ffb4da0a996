"""The pipeline's composition: modes, tracks, skipping, the feature cache, missing streams."""

import numpy as np
import pytest

from autohaptics import synth
from autohaptics.errors import MediaError, ParameterError
from autohaptics.layout import ACTUATOR_IDS
from autohaptics.pipeline import (Analysis, GenerateParams, analyse, analysis_compatible, derive, generate,
                                  resolve_params)
from autohaptics.presets import apply_overrides

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
    params, _ = resolve_params(thresholds={"loudness": 0.05, "sharpness": 0.05, "booming": 0.05, "low_energy": 0.05})
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


# ---- the audio pass beside the video pass (VideoParams.overlap_s)

def _arrays(a: Analysis) -> dict:
    return {**{"audio_" + k: v for k, v in a.audio.items()}, **{"video_" + k: v for k, v in a.video.arrays().items()}}


def _same_analysis(a: Analysis, b: Analysis) -> None:
    x, y = _arrays(a), _arrays(b)
    assert x.keys() == y.keys()
    for k in x:
        np.testing.assert_array_equal(x[k], y[k], err_msg=k)
    for stage in ("saliency", "flow", "depth"):
        for key in ("ticks_computed", "ticks_held", "ticks_skipped"):
            assert a.stats["video"][stage][key] == b.stats["video"][stage][key], (stage, key)


@pytest.fixture(scope="module")
def one_after_the_other(clips):
    return analyse(clips["av"], resolve_params("balanced", {"video.overlap_s": "0"})[0])


def test_the_audio_pass_beside_the_video_pass_gives_the_same_analysis(clips, av_analysis, one_after_the_other):
    assert av_analysis.stats["audio"]["beside_video"] is True
    assert "beside_video" not in one_after_the_other.stats["audio"]
    sal = one_after_the_other.stats["video"]["saliency"]
    assert 0 < sal["ticks_computed"] < one_after_the_other.n_ticks  # not vacuous: silent ticks skip saliency
    _same_analysis(av_analysis, one_after_the_other)


@pytest.mark.parametrize("backlog_bytes", [1, 32 << 20])
def test_a_slow_audio_pass_fills_the_backlog_and_the_result_stays_the_same(clips, one_after_the_other, monkeypatch,
                                                                           backlog_bytes):
    import time

    from autohaptics import pipeline, vision

    real_pass, real_wait = pipeline._audio_pass, vision._Need.wait
    waits = []

    def slow(*args, **kwargs):
        time.sleep(0.5)  # the video pass reaches its first frames before the audio is known
        return real_pass(*args, **kwargs)

    def wait(self):
        waits.append(self.mask is None)  # True: the pass had to wait for the audio
        return real_wait(self)

    monkeypatch.setattr(pipeline, "_audio_pass", slow)
    monkeypatch.setattr(vision, "_BACKLOG_BYTES", backlog_bytes)  # 1 byte: wait at the first frame
    monkeypatch.setattr(vision._Need, "wait", wait)
    a = analyse(clips["av"], GenerateParams())
    assert a.stats["audio"]["beside_video"] is True
    assert waits, "the backlog was never used"
    if backlog_bytes == 1:
        assert waits[0] is True
    _same_analysis(a, one_after_the_other)


def test_an_error_in_the_audio_pass_beside_reaches_the_caller_and_no_thread_is_left(clips, monkeypatch):
    import threading

    from autohaptics import pipeline

    def broken(*args, **kwargs):
        raise MediaError("audio stream unreadable (test)")

    monkeypatch.setattr(pipeline, "_audio_pass", broken)
    with pytest.raises(MediaError, match="unreadable"):
        analyse(clips["av"], GenerateParams())
    assert not [t for t in threading.enumerate() if t.name == "autohaptics-audio"]


def test_an_error_in_the_video_pass_stops_the_audio_pass_beside(clips, monkeypatch):
    import threading
    import time

    from autohaptics import pipeline

    stopped = {}
    real = pipeline._audio_pass

    def watched(info, params, n, stats, progress, cancel, *, share):
        time.sleep(0.3)  # still running when the video pass fails
        try:
            return real(info, params, n, stats, progress, cancel, share=share)
        finally:
            stopped["cancel_set"] = cancel.is_set()

    def broken_video(*args, **kwargs):
        raise RuntimeError("video pass failed (test)")

    monkeypatch.setattr(pipeline, "_audio_pass", watched)
    monkeypatch.setattr(pipeline, "video_pass", broken_video)
    with pytest.raises(RuntimeError, match="video pass failed"):
        analyse(clips["av"], GenerateParams())
    assert not [t for t in threading.enumerate() if t.name == "autohaptics-audio"]
    assert stopped["cancel_set"] is True  # told to stop, and it ended before analyse returned


def test_cancel_stops_both_passes_and_progress_comes_from_the_calling_thread(clips):
    import threading

    from autohaptics.progress import CancelledError

    caller = threading.current_thread()
    calls = []
    flag = threading.Event()

    def progress(stage, fraction):
        calls.append((threading.current_thread() is caller, fraction))
        if fraction > 0.5:
            flag.set()

    with pytest.raises(CancelledError):
        analyse(clips["av"], GenerateParams(), progress=progress, cancel=flag)
    assert calls and all(same for same, _ in calls)
    assert not [t for t in threading.enumerate() if t.name == "autohaptics-audio"]

    calls.clear()
    analyse(clips["av"], GenerateParams(), progress=progress)
    fractions = [f for _, f in calls]
    assert all(same for same, _ in calls)
    assert fractions == sorted(fractions) and fractions[-1] == 1.0


def test_long_media_run_the_passes_one_after_the_other(clips):
    a = analyse(clips["av"], resolve_params("balanced", {"video.overlap_s": "1"})[0])  # the clip is longer
    assert "beside_video" not in a.stats["audio"]
    with pytest.raises(ParameterError):
        resolve_params("balanced", {"video.overlap_s": "-1"})
