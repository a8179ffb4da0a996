"""A file's sound tracks (``media.tracks``, ``media.audio``, ``media.mix``): of several tracks the
film's mix is read, not a commentary, an audio description or a compatibility stereo track; the
channels of one mix kept one per track are read as that mix, the same analysis signal as one stream of
them; what is another version of the sound (an Lt/Rt downmix, a repeated channel, another language, an
unlabelled track outside MXF) is left out; a track that ends early is silence after its end."""

from __future__ import annotations

from fractions import Fraction

import av
import numpy as np
import pytest

from autohaptics import media
from autohaptics.media.audio import read_audio
from autohaptics.media.mix import MIX_LAG_S, Mix
from autohaptics.testing.reencode import reencode

RATE = 48000
N = 960  # samples per frame: 20 ms
FIVE_ONE = ("FL", "FR", "FC", "LFE", "BL", "BR")


def _channels(n: int, seconds: float, seed: int = 3) -> np.ndarray:
    """``n`` channels of independent noise at different levels [shape=(n, samples)], float32."""
    rng = np.random.default_rng(seed)
    levels = np.linspace(0.05, 0.3, n)[:, None]
    return (levels * rng.standard_normal((n, int(seconds * RATE)))).astype(np.float32)


def _write(path, fmt: str, x: np.ndarray, layouts: list[str], *, languages: list[str] | None = None,
           lengths_s: list[float] | None = None, flags: list[str] | None = None,
           titles: list[str] | None = None) -> None:
    """A file with a small picture and one PCM track per entry of ``layouts``, track k holding the
    rows of ``x`` its layout has channels for, from row ``sum of the earlier tracks' channels`` on
    (cut to ``lengths_s[k]`` seconds where given; flagged with the disposition ``flags[k]`` and titled
    ``titles[k]`` where not empty)."""
    with av.open(str(path), "w", format=fmt) as out:
        video = out.add_stream("mpeg2video", rate=25)
        video.width, video.height, video.pix_fmt = 64, 48, "yuv420p"
        tracks, row = [], 0
        for k, name in enumerate(layouts):
            layout = av.AudioLayout(name)
            stream = out.add_stream("pcm_s16le", rate=RATE, layout=layout)
            if languages:
                stream.metadata["language"] = languages[k]
            if flags and flags[k]:
                stream.disposition = getattr(av.stream.Disposition, flags[k])
            if titles and titles[k]:
                stream.metadata["title"] = titles[k]
            n = int((lengths_s[k] if lengths_s else x.shape[1] / RATE) * RATE)
            tracks.append((stream, x[row:row + layout.nb_channels, :n]))
            row += layout.nb_channels
        for i in range(int(x.shape[1] / RATE * 25)):
            frame = av.VideoFrame.from_ndarray(np.zeros((48, 64, 3), np.uint8), format="rgb24")
            frame.pts = i
            for packet in video.encode(frame):
                out.mux(packet)
        for stream, y in tracks:
            for k in range(y.shape[1] // N):
                chunk = np.ascontiguousarray((y[:, k * N:(k + 1) * N].T * 32767).astype(np.int16).reshape(1, -1))
                frame = av.AudioFrame.from_ndarray(chunk, format="s16", layout=stream.codec_context.layout)
                frame.sample_rate, frame.pts, frame.time_base = RATE, k * N, Fraction(1, RATE)
                for packet in stream.encode(frame):
                    out.mux(packet)
        for stream in [video] + [s for s, _ in tracks]:
            for packet in stream.encode(None):
                out.mux(packet)


@pytest.fixture(scope="module")
def mix51(tmp_path_factory):
    """Six channels of noise as one 5.1 stream (the reference) and its analysis signal."""
    d = tmp_path_factory.mktemp("tracks")
    x = _channels(6, 3.0)
    ref = d / "one.mov"
    _write(ref, "mov", x, ["5.1"])
    return d, x, read_audio(ref)


@pytest.mark.parametrize("fmt, suffix, layouts", [
    ("mov", ".mov", list(FIVE_ONE)),  # QuickTime labels each track with its channel
    ("mxf", ".mxf", ["mono"] * 6),  # MXF's tracks carry no label: six are read in FFmpeg's 5.1 order
], ids=["quicktime-labelled", "mxf"])
def test_a_masters_mono_tracks_are_read_as_its_mix(mix51, fmt, suffix, layouts):
    """Before, only the first track was read: the left channel alone, at twice its weight in the mix
    (no centre, where the dialogue is, and no LFE)."""
    d, x, ref = mix51
    path = d / f"six{suffix}"
    _write(path, fmt, x, layouts)
    info = media.probe(path)
    assert (info.audio.channels, info.audio.tracks) == (6, (1, 2, 3, 4, 5, 6))
    got = read_audio(path, info=info)
    assert got.shape == ref.shape
    assert np.abs(got - ref).max() < 1e-6
    assert np.abs(ref - x[0, :ref.size]).max() > 0.1  # the mix is not its first channel: the test tells them apart


def test_the_quicktime_master_written_for_the_matrix_reads_as_its_source(mix51, tmp_path):
    """``testing.reencode(audio_tracks="mono")``, the matrix's row: six labelled 24-bit PCM tracks."""
    d, _, ref = mix51
    split = reencode(d / "one.mov", tmp_path / "split.mov", video_codec="copy", audio_codec="pcm_s24le",
                     audio_tracks="mono")
    info = media.probe(split)
    assert (info.audio.layout, len(info.audio.tracks)) == ("5.1", 6)
    assert np.abs(read_audio(split) - ref).max() < 1e-6


def test_labelled_tracks_that_repeat_the_mix_are_left_out(mix51, tmp_path):
    """An Lt/Rt pair after the discrete channels is their downmix; a second set of the same roles is
    another mix (an M&E); a plain mono track among labelled ones is the centre, in any order."""
    d, x, ref = mix51
    lt_rt = np.concatenate([x, _channels(2, 3.0, seed=9), _channels(2, 3.0, seed=10)])
    path = tmp_path / "with_downmix.mov"
    _write(path, "mov", lt_rt, list(FIVE_ONE) + ["FL", "FR", "DL", "DR"])
    info = media.probe(path)
    assert info.audio.tracks == (1, 2, 3, 4, 5, 6)
    assert np.abs(read_audio(path, info=info) - ref).max() < 1e-6

    three = _channels(3, 2.0)
    plain = tmp_path / "three.mov"
    _write(plain, "mov", three, ["3.0"])  # FL FR FC in one stream
    centre_first = tmp_path / "centre_first.mov"
    _write(centre_first, "mov", three[[2, 0, 1]], ["mono", "FL", "FR"])
    assert np.abs(read_audio(centre_first) - read_audio(plain)).max() < 1e-6


def test_tracks_that_are_versions_of_the_sound_are_not_its_channels(tmp_path):
    """Tracks in another language, and unlabelled mono tracks outside MXF (Matroska, MP4: languages,
    commentary), leave the first track read alone, as one mono sound."""
    x = _channels(2, 2.0)
    first_alone = tmp_path / "first.mov"
    _write(first_alone, "mov", x[:1], ["mono"])
    languages = tmp_path / "languages.mov"
    _write(languages, "mov", x, ["FL", "FR"], languages=["eng", "fra"])
    unlabelled = tmp_path / "unlabelled.mkv"
    _write(unlabelled, "matroska", x, ["mono", "mono"])
    for path in (languages, unlabelled):
        info = media.probe(path)
        assert (info.audio.tracks, info.audio.channels) == ((), 1)
        assert np.abs(read_audio(path, info=info) - read_audio(first_alone)).max() < 1e-6


def test_a_track_that_ends_early_is_silence_after_its_end(tmp_path):
    """The mix runs to the longest track; a shorter one adds nothing past its end."""
    x = _channels(2, 4.0)
    path = tmp_path / "short_right.mov"
    _write(path, "mov", x, ["FL", "FR"], lengths_s=[4.0, 1.0])
    got = read_audio(path)
    left = tmp_path / "left.mov"
    _write(left, "mov", x[:1], ["mono"])
    assert got.size == 4 * RATE
    assert np.abs(got[2 * RATE:] - 0.5 * read_audio(left)[2 * RATE:]).max() < 1e-6


class _Collect:
    def __init__(self):
        self.n = 0

    def emit(self, mono: np.ndarray) -> None:
        self.n += mono.size


def test_a_track_that_falls_behind_never_holds_the_film_in_memory():
    """A track with no samples (empty, or broken from some point on) is silence once it lags the
    others by ``MIX_LAG_S``: the mix goes on emitting, and holds no more than that lag."""
    out = _Collect()
    mix = Mix(2, 1000, out)
    lane = mix.lane(0)
    for _ in range(60):
        lane.emit(np.ones(1000, np.float32))  # 60 s of one track, none of the other
    assert out.n >= (60 - MIX_LAG_S - 1) * 1000
    assert max(mix.have) <= (MIX_LAG_S + 1) * 1000
    mix.lane(1).emit(np.ones(500, np.float32))  # the late track's samples for time already mixed are dropped
    mix.close()
    assert out.n == 60 * 1000


def _alone(tmp_path, x: np.ndarray, layout: str) -> np.ndarray:
    """The analysis signal of ``x`` as the one track of a file."""
    path = tmp_path / f"alone_{layout}_{x.shape[0]}.mkv"
    _write(path, "matroska", x, [layout])
    return read_audio(path)


@pytest.mark.parametrize("flags, titles", [
    (["comment", ""], ["", ""]),  # flagged as a commentary
    (["visual_impaired", ""], ["", ""]),  # an audio description
    (["default", ""], ["Director's Commentary", ""]),  # a rip's title alone, and the commentary the default
])
def test_the_mix_is_read_not_a_commentary_or_description_ahead_of_it(tmp_path, flags, titles):
    """Track 1 is set aside (stereo), track 2 is the mix (stereo): the mix is read, as a file of it alone."""
    x = _channels(4, 2.0)
    path = tmp_path / "tracks.mkv"
    _write(path, "matroska", x, ["stereo", "stereo"], flags=flags, titles=titles)
    info = media.probe(path)
    assert info.audio.index == 2  # stream 0 is the picture
    assert np.abs(read_audio(path, info=info) - _alone(tmp_path, x[2:], "stereo")).max() < 1e-6


def test_the_51_mix_is_read_before_a_compatibility_stereo_track(tmp_path):
    """A stereo track ahead of the 5.1 mix (HandBrake's and iTunes' files, the stereo flagged default):
    the mix is read, as FFmpeg's command line picks; of two mixes of as many channels, the default one,
    else the first; a file whose every track is set aside is read from its first."""
    x = _channels(8, 2.0)
    compat = tmp_path / "compat.mp4"
    _write(compat, "mp4", x, ["stereo", "5.1"], flags=["default", ""])
    assert (media.probe(compat).audio.index, media.probe(compat).audio.channels) == (2, 6)
    assert np.abs(read_audio(compat) - _alone(tmp_path, x[2:], "5.1")).max() < 1e-6
    languages = tmp_path / "languages.mkv"
    _write(languages, "matroska", x[:4], ["stereo", "stereo"], flags=["", "default"], languages=["fra", "eng"])
    assert media.probe(languages).audio.index == 2
    untagged = tmp_path / "untagged.mkv"
    _write(untagged, "matroska", x[:4], ["stereo", "stereo"], flags=["", ""])
    assert media.probe(untagged).audio.index == 1
    aside = tmp_path / "aside.mkv"
    _write(aside, "matroska", x[:4], ["stereo", "stereo"], flags=["comment", "visual_impaired"])
    assert media.probe(aside).audio.index == 1


def test_a_masters_mono_tracks_count_as_their_mix_against_a_stereo_track(tmp_path):
    """Six labelled mono tracks and a stereo downmix after them: the six are the sound (6 channels), as
    without the stereo track."""
    x = _channels(8, 2.0)
    path = tmp_path / "master.mov"
    _write(path, "mov", x, list(FIVE_ONE) + ["stereo"])
    info = media.probe(path)
    assert (info.audio.tracks, info.audio.channels) == ((1, 2, 3, 4, 5, 6), 6)
