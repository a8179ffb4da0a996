"""The audio decode's clock: a frame's timestamp that only rounds (a millisecond container) or
strays for a frame (Vorbis at a block-size switch) moves no sample; a gap or an overlap that the
frames after it keep is silence or a cut, so the sound stays on the picture's clock; an AAC encoder's
priming is left out where the container does not mark it (raw ADTS) as where it does."""

from __future__ import annotations

from fractions import Fraction

import av
import numpy as np
import pytest

from autohaptics import media
from autohaptics.media.audio import AudioClock, read_audio, timestamp_slack_s

RATE = 44100
N = 1024  # samples per frame: 23.22 ms, never a whole number of milliseconds


def _noise(seconds: float) -> np.ndarray:
    """Broadband noise: any silence put into it or cut out of it changes the decoded signal."""
    return (0.3 * np.random.default_rng(1).standard_normal(int(seconds * RATE))).astype(np.float32)


def _write(path, samples: np.ndarray, times_s: list[float], fmt: str) -> None:
    """One PCM packet per ``N`` samples of ``samples``, the k-th at ``times_s[k]`` (s) on the
    container's clock (Matroska rounds it to its millisecond)."""
    codec = "pcm_f32le"
    with av.open(str(path), "w", format=fmt) as out:
        a = out.add_stream(codec, rate=RATE, layout="mono")
        for k, t in enumerate(times_s):
            frame = av.AudioFrame.from_ndarray(samples[None, k * N:(k + 1) * N], format="flt", layout="mono")
            frame.sample_rate, frame.pts, frame.time_base = RATE, k * N, Fraction(1, RATE)
            for packet in a.encode(frame):
                packet.pts = packet.dts = int(round(t / packet.time_base))  # the muxer rounds it to its clock
                out.mux(packet)


def _contiguous(k: int) -> list[float]:
    return [i * N / RATE for i in range(k)]


@pytest.fixture(scope="module")
def plain(tmp_path_factory):
    """The sound with exact timestamps (a WAV-like sample clock): the reference decode."""
    x = _noise(3.0)
    k = len(x) // N
    path = tmp_path_factory.mktemp("clock") / "plain.nut"
    _write(path, x, _contiguous(k), "nut")
    return x, k, read_audio(path)


def test_a_millisecond_clock_moves_no_sample(plain, tmp_path):
    """Matroska's timestamps of 23.22 ms frames read 0.2-0.8 ms off; before, each was a run of zeros
    or a cut (on the shared BBB WebM 423 runs of silence and 1,011 cuts in 30 s)."""
    x, k, ref = plain
    path = tmp_path / "ms.mkv"
    _write(path, x, _contiguous(k), "matroska")
    np.testing.assert_array_equal(read_audio(path), ref)


def test_a_timestamp_that_strays_for_one_frame_moves_no_sample(plain, tmp_path):
    """A Vorbis block-size switch: one frame's time 10 ms late (or early), the next on time again;
    before, 10 ms of silence went in there and the next frames were cut back (the BBB opening's
    WebM: 23 times, each at a transient, where the switch happens)."""
    x, k, ref = plain
    times = _contiguous(k)
    times[40] += 0.010
    times[80] -= 0.010
    path = tmp_path / "stray.mkv"
    _write(path, x, times, "matroska")
    np.testing.assert_array_equal(read_audio(path), ref)


@pytest.mark.parametrize("fmt", ["nut", "matroska"])
def test_a_gap_the_frames_after_it_keep_is_silence(plain, tmp_path, fmt):
    """Frames 40 on 100 ms late (a dropout in the stream): 100 ms of silence before them, so every
    later sample lies at its time (to the millisecond Matroska counts in)."""
    x, k, ref = plain
    times = [t + (0.1 if i >= 40 else 0.0) for i, t in enumerate(_contiguous(k))]
    path = tmp_path / f"gap.{fmt}"
    _write(path, x, times, fmt)
    got = read_audio(path)
    cut, gap = int(40 * N / RATE * 48000), int(0.1 * 48000)
    np.testing.assert_array_equal(got[:cut - 48], ref[:cut - 48])
    assert np.abs(got[cut + 48:cut + gap - 48]).max() == 0.0
    after, want = got[cut + gap + 480:cut + gap + 5280], ref[cut + 480:cut + 5280]
    lags = range(-48, 49)
    lag = max(lags, key=lambda d: float(np.dot(got[cut + gap + 480 + d:cut + gap + 5280 + d], want)))
    assert abs(lag) <= (1 if fmt == "nut" else 48), lag
    if fmt == "nut":
        np.testing.assert_allclose(after, want, atol=2e-3)


@pytest.mark.parametrize("after, cut", [(-0.05, True), (0.0, False), (None, False)])
def test_an_overlap_is_cut_where_the_next_frame_keeps_it(after, cut):
    """A frame 50 ms early whose successor is as early (its first 50 ms repeat the sound before: cut)
    or on time again (a stray timestamp: kept whole); the last frame has no successor to confirm it."""
    n = 4096  # 93 ms: a cut never takes more than the frame's own samples
    clock = AudioClock(0.0, RATE, timestamp_slack_s(Fraction(1, 1000), RATE))
    assert clock.offset(0.0, n, n / RATE) == 0
    t = n / RATE - 0.05
    t_next = None if after is None else 2 * n / RATE + after
    shift = clock.offset(t, n, t_next)
    assert shift == (-int(round(0.05 * RATE)) if cut else 0)
    assert clock.next_s == pytest.approx((2 * n + shift) / RATE)


def test_the_slack_is_one_tick_of_the_time_base_and_two_samples():
    assert timestamp_slack_s(Fraction(1, 1000), 44100) == pytest.approx(0.001 + 2 / 44100)
    assert timestamp_slack_s(Fraction(1, 48000), 48000) == pytest.approx(3 / 48000)
    assert timestamp_slack_s(None, 48000) == pytest.approx(2 / 48000)


@pytest.mark.parametrize("suffix", [".aac", ".m4a"])
def test_an_aac_encoders_priming_is_left_out_whether_or_not_the_container_marks_it(tmp_path, suffix):
    """Raw ADTS has no field for the encoder's 1024 samples of priming (128 ms at 8 kHz, near-silence
    with the sound's pre-echo): they are left out as MP4 leaves them out, so a sound under way at the
    file's first sample is under way at the analysis's first sample in both."""
    from autohaptics.testing import Scene, Tone, write_scene

    scene = Scene(duration_s=2.0, audio=(Tone(0.0, 2.0, 200.0, level_dbfs=-12.0, ramp_s=0.0),), name="tone")
    path = write_scene(tmp_path / f"tone{suffix}", scene, video=False, sample_rate=8000, channels=1)
    x = read_audio(path)  # 48 kHz
    rms = [float(np.sqrt(np.mean(x[i:i + 480] ** 2))) for i in range(0, 4800, 480)]  # the first 0.1 s, 10 ms at a time
    assert min(rms[1:]) > 0.5 * max(rms), rms  # no 128 ms of priming before the tone
    assert abs(len(x) / 48000 - 2.0) < 0.05


def _two_tracks(path, first: np.ndarray, second: np.ndarray) -> None:
    """A Matroska file with two mono PCM audio tracks: 16-bit ``first``, float ``second``."""
    with av.open(str(path), "w", format="matroska") as out:
        streams = [out.add_stream(codec, rate=RATE, layout="mono") for codec in ("pcm_s16le", "pcm_f32le")]
        for stream, x, fmt in zip(streams, (first, second), ("s16", "flt")):
            for k in range(len(x) // N):
                chunk = x[None, k * N:(k + 1) * N]
                chunk = (chunk * 32767).astype(np.int16) if fmt == "s16" else chunk
                frame = av.AudioFrame.from_ndarray(chunk, format=fmt, layout="mono")
                frame.sample_rate, frame.pts, frame.time_base = RATE, k * N, Fraction(1, RATE)
                for packet in stream.encode(frame):
                    out.mux(packet)


def test_the_sound_read_is_the_stream_probe_chose(tmp_path):
    """The first audio stream FFmpeg can decode: a first track without a decoder is passed over
    (before, the probe named the second track and the decode read the first, and the file failed
    with "no decodable samples"); with both decodable, the first."""
    noise = _noise(2.0)
    both = tmp_path / "both.mkv"
    _two_tracks(both, np.zeros_like(noise), noise)
    data = both.read_bytes()
    assert data.count(b"A_PCM/INT/LIT") == 1
    unknown_first = tmp_path / "unknown_first.mkv"
    unknown_first.write_bytes(data.replace(b"A_PCM/INT/LIT", b"A_QQQ/INT/LIT"))

    assert media.probe(unknown_first).audio.index == 1
    got = read_audio(unknown_first)
    assert np.abs(got).max() > 0.1  # the noise of the second track
    assert media.probe(both).audio.index == 0
    assert np.abs(read_audio(both)).max() == 0.0  # the first track's silence
