"""Dolby dynamic range compression (``media.audio``, ``testing.dolby``): an AC-3 stream from a DVD, a
Blu-ray or a broadcast carries gain words that FFmpeg's decoder applies in full unless told not to
(loud passages cut, quiet ones raised, as a player's night mode); the sound analysed is the mix as
made, whatever the words say. Each file here is compared with the same frames carrying 0 dB words
(writing a word moves the frame's last bits, so the stream without words is not the same sound)."""

from __future__ import annotations

import av
import numpy as np
import pytest

from autohaptics import pipeline
from autohaptics.media import read_audio
from autohaptics.testing.dolby import SAMPLES_PER_FRAME, write_ac3

RATE = 48000


def _noise(channels: int, seconds: float, level: float = 0.1, seed: int = 5) -> np.ndarray:
    rng = np.random.default_rng(seed)
    return (level * rng.standard_normal((channels, int(seconds * RATE)))).astype(np.float32)


def _decoded(path, options=None) -> np.ndarray:
    """The file as FFmpeg decodes it (its own options unless ``options``): [shape=(channels, n)]."""
    with av.open(str(path)) as c:
        s = c.streams.audio[0]
        if options:
            s.codec_context.options = options
        return np.concatenate([f.to_ndarray() for f in c.decode(s)], axis=1)


@pytest.mark.parametrize("layout", ["stereo", "5.1"])
def test_ffmpeg_applies_the_words_unless_told_not_to(tmp_path, layout):
    """The words written are the ones FFmpeg's decoder reads: -6 dB and 0 dB on alternate frames halve every
    other frame's level by default, and leave it as it is with ``drc_scale`` 0."""
    n = av.AudioLayout(layout).nb_channels
    x = _noise(n, 2.0)
    frames = x.shape[1] // SAMPLES_PER_FRAME + 1
    clean = _decoded(write_ac3(tmp_path / "clean.ac3", x, layout, gains_db=[0.0] * frames))
    drc = tmp_path / "drc.ac3"
    write_ac3(drc, x, layout, gains_db=[-6.02 if k % 2 else 0.0 for k in range(frames)])
    squeezed, kept = _decoded(drc), _decoded(drc, {"drc_scale": "0"})
    for k in range(4, 20):
        part = slice(k * SAMPLES_PER_FRAME + 256, (k + 1) * SAMPLES_PER_FRAME - 256)  # clear of the overlap
        ratio = np.sqrt((squeezed[:, part] ** 2).mean() / (clean[:, part] ** 2).mean())
        assert ratio == pytest.approx(0.5 if k % 2 else 1.0, abs=0.02)
    assert np.abs(kept - clean).max() < 1e-3


@pytest.mark.parametrize("layout", ["stereo", "5.1"])
def test_the_sound_is_read_without_the_streams_compression(tmp_path, layout):
    x = _noise(av.AudioLayout(layout).nb_channels, 2.0)
    clean = read_audio(write_ac3(tmp_path / "clean.ac3", x, layout, gains_db=[0.0] * 100))
    drc = read_audio(write_ac3(tmp_path / "drc.ac3", x, layout, gains_db=[-12.0] * 100))
    assert np.sqrt((clean ** 2).mean()) > 0.01
    assert np.abs(drc - clean).max() < 1e-3 * np.abs(clean).max()


def test_a_boom_cut_by_night_mode_compression_vibrates_as_the_mix_does(tmp_path):
    """A low boom over a quiet bed, the stream's words cutting the boom by 12 dB and raising the bed by
    6 dB (a film profile's line mode): the vibration is the uncompressed mix's."""
    t = np.arange(int(6.0 * RATE)) / RATE
    bed = _noise(2, 6.0, level=0.01)
    boom = (0.6 * np.sin(2 * np.pi * 50 * t) * ((t >= 3.0) & (t < 3.6))).astype(np.float32)
    x = bed + boom[None, :]
    frames = x.shape[1] // SAMPLES_PER_FRAME + 1
    loud = [bool(np.abs(boom[k * SAMPLES_PER_FRAME:(k + 1) * SAMPLES_PER_FRAME]).max() > 0) for k in range(frames)]
    clean = pipeline.generate(write_ac3(tmp_path / "clean.ac3", x, "stereo", gains_db=[0.0] * frames))
    drc = pipeline.generate(write_ac3(tmp_path / "drc.ac3", x, "stereo", gains_db=[-12.0 if v else 6.0 for v in loud]))
    assert clean.vibration[28:40].max() > 0.5  # the boom vibrates
    np.testing.assert_allclose(drc.vibration, clean.vibration, atol=1e-3)
