"""Re-encodes as the material matrix needs them: bars (pad), crop (fill), anamorphic pixels, 10 bits, HDR
grades, a variable frame rate, a stretch cut out of a film, the sound alone mixed again with the picture's
packets kept, the sound at another level, and a surround sound mixed to stereo at its own level."""

from __future__ import annotations

from fractions import Fraction

import av
import numpy as np
import pytest

from autohaptics import testing as synth
from autohaptics.errors import ParameterError
from autohaptics.media import probe
from autohaptics.media.audio import read_audio
from autohaptics.testing import Scene, Segment, Shape, Tone
from autohaptics.testing.reencode import reencode

# a bright frame-filling picture with a marker disc, and a tone that starts at 1 s
SCENE = Scene(3.0, background=(Segment(0, 3.0, (200, 180, 160)),),
              shapes=(Shape("circle", (20, 20, 200), t_on=0, t_off=3.0, xy0=(0.5, 0.5), size0=(0.2, 0.35)),),
              audio=(Tone(1.0, 3.0, 440.0, level_dbfs=-12.0),))


@pytest.fixture(scope="module")
def src(tmp_path_factory):
    return synth.write_scene(tmp_path_factory.mktemp("re") / "src.mp4", SCENE, width=320, height=180, fps=25)


def _frame(path, index: int = 10) -> np.ndarray:
    with av.open(str(path)) as c:
        for i, f in enumerate(c.decode(c.streams.video[0])):
            if i == index:
                return f.to_ndarray(format="rgb24").astype(int)
    raise AssertionError("too few frames")


@pytest.mark.parametrize("size, bars", [((320, 240), "rows"), ((426, 180), "cols")])
def test_pad_centres_the_whole_picture_on_black_bars(src, tmp_path, size, bars):
    out = reencode(src, tmp_path / "pad.mp4", width=size[0], height=size[1], fit="pad")
    img = _frame(out)
    assert img.shape[:2] == (size[1], size[0])
    rows_black = img.max(axis=(1, 2)) < 24
    cols_black = img.max(axis=(0, 2)) < 24
    lines, across = (rows_black, cols_black) if bars == "rows" else (cols_black, rows_black)
    assert lines[:26].all() and lines[-26:].all() and not lines[lines.size // 2] and not across.any()
    # the marker disc stays round and centred: as wide as it is tall, in pixels
    blue = (img[..., 2] > 150) & (img[..., 0] < 90)
    ys, xs = np.nonzero(blue)
    assert abs((xs.max() - xs.min()) - (ys.max() - ys.min())) <= 4
    assert abs(xs.mean() - size[0] / 2) <= 3 and abs(ys.mean() - size[1] / 2) <= 3


@pytest.mark.parametrize("sar, bar_rows", [(Fraction(64, 45), 0), (Fraction(16, 15), 72)])
def test_an_anamorphic_picture_is_fitted_as_it_is_shown(src, tmp_path, sar, bar_rows):
    """A PAL DVD's 720 x 576 with pixels 64/45 wide shows 16:9: the 16:9 source fills it; with pixels
    16/15 wide (4:3 on screen) it is letterboxed (768 x 432 of 768 x 576 on screen). The file says
    its pixels' aspect, and the marker disc is round on screen (wider than high in stored pixels)."""
    out = reencode(src, tmp_path / "dvd.mkv", width=720, height=576, fit="pad", pixel_aspect=sar,
                   video_codec="mpeg2video", video_bit_rate=6_000_000)
    video = probe(out).video
    assert video.pixel_aspect == pytest.approx(float(sar))
    assert video.shown_aspect() == pytest.approx(float(720 * sar / 576))
    img = _frame(out)
    assert int((img.max(axis=(1, 2)) < 24).sum()) == pytest.approx(2 * bar_rows, abs=4)
    ys, xs = np.nonzero((img[..., 2] > 150) & (img[..., 0] < 90))
    assert (xs.max() - xs.min()) * float(sar) == pytest.approx(ys.max() - ys.min(), abs=5)


def test_fill_crops_the_overhang_and_leaves_no_bar(src, tmp_path):
    img = _frame(reencode(src, tmp_path / "fill.mp4", width=240, height=180, fit="fill"))
    assert img.shape[:2] == (180, 240) and img.max(axis=(1, 2)).min() > 100 and img.max(axis=(0, 2)).min() > 100


def test_ten_bits(src, tmp_path):
    out = reencode(src, tmp_path / "ten.mp4", pix_fmt="yuv420p10le")
    with av.open(str(out)) as c:
        assert c.streams.video[0].codec_context.pix_fmt == "yuv420p10le"
    assert np.abs(_frame(out) - _frame(src)).mean() < 3


@pytest.mark.parametrize("transfer, codec", [("pq", "libx265"), ("hlg", "libx264")])
def test_an_hdr_grade_is_tagged_and_reads_as_the_sdr_picture(src, tmp_path, transfer, codec):
    """An HDR10 (HEVC) or HLG grade: 10-bit BT.2020 frames tagged with their transfer, whose SDR proxies
    (``media.hdr``) are the source's picture; FFmpeg's own conversion, which ignores the transfer, is not."""
    from autohaptics import media

    quiet = {"x265-params": "log-level=error"} if codec == "libx265" else None
    out = reencode(src, tmp_path / f"{transfer}.mp4", video_codec=codec, pix_fmt="yuv420p10le", transfer=transfer,
                   video_options=quiet)
    with av.open(str(out)) as c:
        f = [f for _, f in zip(range(11), c.decode(c.streams.video[0]))][-1]
        assert (f.format.name, f.color_primaries, f.colorspace, f.color_trc) == ("yuv420p10le", 9, 9,
                                                                                  {"pq": 16, "hlg": 18}[transfer])
        got = media.Frame(f, 10, 0.4, 0).proxy(160).astype(int)
        as_is = f.to_ndarray(width=160, height=90, format="rgb24", interpolation="AREA").astype(int)
    with av.open(str(src)) as c:
        g = [g for _, g in zip(range(11), c.decode(c.streams.video[0]))][-1]
        want = media.Frame(g, 10, 0.4, 0).proxy(160).astype(int)
    assert np.abs(got - want).mean() < 4
    assert np.abs(as_is - want).mean() > 10


def test_variable_frame_rate_keeps_each_frame_at_its_own_time(src, tmp_path):
    out = reencode(src, tmp_path / "vfr.mp4", conversion="vfr")
    with av.open(str(out)) as c:
        times = np.array([float(f.time) for f in c.decode(c.streams.video[0])])
    steps = np.round(np.diff(times) * 25).astype(int)
    assert set(steps) == {1, 2, 3}  # 1, 2 and 3 source frames apart, never evenly
    assert times[-1] == pytest.approx(3.0 - 0.04, abs=0.13)


def test_a_millisecond_time_base_at_its_own_rate_shows_every_frame_once(tmp_path):
    """Matroska stores 24 fps frame times rounded to the millisecond (0.042 s for 1/24 s): a re-encode
    at the source's own rate shows each source frame once, with no repeat and no frame dropped."""
    moving = Scene(2.0, background=(Segment(0, 2.0, (200, 180, 160)),),
                   shapes=(Shape("circle", (20, 20, 200), t_on=0, t_off=2.0, xy0=(0.1, 0.5), xy1=(0.9, 0.5),
                                 size0=(0.15, 0.25)),))
    first = synth.write_scene(tmp_path / "a.mp4", moving, width=160, height=90, fps=24, audio=False)
    mkv = reencode(first, tmp_path / "ms.mkv")
    with av.open(str(mkv)) as c:
        assert c.streams.video[0].time_base == Fraction(1, 1000)
        src = [f.to_ndarray(format="gray").astype(int) for f in c.decode(c.streams.video[0])]
    again = reencode(mkv, tmp_path / "again.mp4")
    with av.open(str(again)) as c:
        out = [f.to_ndarray(format="gray").astype(int) for f in c.decode(c.streams.video[0])]
    assert len(out) == len(src) == 48
    steps = [np.abs(b - a).mean() for a, b in zip(out, out[1:])]
    assert min(steps) > 0.2, steps  # the disc moved between every two frames: none repeated
    for i in range(1, len(out) - 1):  # frame i is source frame i, not its neighbour
        assert np.abs(out[i] - src[i]).mean() < min(np.abs(out[i] - src[j]).mean() for j in (i - 1, i + 1))


def test_a_cut_keeps_the_stretch_asked_for(src, tmp_path):
    out = reencode(src, tmp_path / "cut.mp4", start_s=0.6, duration_s=1.8)
    info = probe(out)
    assert info.duration_s == pytest.approx(1.8, abs=0.1)
    got = read_audio(out)
    onset = int(np.argmax(np.abs(got) > 0.05)) / 48000
    assert onset == pytest.approx(1.0 - 0.6, abs=0.03)  # the tone at 1 s of the film, 0.4 s into the cut


def test_a_cut_between_two_frames_keeps_the_picture_on_the_films_time(tmp_path):
    """A 24 fps film whose picture and sound change together at 1 s, cut at 0.61 s (between frames
    14 and 15): the picture changes 0.39 s into the cut, as in the film (before: 27 ms late, laid on
    a frame grid from 0, the frame on screen at the cut lasting a whole frame, which moved the
    matrix's fans and colour against the film's own ticks). The sound changes with it: the AAC
    encoder's priming is marked in the file (before: left in, the sound 21 ms late)."""
    scene = Scene(2.0, background=(Segment(0, 1.0, (40, 40, 40)), Segment(1.0, 2.0, (220, 220, 220))),
                  audio=(Tone(1.0, 2.0, 440.0, level_dbfs=-12.0, ramp_s=0.002),))
    film = synth.write_scene(tmp_path / "film.mp4", scene, width=160, height=90, fps=24)
    out = reencode(film, tmp_path / "cut.mp4", start_s=0.61, duration_s=1.0)
    with av.open(str(out)) as c:
        times = [(float(f.time), f.to_ndarray(format="gray").mean()) for f in c.decode(c.streams.video[0])]
    assert times[0][0] == pytest.approx(0.0, abs=1e-3) and times[0][1] < 100  # the frame on screen at the cut
    bright = next(t for t, level in times if level > 130)
    sound = int(np.argmax(np.abs(read_audio(out)) > 0.05)) / 48000
    assert bright == pytest.approx(0.39, abs=0.003) and sound == pytest.approx(0.39, abs=0.005), \
        (bright, sound)


@pytest.mark.parametrize("name, audio_codec", [("aac.mp4", "aac"), ("aac.mkv", "aac"), ("opus.webm", "libopus"),
                                               ("opus.mkv", "libopus")])
def test_the_sound_starts_where_the_sources_did_in_every_container(src, tmp_path, name, audio_codec):
    """The encoder's priming (AAC 1024 samples, Opus 312) is marked as FFmpeg's tools mark it, so the
    tone at the film's 1 s decodes at 1 s (before: 21 ms late in AAC, 6.5 ms in Opus)."""
    copy = "copy" if not name.endswith(".webm") else None  # WebM takes VP8/VP9 only: the picture encoded again
    out = reencode(src, tmp_path / name, video_codec=copy, audio_codec=audio_codec)
    onset = int(np.argmax(np.abs(read_audio(out)) > 0.05)) / 48000
    assert onset == pytest.approx(1.0, abs=0.004), onset


def _late_sound(path, late_s: float):
    """A 2 s grey picture whose sound's first frame lies ``late_s`` after the picture's (as a Vorbis
    stream's first decoded frame does, 23 ms in): a tone from 1 s of the sound, 1 s + late_s of the film."""
    rate, n = 48000, 1024
    tone = np.where(np.arange(2 * rate) >= rate, 0.25 * np.sin(2 * np.pi * 440 * np.arange(2 * rate) / rate), 0.0)
    with av.open(str(path), "w", format="matroska") as out:
        vs = out.add_stream("mpeg4", rate=25)
        vs.width, vs.height, vs.pix_fmt = 64, 48, "yuv420p"
        a = out.add_stream("pcm_s16le", rate=rate, layout="mono")
        for i in range(50):
            frame = av.VideoFrame.from_ndarray(np.full((48, 64, 3), 128, np.uint8), format="rgb24")
            frame.pts = i
            out.mux(vs.encode(frame))
        out.mux(vs.encode(None))
        for k in range(0, 2 * rate, n):
            frame = av.AudioFrame.from_ndarray((tone[None, k:k + n] * 32767).astype(np.int16), format="s16", layout="mono")
            frame.sample_rate, frame.pts, frame.time_base = rate, int(round(late_s * rate)) + k, Fraction(1, rate)
            out.mux(a.encode(frame))
        out.mux(a.encode(None))
    return path


@pytest.mark.parametrize("name, copy", [("copy.mkv", "copy"), ("again.mp4", None)])
def test_a_sound_that_starts_after_the_picture_keeps_its_time(tmp_path, name, copy):
    """The source's sound starts 40 ms after its picture: the re-encode's does too (before: its first
    sample was written at 0, the whole sound 40 ms early, 23 ms in every matrix row of a Vorbis film)."""
    film = _late_sound(tmp_path / "late.mkv", 0.04)
    assert int(np.argmax(np.abs(read_audio(film)) > 0.05)) / 48000 == pytest.approx(1.04, abs=0.002)
    out = reencode(film, tmp_path / name, video_codec=copy, audio_codec="libopus" if copy else "aac", audio_layout="stereo")
    onset = int(np.argmax(np.abs(read_audio(out)) > 0.05)) / 48000
    assert onset == pytest.approx(1.04, abs=0.004), onset


def test_copy_keeps_the_picture_packets_and_mixes_the_sound_again(src, tmp_path):
    out = reencode(src, tmp_path / "six.mkv", video_codec="copy", audio_layout="5.1", audio_bit_rate=384_000)
    assert probe(out).audio.channels == 6
    with av.open(str(src)) as a, av.open(str(out)) as b:
        pa = [bytes(p) for p in a.demux(a.streams.video[0]) if p.size]
        pb = [bytes(p) for p in b.demux(b.streams.video[0]) if p.size]
    assert pa == pb


@pytest.mark.parametrize("gain_db, copy", [(-8.0, "copy"), (-8.0, None), (6.0, "copy")])
def test_the_sound_can_be_quieter_or_louder_and_nothing_else_moves(src, tmp_path, gain_db, copy):
    """The level row of the matrix: the same sound ``gain_db`` dB off the source's, at its own time."""
    plain = read_audio(reencode(src, tmp_path / "plain.mkv", video_codec=copy, audio_codec="pcm_f32le"))
    out = read_audio(reencode(src, tmp_path / f"gain{gain_db:g}.mkv", video_codec=copy, audio_codec="pcm_f32le",
                              audio_gain_db=gain_db))
    assert out.shape == plain.shape
    level = 20 * np.log10(np.sqrt(np.mean(out ** 2)) / np.sqrt(np.mean(plain ** 2)))
    assert level == pytest.approx(gain_db, abs=0.05)
    np.testing.assert_allclose(out, plain * 10 ** (gain_db / 20), atol=2e-4)  # the tone at -12 dBFS: no clipping


@pytest.mark.parametrize("codec, suffix", [("libopus", ".webm"), ("aac", ".mp4")])
def test_a_surround_sound_mixed_to_stereo_keeps_ffmpegs_float_level(tmp_path, codec, suffix):
    """As ``ffmpeg -ac 2`` does, the encoder gets float samples where it takes them (libopus takes
    16-bit ones too: FFmpeg then normalises the 5.1 -> stereo downmix against clipping, -7.7 dB), so
    the screener's sound reads at its source's level."""
    film = synth.write_scene(tmp_path / "six.mkv", SCENE, width=64, height=36, fps=25, channels=6)
    out = reencode(film, tmp_path / f"two{suffix}", audio_codec=codec, audio_layout="stereo")
    assert probe(out).audio.channels == 2
    a, b = read_audio(film), read_audio(out)
    level = 20 * np.log10(np.sqrt(np.mean(b ** 2)) / np.sqrt(np.mean(a ** 2)))
    assert level == pytest.approx(0.0, abs=0.5), level


def test_bad_options_are_refused(src, tmp_path):
    with pytest.raises(ParameterError, match="fit"):
        reencode(src, tmp_path / "x.mp4", fit="zoom")
    with pytest.raises(ParameterError, match="pixel_aspect"):
        reencode(src, tmp_path / "x.mp4", pixel_aspect=-1)
    with pytest.raises(ParameterError, match="transfer"):
        reencode(src, tmp_path / "x.mp4", transfer="pq")  # an HDR grade is 10-bit
    with pytest.raises(ParameterError, match="audio_tracks"):
        reencode(src, tmp_path / "x.mp4", audio_tracks="stereo")
    with pytest.raises(ParameterError, match="start_s"):
        reencode(src, tmp_path / "x.mp4", start_s=1.0, duration_s=0.0)
