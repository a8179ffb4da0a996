"""The mono analysis signal of a multichannel file is the mean of FFmpeg's own default stereo
downmix of it (plus the LFE at its share), so a film and its stereo copy read the same sound at the
same level: checked against FFmpeg's resampler itself, and on a stereo sound written as 5.1."""

from __future__ import annotations

import av
import numpy as np
import pytest

from autohaptics.media.audio import read_audio
from stress_inputs import write_streams

RATE = 48_000
LFE_GAIN = 10.0 ** 0.5  # +10 dB, read_audio's default


def _signals(n_channels: int, seconds: float = 0.5) -> np.ndarray:
    """A different noise in each channel, float32 [shape=(channels, n)]."""
    rng = np.random.default_rng(n_channels)
    return (0.1 * rng.standard_normal((n_channels, int(seconds * RATE)))).astype(np.float32)


def _write(path, x: np.ndarray, layout: str) -> None:
    """``x`` [shape=(channels, n)] as float PCM (a WAV's channel mask keeps ``layout``)."""
    write_streams(path, audio=x, layout=layout, audio_codec="pcm_f32le", sample_rate=RATE)


def _ffmpeg_stereo(x: np.ndarray, layout: str) -> np.ndarray:
    """FFmpeg's default stereo downmix of ``x`` in float (what ``ffmpeg -ac 2`` hands a float
    encoder), float64 [shape=(2, n)]."""
    frame = av.AudioFrame.from_ndarray(np.ascontiguousarray(x.T).reshape(1, -1), format="flt", layout=layout)
    frame.sample_rate, frame.pts = RATE, 0
    resampler = av.AudioResampler(format="fltp", layout="stereo", rate=RATE)
    out = resampler.resample(frame) + resampler.resample(None)
    return np.concatenate([f.to_ndarray() for f in out], axis=1).astype(np.float64)


@pytest.mark.parametrize("layout", ["5.1", "5.1(side)", "7.1", "quad", "3.0", "6.1"])
def test_the_mono_signal_is_the_mean_of_ffmpegs_stereo_downmix_plus_the_lfe(tmp_path, layout):
    names = [ch.name for ch in av.AudioLayout(layout).channels]
    x = _signals(len(names))
    _write(tmp_path / "surround.wav", x, layout)
    got = read_audio(tmp_path / "surround.wav").astype(np.float64)
    expected = _ffmpeg_stereo(x, layout).mean(axis=0)
    if "LFE" in names:  # FFmpeg's downmix leaves the LFE out; ours adds it at its share
        expected += LFE_GAIN / (len(names) - 1) * x[names.index("LFE")]
    n = min(got.size, expected.size)
    assert n >= x.shape[1] - 1
    np.testing.assert_allclose(got[:n], expected[:n], rtol=0, atol=1e-6)


@pytest.mark.parametrize("layout", ["5.1", "7.1"])
def test_a_stereo_sound_written_as_surround_reads_as_the_stereo_file(tmp_path, layout):
    """FFmpeg's upmix of stereo puts it in the front pair alone: the same sound at the same level
    (the equal mean of the channels read it 8 dB quieter in 5.1)."""
    stereo = _signals(2)
    n_out = av.AudioLayout(layout).nb_channels
    surround = np.zeros((n_out, stereo.shape[1]), np.float32)
    surround[:2] = stereo
    _write(tmp_path / "stereo.mkv", stereo, "stereo")
    _write(tmp_path / "surround.wav", surround, layout)
    a, b = read_audio(tmp_path / "stereo.mkv"), read_audio(tmp_path / "surround.wav")
    np.testing.assert_allclose(b, a, rtol=0, atol=1e-7)


def test_six_unlabelled_channels_are_read_as_ffmpegs_default_5_1(tmp_path):
    x = _signals(6)
    _write(tmp_path / "labelled.wav", x, "5.1")
    _write(tmp_path / "unlabelled.wav", x, "6 channels")
    np.testing.assert_array_equal(read_audio(tmp_path / "unlabelled.wav"), read_audio(tmp_path / "labelled.wav"))


def test_an_unusual_unlabelled_layout_is_the_equal_mean_of_its_channels(tmp_path):
    x = _signals(3)
    _write(tmp_path / "three.wav", x, "3 channels")
    got = read_audio(tmp_path / "three.wav").astype(np.float64)
    np.testing.assert_allclose(got[:x.shape[1]], x.astype(np.float64).mean(axis=0), rtol=0, atol=1e-7)
