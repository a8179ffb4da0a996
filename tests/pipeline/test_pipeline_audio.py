"""The audio path end to end on real clips: decode -> features -> intensity -> timeline."""

import subprocess
import sys

import numpy as np
import pytest

from autohaptics import intensity as it
from autohaptics.metrics import compare_timelines
from autohaptics.params import THESIS_RULES, GenerateParams, resolve_params
from autohaptics.pipeline import analyse, derive, generate
from autohaptics.timeline import Timeline
from shared_data import SHARED_CLIPS, shared_clip


def _onsets(x: np.ndarray) -> np.ndarray:
    on = (np.asarray(x) > 0).astype(int)
    return np.flatnonzero(np.diff(np.r_[0, on]) == 1)


def _sintel(params: GenerateParams) -> tuple:
    return (generate(shared_clip("sintel_trailer_640x272_vp8_vorbis.webm"), params),
            generate(shared_clip("sintel_trailer_480x204_h264_aac.mp4"), params))


@pytest.fixture(scope="module")
def sintel_pair():
    """The two encodes under the thesis's vibration rule (feature thresholds, no gate)."""
    rule = {key: value for key, value in THESIS_RULES.items() if key.startswith("intensity.")}
    return _sintel(resolve_params(overrides={"mode": "audio", **rule})[0])


def test_sintel_encodes_agree_on_where_the_chair_starts_by_default():
    """The default rule on both encodes: the chair's onsets match within one tick (F1, measured 0.91)."""
    a, b = _sintel(GenerateParams(mode="audio"))
    onsets = compare_timelines(a, b)["vibration"]["chair_onsets"]
    assert onsets["ref_onsets"] >= 10 and onsets["f1"] >= 0.85, onsets


@pytest.mark.parametrize("clip", SHARED_CLIPS or ["(no shared clips)"])
def test_generate_audio_mode_on_every_shared_clip(clip, tmp_path):
    path = shared_clip(clip)
    tl = generate(path, GenerateParams(mode="audio"))
    out = tl.save(tmp_path / "t.json")
    back = Timeline.load(out)
    assert back.n_ticks == int(np.ceil(back.source["duration_s"] / 0.1 - 1e-6))
    on = back.vibration.max(axis=0) > 0
    # the audio condition drives A1, A2 and A5 only (thesis table 4.1)
    assert set(np.flatnonzero(on)) <= {0, 1, 4}
    np.testing.assert_array_equal(back.vibration[:, 0], back.vibration[:, 4])
    for name in it.FEATURES + ("intensity",):
        f = back.features[name]
        assert f.shape == (back.n_ticks,) and np.isfinite(f).all() and 0 <= f.min() and f.max() <= 1


def test_sintel_encodes_agree_on_event_onsets(sintel_pair):
    """VP8/Vorbis and H.264/AAC encodes of the same trailer: every onset that clears its threshold
    decisively (by 0.05 after normalisation) has a counterpart in the other encode within one tick:
    an onset there, or vibration already under way. Onsets that only graze a threshold depend on
    the codec's rounding and are not expected to agree."""
    a, b = sintel_pair
    n = min(a.n_ticks, b.n_ticks)
    thr = np.array([it.DEFAULT_THRESHOLDS[f] for f in it.FEATURES])
    checked = 0
    for x, y in ((a, b), (b, a)):
        ox, oy = _onsets(x.features["intensity"][:n]), _onsets(y.features["intensity"][:n])
        active_y = y.features["intensity"][:n] > 0
        for o in ox:
            margin = max(x.features[f][o] - thr[i] for i, f in enumerate(it.FEATURES))
            if margin < 0.05:
                continue
            checked += 1
            lo, hi = max(0, o - 1), min(n, o + 2)
            assert np.any(np.abs(oy - o) <= 1) or active_y[lo:hi].any(), f"onset at tick {o} has no counterpart"
    assert checked >= 20


def test_derive_rethresholds_without_decoding(tmp_path):
    path = shared_clip("sintel_trailer_480x204_h264_aac.mp4")
    params = GenerateParams(mode="audio")
    analysis = analyse(path, params)
    analysis.save(tmp_path / "a.npz")
    cached = type(analysis).load(tmp_path / "a.npz")
    base = derive(cached, params)
    lower, _ = resolve_params(overrides={"mode": "audio"}, thresholds={"loudness": 0.5})
    more = derive(cached, lower)
    assert (more.vibration > 0).sum() > (base.vibration > 0).sum()
    np.testing.assert_allclose(derive(analysis, params).vibration, base.vibration)


def test_cli_generate_and_one_line_errors(tmp_path):
    exe = [sys.executable, "-m", "autohaptics.cli.main"]
    out = tmp_path / "t.json"
    r = subprocess.run(exe + ["generate", str(shared_clip("bbb_1s_1280x720_vp8_vorbis.webm")), "-o", str(out),
                              "--mode", "audio", "--threshold", "loudness=0.7"], capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    tl = Timeline.load(out)
    assert tl.generator["params"]["thresholds"]["loudness"] == 0.7
    bad = tmp_path / "garbage.mp4"
    bad.write_bytes(b"\x00garbage" * 100)
    cases = [
        ([str(tmp_path / "missing.mp4")], "no such file"),
        ([str(bad)], "not a readable media file"),
        ([str(shared_clip("bbb_1s_1280x720_vp8_vorbis.webm")), "--threshold", "bass=0.5"], "unknown threshold"),
    ]
    for args, msg in cases:
        r = subprocess.run(exe + ["generate", *args, "-o", str(out)], capture_output=True, text=True)
        assert r.returncode == 2
        assert msg in r.stderr and "Traceback" not in r.stderr
        assert len(r.stderr.strip().splitlines()) == 1


# A score cut mid-way, and a boom out of silence, through each audio path: AAC in Matroska, in .m4a
# and raw ADTS at 8 kHz (its 128 ms of priming unmarked), Opus through the resampler, FLAC at 96 kHz,
# 16-bit PCM 7.1.
AUDIO_PATHS = {"aac_mkv_22k05_stereo": ("mkv", dict(audio_codec="aac", sample_rate=22050, channels=2)),
               "aac_adts_8k_mono": ("aac", dict(sample_rate=8000, channels=1)),
               "aac_m4a_44k1_mono": ("m4a", dict(sample_rate=44100, channels=1)),
               "opus_mkv_24k_5.1": ("mkv", dict(audio_codec="libopus", sample_rate=24000, channels=6)),
               "flac_mkv_96k_stereo": ("mkv", dict(audio_codec="flac", sample_rate=96000, channels=2)),
               "s16_wav_32k_7.1": ("wav", dict(audio_codec="pcm_s16le", sample_rate=32000, channels=8))}


@pytest.mark.parametrize("audio_path", sorted(AUDIO_PATHS))
def test_a_cut_score_does_not_jolt_and_a_boom_after_silence_vibrates_through_every_audio_path(tmp_path, audio_path):
    from autohaptics.testing import Scene, sounds, write_scene

    suffix, kwargs = AUDIO_PATHS[audio_path]
    params, _ = resolve_params("balanced", {"mode": "audio", "tracks": ["vibration"]})
    film = Scene(duration_s=16.0, audio=tuple(sounds.music_bed(0.0, 16.0, level_dbfs=-20.0))
                 + tuple(sounds.impact(6.5, seed=1)), name="score")
    cut = write_scene(tmp_path / f"cut.{suffix}", sounds.cut_in(film, 5.23, 4.0), video=False, **kwargs)
    chair = generate(cut, params).vibration.max(axis=1)
    hit = slice(int(round((6.5 - 5.23 + 0.05) / 0.1)), int(round((6.5 - 5.23 + sounds.IMPACT_LENGTH_S - 0.05) / 0.1)))
    assert chair[:5].max() <= 0.2 and chair[hit].min() >= 0.7 * chair.max() > 0.5, chair[:20]
    boom = write_scene(tmp_path / f"boom.{suffix}", Scene(duration_s=3.0, audio=tuple(sounds.impact(0.3))),
                       video=False, **kwargs)
    chair = generate(boom, params).vibration.max(axis=1)
    assert not chair[:3].any() and chair[3:3 + int(sounds.IMPACT_LENGTH_S / 0.1)].min() >= 0.7, chair[:12]
