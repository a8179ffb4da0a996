"""Known answers for the default "events" vibration rule and the density control, on sound the
tests write themselves (autohaptics.testing.sounds -> a real .wav -> the pipeline), and properties
of the rule on any input."""

import dataclasses

import numpy as np
import pytest
from hypothesis import given, settings, strategies as st
from hypothesis.extra import numpy as hnp

from autohaptics import intensity as it
from autohaptics.errors import ParameterError
from autohaptics.params import THESIS_RULES, resolve_params
from autohaptics.pipeline.generate import generate
from autohaptics.testing import Noise, Scene, Tone, sounds, write_scene
from autohaptics.timebase import FRAMES_PER_TICK, TICK_S


def _run(tmp_path, scene, **overrides):
    """(per-tick intensity, the chair's strongest actuator per tick, stats) for ``scene``."""
    path = tmp_path / f"{scene.name}.wav"
    if not path.exists():
        write_scene(path, scene)
    params, _ = resolve_params("balanced", {"mode": "audio", "tracks": ["vibration"], **overrides})
    tl = generate(path, params)
    return tl.features["intensity"], tl.vibration.max(axis=1), tl.stats["vibration"]


def _ticks(t0, t1):
    return np.arange(int(round(t0 / TICK_S)), int(round(t1 / TICK_S)))


def test_impacts_drive_the_chair_and_the_music_bed_does_not(tmp_path):
    intensity, chair, stats = _run(tmp_path, sounds.music_with_impacts())
    impact = np.concatenate([_ticks(t, t + sounds.IMPACT_LENGTH_S) for t in sounds.IMPACT_TIMES_S])
    assert (chair[impact] >= 0.7 * chair.max()).all(), chair[impact]
    assert (intensity[impact] >= 0.7 * intensity.max()).all()
    music_only = np.ones(chair.size, bool)
    for t in sounds.IMPACT_TIMES_S:  # an impact and the second after it (its decay)
        music_only[_ticks(t, t + 1.3)] = False
    assert (chair[music_only] > 0).mean() <= 0.2
    assert stats["share"] == pytest.approx((chair > 0).mean())


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_speech_alone_rarely_vibrates(tmp_path, seed):
    scene = sounds.speech(level_dbfs=-20.0 - 4 * seed, seed=seed)
    _, chair, _ = _run(tmp_path, scene)
    assert (chair > 0).mean() <= 0.2
    _, thesis, _ = _run(tmp_path, scene, **THESIS_RULES)
    assert (thesis > 0).mean() > 0.4  # what the default fixes: the thesis rule buzzes on speech


def test_silence_never_vibrates(tmp_path):
    intensity, chair, stats = _run(tmp_path, sounds.silence())
    assert not chair.any() and not intensity.any() and stats["share"] == 0.0
    _, chair, _ = _run(tmp_path, sounds.silence(), **{"intensity.density": 0.5})
    assert not chair.any()


def test_a_rising_rumble_vibrates_ever_harder(tmp_path):
    scene = sounds.rising_rumble(duration_s=10.0, start_s=1.0)
    _, chair, _ = _run(tmp_path, scene)
    rumble = chair[_ticks(1.0, 10.0)]
    assert not chair[_ticks(0.0, 1.0)].any()
    second_half = rumble[rumble.size // 2:]
    assert (second_half > 0).all()
    on = rumble[rumble > 0]
    assert on.size > rumble.size / 2
    # rising: each later second vibrates harder than the one before it
    per_second = [on[k:k + 10].mean() for k in range(0, on.size - 9, 10)]
    assert all(b > a for a, b in zip(per_second, per_second[1:])), per_second
    assert np.corrcoef(np.arange(on.size), on)[0, 1] > 0.95


@pytest.mark.parametrize("start_s", [4.0, 5.23, 7.61])
@pytest.mark.parametrize("impacts", [False, True])
def test_a_file_cut_inside_the_score_does_not_jolt_at_its_start(tmp_path, start_s, impacts):
    """A reel or trailer that begins mid-score: the music was there before the file began."""
    audio = sounds.music_bed(0.0, 16.0, level_dbfs=-20.0)
    audio += [e for i, t in enumerate(sounds.IMPACT_TIMES_S) for e in sounds.impact(t, seed=i)] if impacts else []
    film = Scene(duration_s=16.0, audio=tuple(audio), name=f"score_{impacts}")
    scene = sounds.cut_in(film, start_s, 6.0)
    _, chair, _ = _run(tmp_path, scene)
    assert chair[_ticks(0.0, 0.5)].max() <= 0.2, chair[:8]
    later = [t - start_s for t in sounds.IMPACT_TIMES_S if 0.5 <= t - start_s <= scene.duration_s - 0.5]
    assert later or not impacts  # an impact after the cut still vibrates as the uncut film's does
    for t in later if impacts else []:
        assert chair[_ticks(t, t + sounds.IMPACT_LENGTH_S)].min() >= 0.7 * chair.max()


@pytest.mark.parametrize("delay_s", [0.02, 0.045, 0.08])
@pytest.mark.parametrize("room_dbfs", [None, -60.0])
def test_a_score_that_begins_a_moment_after_the_file_does_not_jolt_either(tmp_path, delay_s, room_dbfs):
    """A lossy encode's priming or a cut's first packets put a few silent frames (under GAP_S) before
    the score: still under way before the file began, while the impacts after it vibrate. The same
    over room tone under way from the first frame: the smoothed loudness holds the room tone's level
    for the running median's lag, and before, its opening check read the score as a hit (0.41-0.49
    from tick 1 on, at 45 and 80 ms)."""
    audio = sounds.music_bed(0.0, 16.0, level_dbfs=-20.0)
    audio += [e for i, t in enumerate(sounds.IMPACT_TIMES_S) for e in sounds.impact(t, seed=i)]
    cut = sounds.cut_in(Scene(duration_s=16.0, audio=tuple(audio), name="score"), 5.23, 6.0)
    late = tuple(dataclasses.replace(ev, t0=ev.t0 + delay_s, t1=min(ev.t1 + delay_s, cut.duration_s)) for ev in cut.audio)
    if room_dbfs is not None:
        late += (Noise(0.0, cut.duration_s, level_dbfs=room_dbfs, colour="pink", seed=3),)
    name = f"late_{delay_s:g}" + ("" if room_dbfs is None else f"_room{-room_dbfs:g}")
    _, chair, _ = _run(tmp_path, Scene(duration_s=cut.duration_s, audio=late, name=name))
    assert chair[_ticks(0.0, 0.5)].max() <= 0.2, chair[:8]
    later = [t - 5.23 + delay_s for t in sounds.IMPACT_TIMES_S if 0.5 <= t - 5.23 <= cut.duration_s - 0.5]
    inside = [_ticks(t + 0.05, t + sounds.IMPACT_LENGTH_S - 0.05) for t in later]  # whole ticks in the impact
    assert later and all(chair[k].min() >= 0.7 * chair.max() for k in inside), chair


@pytest.mark.parametrize("bed_hz, join_dbfs, hit", [(50.0, -21.0, False), (63.0, -21.0, False), (50.0, -18.0, True),
                                                    (63.0, -18.0, True)])
def test_a_low_score_under_way_is_judged_on_the_level_it_reached(tmp_path, bed_hz, join_dbfs, hit):
    """A low score under way from the first frame reaches its level only after the loudness model's
    attack (a 50 Hz tone: 0.56 of it over the first 0.1 s). A voice joining at 0.4 s that lifts it
    under twice that level (1.8 x) is the score's own swell: no vibration (before: 0.95 from 0.4 s,
    the rise read against the first 0.1 s); one that lifts it more is a hit and vibrates from the
    tick it begins in, though its own attack ends after the opening."""
    scene = Scene(duration_s=4.0, audio=(Tone(0.0, 4.0, bed_hz, level_dbfs=-24.0, ramp_s=0.0),
                                         Tone(0.4, 4.0, bed_hz * 1.26, level_dbfs=join_dbfs, ramp_s=0.005)),
                  name=f"low_score_{bed_hz:g}_{join_dbfs:g}")
    _, chair, _ = _run(tmp_path, scene)
    assert not chair[_ticks(0.0, 0.4)].any(), chair[:12]
    if hit:
        assert chair[_ticks(0.4, 1.0)].min() >= 0.7 * chair.max() and chair.max() > 0.5, chair[:12]
    else:
        assert chair.max() <= 0.2, chair[:12]


@pytest.mark.parametrize("at_s", [0.3, 0.6, 1.5])
def test_a_boom_out_of_silence_at_the_start_vibrates_at_its_level(tmp_path, at_s):
    boom = Scene(duration_s=4.0, audio=tuple(sounds.impact(at_s)), name=f"boom_{at_s:g}")
    intensity, chair, _ = _run(tmp_path, boom)
    hit = _ticks(at_s, at_s + sounds.IMPACT_LENGTH_S)
    assert (chair[hit] >= 0.7).all() and (intensity[hit] >= 0.7).all(), chair[:20]
    assert not chair[_ticks(0.0, at_s)].any()
    # the same boom over room tone, or under a score, that starts with the file: the boom vibrates
    for name, bed in (("room", [Noise(0.0, 4.0, level_dbfs=-60.0, colour="pink", seed=3)]),
                      ("score", sounds.music_bed(0.0, 4.0))):
        scene = Scene(duration_s=4.0, audio=tuple(bed) + tuple(sounds.impact(at_s)), name=f"{name}_boom_{at_s:g}")
        _, chair, _ = _run(tmp_path, scene)
        assert (chair[hit] >= 0.7 * chair.max()).all() and chair.max() > 0.5, (name, chair[:20])
        assert not chair[_ticks(0.0, at_s)].any(), (name, chair[:20])


@settings(max_examples=60, deadline=None)
@given(st.floats(1e-6, 1e6), st.integers(1, 400), st.floats(0.5, 30.0))
def test_a_level_held_from_the_first_frame_is_never_novel(level, n, baseline_s):
    from autohaptics.intensity.novelty import feature_novelty

    flat = np.full(n, level)
    out = feature_novelty({f: flat for f in it.rule.FEATURES}, baseline_s=baseline_s)
    assert all(not v.any() for v in out.values())


@settings(max_examples=60, deadline=None)
@given(st.integers(0, 100), st.integers(1, 200), st.floats(1e-3, 1e3))
def test_a_sound_after_an_opening_silence_is_an_onset_and_one_under_way_is_not(silent_frames, n, level):
    """At least GAP_S of opening silence: the sound after it is an onset; less (an encoder's priming,
    the fade of a cut): the sound was under way before the file began."""
    from autohaptics.intensity.novelty import GAP_S, novelty

    x = np.r_[np.zeros(silent_frames), np.full(n, level)]
    out = novelty(x)
    assert not out[:silent_frames].any()
    if silent_frames * 0.02 >= GAP_S - 1e-9:
        assert out[silent_frames] == 1.0
    else:
        assert not out.any()


def test_a_rise_far_below_the_films_top_counts_for_less():
    """The same 1.4 x rise passes every default threshold near the film's level and none among values
    at 2 % of its top, where a lossy codec's few-percent differences would decide it."""
    from autohaptics.intensity.novelty import novelty

    x = np.r_[np.full(300, 0.02), np.full(20, 0.028), np.full(300, 0.3), np.full(20, 0.42), np.full(60, 0.3),
              np.full(10, 1.0)]
    out = novelty(x, clip=False)
    assert out[300:320].max() < min(it.rule.DEFAULT_THRESHOLDS.values()), out[300:320]
    assert out[620:625].min() > max(it.rule.DEFAULT_THRESHOLDS.values()), out[620:625]


@pytest.mark.parametrize("loud_rise", [1.0, 1.01, 1.02, 1.04, 1.1, 1.3])
def test_a_brightening_counts_as_far_as_the_loudness_rises_with_it(loud_rise):
    """Sharpness doubles while the loudness rises by ``loud_rise``: its novelty is kept in proportion
    to the loudness's up to ``SHARPNESS_RISE``, in full above it; none where the loudness does not rise
    (before: in full from any rise at all, so a level change of a few percent switched it)."""
    from autohaptics.intensity.novelty import SHARPNESS_RISE, feature_novelty

    def step(a, b):
        return np.r_[np.full(300, a), np.full(30, b)]

    feats = {"sharpness": step(1.0, 2.0), "loudness": step(10.0, 10.0 * loud_rise),
             "booming": step(1.0, 1.0), "low_energy": step(1.0, 1.0)}
    out = feature_novelty(feats)
    alone = feature_novelty({**feats, "loudness": step(10.0, 1e3)})["sharpness"]  # the loudness's gate wide open
    share = np.clip(out["loudness"][310:] / SHARPNESS_RISE, 0.0, 1.0)
    np.testing.assert_allclose(out["sharpness"][310:], alone[310:] * share)
    assert alone[310:].min() > 0.5  # a doubling: over the threshold by itself
    weak = out["loudness"][310:] < SHARPNESS_RISE
    assert (out["sharpness"][310:][weak] < alone[310:][weak]).all()
    np.testing.assert_array_equal(out["sharpness"][310:][~weak], alone[310:][~weak])
    assert weak.all() == (loud_rise < 1.04) and (loud_rise > 1.0 or out["sharpness"].max() == 0.0)


def _pause_cuts(scene: Scene, count: int, *, lead_s: float = 0.25) -> list[float]:
    """Times (s) ``lead_s`` before the first ``count`` words of ``scene`` after 1.3 s that follow at
    least 0.3 s without sound: a file cut there opens on silence, its next word ``lead_s`` in."""
    events = sorted(scene.audio, key=lambda ev: ev.t0)
    cuts, end = [], 0.0
    for ev in events:
        if ev.t0 - end >= 0.3 and ev.t0 >= 1.3 + lead_s and ev.t0 + 5.0 <= scene.duration_s:
            cuts.append(ev.t0 - lead_s)
        end = max(end, ev.t1)
    return cuts[:count]


@pytest.mark.parametrize("room_dbfs", [None, -50.0])
def test_a_cut_inside_dialogue_does_not_jolt_on_its_next_word(tmp_path, room_dbfs):
    """A reel cut in a pause of the dialogue: its next word, 0.15-0.35 s in, is like the words after
    it, whose baseline tells what the film held before the file began (the rule before read each
    such word as an onset: 0.80-1.0 on all 8 cuts, over silence and room tone alike, where the film
    is still). Judged as the matrix judges a jolt: not above 0.2 where the uncut film is still."""
    speech = sounds.speech(30.0, level_dbfs=-20.0, seed=0)
    bed = () if room_dbfs is None else (Noise(0.0, 30.0, level_dbfs=room_dbfs, colour="pink", seed=3),)
    film = Scene(duration_s=30.0, audio=speech.audio + bed, name=f"dialogue_{room_dbfs}")
    _, whole, _ = _run(tmp_path, film)
    cuts = [c for lead in (0.15, 0.35) for c in _pause_cuts(speech, 4, lead_s=lead)]
    assert len(cuts) == 8
    for start in cuts:
        _, chair, _ = _run(tmp_path, sounds.cut_in(film, start, 5.0))
        k0 = int(round(start / TICK_S))
        assert chair[:5].max() <= max(0.2, whole[k0:k0 + 5].max()), (start, chair[:8], whole[k0:k0 + 8])


@pytest.mark.parametrize("every_s", [2.0, 3.5])
def test_booms_seconds_apart_out_of_silence_each_vibrate_the_first_too(tmp_path, every_s):
    """Drums seconds apart after 0.3 s of silence are like each other, but the baseline at the later
    ones holds the silence between them: the first is an onset as every later one is."""
    times = np.arange(0.3, 9.0 - sounds.IMPACT_LENGTH_S, every_s)
    scene = Scene(duration_s=9.0, audio=tuple(e for i, t in enumerate(times) for e in sounds.impact(float(t), seed=i)),
                  name=f"drums_{every_s:g}")
    _, chair, _ = _run(tmp_path, scene)
    for t in times:
        assert chair[_ticks(t, t + sounds.IMPACT_LENGTH_S)].min() >= 0.7 * chair.max(), (t, chair[:40])
    assert not chair[_ticks(0.0, 0.3)].any()


def test_the_first_onsets_likes_are_later_onsets_near_its_level_and_none_for_a_single_sound():
    from autohaptics.intensity.novelty import GAP_S, novelty, resumed_onsets

    frames = lambda s: int(round(s / 0.02))  # noqa: E731
    series = np.zeros(frames(8.0))
    for t in np.arange(0.3, 7.8, 0.5):  # a word every 0.5 s at one level, after 0.3 s of silence
        series[frames(t):frames(t + 0.25)] = 1.0
    likes = resumed_onsets(series)
    assert likes is not None and likes.min() >= frames(0.3 + GAP_S + 3.0) and likes.size >= 5
    assert not novelty(series)[:frames(0.6)].any()  # resumed: the first word is no onset
    assert novelty(series, resumed=None)[frames(0.3)] == 1.0  # the rule before: an onset out of silence
    quieter = series.copy()
    quieter[frames(1.0):] *= 0.3  # the words after the first at under half its level: not its likes
    assert resumed_onsets(quieter) is None and novelty(quieter)[frames(0.3)] == 1.0
    long_hit = np.r_[np.zeros(frames(0.3)), np.ones(frames(4.0)), np.full(frames(3.0), 0.2)]
    assert resumed_onsets(long_hit) is None and novelty(long_hit)[frames(0.3)] == 1.0
    assert resumed_onsets(np.zeros(50)) is None and resumed_onsets(np.ones(10)) is None


@pytest.mark.parametrize("make", [sounds.speech, sounds.rising_rumble, sounds.music_with_impacts])
def test_density_gives_about_that_share(tmp_path, make):
    scene = make()
    _, chair, stats = _run(tmp_path, scene, **{"intensity.density": 0.25})
    gated = _run(tmp_path, scene, **{"intensity.density": 1.0})[1]
    want = min(0.25, (gated > 0).mean())  # never more than the ticks above the loudness gate
    assert abs((chair > 0).mean() - want) <= 0.03
    assert stats["density"] == 0.25 and stats["share"] == pytest.approx((chair > 0).mean())


def test_density_works_with_the_thesis_rule_too(tmp_path):
    _, chair, _ = _run(tmp_path, sounds.speech(), **THESIS_RULES, **{"intensity.density": 0.25})
    assert abs((chair > 0).mean() - 0.25) <= 0.03


@pytest.mark.parametrize("override, value, message", [
    ("intensity.rule", "loud", "intensity.rule"), ("intensity.density", 1.5, "density"),
    ("intensity.density", "nan", "density"), ("intensity.baseline_s", 0.0, "baseline_s"),
])
def test_rule_and_density_are_validated(override, value, message):
    with pytest.raises(ParameterError, match=message):
        resolve_params("balanced", {override: value})


def test_no_density_is_the_default_and_can_be_asked_for():
    assert resolve_params("balanced")[0].intensity.density is None
    assert resolve_params("balanced", {"intensity.density": "none"})[0].intensity.density is None


_feature = hnp.arrays(np.float64, st.integers(1, 80).map(lambda k: k * FRAMES_PER_TICK),
                      elements=st.floats(0, 1e6) | st.just(0.0) | st.just(np.nan) | st.just(np.inf))


@settings(max_examples=80, deadline=None)
@given(st.data(), st.sampled_from(it.RULES), st.none() | st.floats(0, 1), st.sampled_from(["max", "percentile"]))
def test_intensity_is_finite_and_in_range_for_any_features(data, rule, density, normaliser):
    first = data.draw(_feature)
    feats = {f: data.draw(hnp.arrays(np.float64, first.size, elements=st.floats(0, 1e6) | st.just(np.nan)))
             for f in it.FEATURES[1:]}
    feats["sharpness"] = first
    feats = {f: np.where(np.isfinite(x), x, 0.0) for f, x in feats.items()}  # the analysis repairs these
    n = first.size // FRAMES_PER_TICK
    params = it.IntensityParams(rule=rule, density=density, normaliser=normaliser)
    out, curves, stats = it.audio_intensity(feats, n, params=params)
    assert out.shape == (n,) and np.isfinite(out).all() and out.min() >= 0 and out.max() <= 1
    for c in curves.values():
        assert c.shape == (n,) and np.isfinite(c).all() and c.min() >= 0 and c.max() <= 1
    assert np.isfinite(stats["threshold_scale"]) and stats["threshold_scale"] >= 0


@settings(max_examples=40, deadline=None)
@given(hnp.arrays(np.float64, st.integers(0, 400), elements=st.floats(0, 1e9) | st.just(np.nan) | st.just(np.inf)),
       st.floats(0.5, 30))
def test_novelty_is_finite_and_zero_for_silence(x, baseline_s):
    from autohaptics.intensity.novelty import novelty

    out = novelty(x, baseline_s=baseline_s)
    assert out.shape == x.shape and np.isfinite(out).all() and (out >= 0).all() and (out <= 1).all()
    assert not novelty(np.zeros(x.size), baseline_s=baseline_s).any()


@settings(max_examples=40, deadline=None)
@given(hnp.arrays(np.float64, st.integers(0, 300), elements=st.floats(-1e6, 1e6)), st.integers(1, 80))
def test_trailing_max_equals_scipy_maximum_filter(v, n):
    """The envelope's running maximum gives scipy.ndimage's trailing maximum_filter1d exactly."""
    from scipy.ndimage import maximum_filter1d

    from autohaptics.intensity.novelty import trailing_max

    out = trailing_max(v, n)
    assert out.shape == v.shape and out.dtype == v.dtype
    if v.size:
        assert np.array_equal(out, maximum_filter1d(v, n, origin=(n - 1) // 2, mode="nearest"))


def test_novelty_of_a_denormal_curve_is_finite():
    """Found by the property above: a curve whose peak is a denormal number (5e-324) made its floor
    underflow to 0 and its novelty 0/0."""
    from autohaptics.intensity.novelty import novelty

    out = novelty(np.r_[np.zeros(40), np.full(40, 5e-324)])
    assert np.isfinite(out).all() and out.min() >= 0 and out.max() <= 1 and out[40] > 0
