"""The synthetic scene generator: rendering is resolution independent, audio levels are as asked,
every container and channel layout the other tests rely on round-trips through autohaptics.media."""

from __future__ import annotations

from fractions import Fraction

import cv2
import numpy as np
import pytest

from autohaptics import media
from autohaptics import testing as synth
from autohaptics.errors import ParameterError
from autohaptics.testing import Noise, Scene, Segment, Shape, Texture, Tone


def _scene() -> Scene:
    return Scene(
        duration_s=2.0,
        background=(Segment(0.0, 1.0, (200, 30, 30), texture=Texture("noise", 0.08, 0.4)),
                    Segment(1.0, 2.0, (30, 160, 40))),
        shapes=(Shape("circle", (255, 255, 255), t_on=0.2, t_off=1.8, xy0=(0.25, 0.5), xy1=(0.75, 0.5),
                      size0=(0.1, 0.2), size1=(0.3, 0.5)),),
        audio=(Tone(0.5, 1.5, 1000.0, level_dbfs=-20.0), Noise(1.2, 1.8, level_dbfs=-30.0, colour="pink")),
    )


def test_render_is_resolution_independent():
    sc = _scene()
    big = synth.render_frame(sc, 0.7, width=1280, height=720)
    small = synth.render_frame(sc, 0.7, width=320, height=180)
    down = cv2.resize(big, (320, 180), interpolation=cv2.INTER_AREA)
    diff = np.abs(down.astype(np.int32) - small.astype(np.int32))
    assert diff.mean() < 1.5, diff.mean()
    assert np.percentile(diff, 99) < 12


def test_shape_moves_and_grows_in_normalised_coordinates():
    sc = Scene(duration_s=1.0, background=(Segment(0, 1, (0, 0, 0)),),
               shapes=(Shape("rect", (255, 255, 255), xy0=(0.25, 0.5), xy1=(0.75, 0.5),
                             size0=(0.1, 0.1), size1=(0.3, 0.3)),))
    for w, h in ((160, 90), (640, 360)):
        f0 = synth.render_frame(sc, 0.0, width=w, height=h)[..., 0] / 255.0
        f1 = synth.render_frame(sc, 0.999999, width=w, height=h)[..., 0] / 255.0
        xc = (np.arange(w) + 0.5) / w
        np.testing.assert_allclose((f0.sum(axis=0) * xc).sum() / f0.sum(), 0.25, atol=0.005)
        np.testing.assert_allclose((f1.sum(axis=0) * xc).sum() / f1.sum(), 0.75, atol=0.005)
        # Coverage (area in frame fractions) grows from 0.1 x 0.1 to 0.3 x 0.3.
        np.testing.assert_allclose([f0.mean(), f1.mean()], [0.01, 0.09], rtol=0.03)


def test_blinking_and_on_off_times():
    sc = Scene(duration_s=2.0, shapes=(Shape("rect", (255, 0, 0), t_on=0.5, t_off=1.5, blink_hz=2.0,
                                             size0=(0.5, 0.5)),))
    lit = [synth.render_frame(sc, t, width=32, height=18).max() > 0 for t in (0.2, 0.6, 0.9, 1.1, 1.6)]
    assert lit == [False, True, False, True, False]


def test_fade_and_cut_times():
    sc = Scene(duration_s=3.0, background=(Segment(0, 1, (200, 200, 200), rgb_end=(0, 0, 0)),
                                           Segment(1, 2, (0, 0, 0)), Segment(2, 3, (0, 0, 255))))
    # 0..1 fades into the identical 1..2 segment (no cut); 2 is a hard cut.
    assert sc.cut_times() == [2.0]
    mid = synth.render_frame(sc, 0.5, width=8, height=8)
    assert abs(int(mid[0, 0, 0]) - 100) <= 1


def test_iter_frames_count_and_reuse():
    sc = Scene(duration_s=1.0, background=(Segment(0, 1, (10, 20, 30)),))
    frames = list(synth.iter_frames(sc, width=16, height=8, fps=Fraction(30000, 1001)))
    assert len(frames) == 30
    assert frames[0][1] is frames[-1][1]  # static content is rendered once
    np.testing.assert_allclose([t for t, _ in frames[:3]], [0, 1001 / 30000, 2002 / 30000])


def test_iter_frames_equals_render_frame_with_a_cached_background():
    """A moving textured shape over a static textured background (rendered once per segment), a
    fading segment and a panning one (rendered every frame): every frame equals render_frame."""
    tex = synth.Texture("noise", 0.1, 0.4, seed=2)
    sc = Scene(duration_s=1.5, background=(Segment(0, 0.5, (90, 100, 110), texture=tex),
                                           Segment(0.5, 1.0, (200, 40, 30), rgb_end=(30, 40, 200), texture=tex),
                                           Segment(1.0, 1.5, (120, 110, 100), texture=tex, pan=(0.3, 0.0))),
               shapes=(Shape("circle", (240, 150, 40), xy0=(0.2, 0.5), xy1=(0.8, 0.4), size0=(0.1, 0.2),
                             size1=(0.3, 0.5), texture=synth.Texture("checker", 0.2, 0.5)),))
    for t, frame in synth.iter_frames(sc, width=64, height=36, fps=24):
        np.testing.assert_array_equal(frame, synth.render_frame(sc, t, width=64, height=36))


def test_audio_levels_and_channels():
    sc = Scene(duration_s=1.0, audio=(Tone(0.1, 0.9, 440.0, level_dbfs=-20.0, channels=(1,)),
                                      Noise(0.1, 0.9, level_dbfs=-30.0, colour="pink", channels=(0,))))
    x = synth.render_audio(sc, sample_rate=48000, channels=2)
    assert x.shape == (2, 48000) and x.dtype == np.float32
    rms = np.sqrt(np.mean(x[:, 10000:38000].astype(np.float64) ** 2, axis=1))
    np.testing.assert_allclose(20 * np.log10(rms), [-30.0, -20.0], atol=0.5)
    assert np.all(x[:, :4000] == 0) and np.all(x[:, 44000:] == 0)  # silence by default


def test_audio_chunked_equals_whole():
    sc = _scene()
    whole = synth.render_audio(sc, sample_rate=8000, channels=1)
    parts = np.concatenate([synth.render_audio(sc, sample_rate=8000, channels=1, start=s, n=1000)
                            for s in range(0, 16000, 1000)], axis=1)
    np.testing.assert_array_equal(whole, parts)


@pytest.mark.parametrize("suffix,kwargs,channels,layout", [
    (".mp4", {}, 2, "stereo"),
    (".webm", {}, 2, "stereo"),
    (".mkv", {"channels": 6}, 6, "5.1"),
    (".mov", {"channels": 1, "audio_codec": "pcm_s16le"}, 1, "mono"),
    (".avi", {"channels": 8}, 8, "7.1"),
    (".wav", {"channels": 6, "channel_layout": None}, 6, "6 channels"),
    (".m4a", {}, 2, "stereo"),
])
def test_containers_round_trip(tmp_path, suffix, kwargs, channels, layout):
    path = synth.write_scene(tmp_path / f"clip{suffix}", _scene(), width=64, height=36, fps=24, **kwargs)
    info = media.probe(path)
    assert abs(info.duration_s - 2.0) < 0.05
    assert info.audio is not None and info.audio.channels == channels and info.audio.layout == layout
    if suffix in (".wav", ".m4a"):
        assert info.video is None
    else:
        assert (info.video.width, info.video.height) == (64, 36)
        assert abs(info.video.fps - 24.0) < 1e-6


def test_video_only_and_colours_survive_encoding(tmp_path):
    path = synth.write_scene(tmp_path / "v.mp4", _scene(), width=64, height=36, fps=10, audio=False)
    info = media.probe(path)
    assert info.audio is None
    frames = [(f.time_s, f.proxy(64, 36).reshape(-1, 3).mean(axis=0)) for f in media.iter_video(path, info=info)]
    assert len(frames) == 20
    # 0..1 s red background (with a white disc), 1..2 s green.
    t, red = frames[1]
    t, green = frames[15]
    assert red[0] > red[1] + 50 and green[1] > green[0] + 50


def test_wav_levels_after_pcm(tmp_path):
    sc = Scene(duration_s=1.0, audio=(Tone(0.0, 1.0, 1000.0, level_dbfs=-20.0),))
    path = synth.write_scene(tmp_path / "t.wav", sc, channels=1)
    x = media.read_audio(path)
    rms = np.sqrt(np.mean(x[4800:-4800].astype(np.float64) ** 2))
    np.testing.assert_allclose(20 * np.log10(rms), -20.0, atol=0.05)


def test_sample_clip(tmp_path):
    path = synth.sample_clip(tmp_path / "sample.mp4", width=160, height=90)
    info = media.probe(path)
    assert abs(info.duration_s - 10.0) < 0.05
    assert synth.sample_scene().cut_times() == [3.0, 5.0, 7.0]


@pytest.mark.parametrize("kwargs,match", [
    ({"width": 65, "height": 36}, "even width"),
    ({"sample_rate": 44100, "audio_codec": "libopus"}, "libopus"),
    ({"channels": 6, "channel_layout": None}, "PCM"),
    ({"channels": 3}, "standard layout"),
])
def test_impossible_combinations_raise(tmp_path, kwargs, match):
    args = {"width": 64, "height": 36, **kwargs}
    with pytest.raises(ParameterError, match=match):
        synth.write_scene(tmp_path / "x.mkv", _scene(), **args)
    assert not list(tmp_path.iterdir())


def test_bad_scene_values_raise():
    with pytest.raises(ParameterError):
        Scene(duration_s=0.0)
    with pytest.raises(ParameterError):
        Segment(1.0, 0.5, (0, 0, 0))
    with pytest.raises(ParameterError):
        Shape(rgb=(300, 0, 0))
    with pytest.raises(ParameterError, match="suffix"):
        synth.write_scene("/tmp/x.xyz", _scene())


@pytest.mark.slow
def test_long_low_resolution_file_streams(tmp_path):
    """A 20-minute file at 32x18 @ 10 fps: written in constant memory with the long settings."""
    import psutil

    sc = Scene(duration_s=1200.0, background=(Segment(0, 600, (90, 90, 90)), Segment(600, 1200, (20, 20, 200))),
               shapes=(Shape("rect", t_on=100, t_off=110, xy0=(0.1, 0.5), xy1=(0.9, 0.5)),),
               audio=(Noise(0, 1200, level_dbfs=-40.0),))
    rss0 = psutil.Process().memory_info().rss
    path = synth.write_scene(tmp_path / "long.mkv", sc, width=32, height=18, fps=10, long=True,
                             quality="low", audio_codec="aac", sample_rate=8000, channels=1)
    grown_mb = (psutil.Process().memory_info().rss - rss0) / 2**20
    assert grown_mb < 150, grown_mb
    assert abs(media.probe(path).duration_s - 1200.0) < 0.5
