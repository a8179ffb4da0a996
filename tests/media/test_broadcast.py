"""Broadcast recordings (MPEG-TS, ``testing.broadcast`` writes them from the tests' scene): a clock hours in, a
clock that wraps inside the file, a recording begun mid-GOP, a sound whose first packet comes after
FFmpeg's first look at the file, an adaptive stream's renditions of several sizes and a channel's sound
that changes layout or sample rate are all read as the film they hold."""

from __future__ import annotations

from fractions import Fraction

import av
import numpy as np
import pytest

from autohaptics import pipeline
from autohaptics import testing as synth
from autohaptics.bench.matrix import cut_analysis, misses, row_figures
from autohaptics.bench.variants import VARIANTS, Variant
from autohaptics.media import iter_video, probe, read_audio
from autohaptics.server import posters
from autohaptics.testing.broadcast import WRAP_S, ac3_packets, as_adaptive, as_rate_break, as_recording
from autohaptics.testing.scenes import MATERIAL_IMPACTS_S, material_scene
from autohaptics.timebase import TICK_S


@pytest.fixture(scope="module")
def film(tmp_path_factory):
    d = tmp_path_factory.mktemp("broadcast")
    src = synth.write_scene(d / "film.mp4", material_scene(), width=320, height=180, fps=25)
    analysis = pipeline.analyse(src)
    return d, src, analysis, pipeline.derive(analysis)


def _same(a, b):
    """The film's timeline ``a`` and a recording's ``b``: the same ticks, and figures that meet the matrix's
    targets (a transport stream plays the AAC encoder's priming that MP4 skips: its sound starts 21 ms
    earlier on the clock, the picture's frames with it)."""
    assert abs(a.n_ticks - b.n_ticks) <= 1
    fig = row_figures(a, b, Variant("recording", "codec"))
    assert misses(fig) == [] and fig["onset_f1"] == 1.0, fig


@pytest.mark.parametrize("clock_s, wraps", [(10 * 3600.0, False), (WRAP_S - 5.0, True)])
def test_a_recording_on_the_broadcasters_clock_reads_as_the_film(film, clock_s, wraps):
    """10 h into the clock, and 5 s before it wraps: the file's times fall back to 0 after 5 s (FFmpeg
    reads the 5 s before as negative). Before, the wrapped file was refused as truncated (the times
    before 0 were dropped)."""
    d, src, _, timeline = film
    rec = as_recording(src, d / f"clock_{int(clock_s)}.ts", clock_s=clock_s)
    info = probe(rec)
    assert info.start_s == pytest.approx(-5.0 if wraps else clock_s, abs=0.2)
    assert info.duration_s == pytest.approx(probe(src).duration_s, abs=0.1)
    _same(timeline, pipeline.generate(rec))


def test_a_sound_that_comes_after_the_first_look_is_found(film):
    """The sound's first packet 10 s after the picture's: past what FFmpeg reads (5 s of its clock) before
    it says what a file holds, so its rate and channels were unknown and the file was refused. Now they are read, the
    sound is silent until it comes and the film's sound from there."""
    d, src, analysis, timeline = film
    rec = as_recording(src, d / "late_sound.ts", sound_late_s=10.0)
    info = probe(rec)
    assert (info.audio.sample_rate, info.audio.channels) == (48000, 2)
    got = pipeline.generate(rec)
    k = int(round(10.0 / TICK_S))
    assert got.vibration[:k - 1].max() == 0.0 < timeline.vibration[:k - 1].max()
    for hit_s in (s for s in MATERIAL_IMPACTS_S if 11.0 < s < 21.0):  # the impacts after it vibrate as in the film
        hit = slice(int(hit_s / TICK_S), int(hit_s / TICK_S) + 4)
        assert got.vibration[hit].max() == pytest.approx(timeline.vibration[hit].max(), abs=0.1)
    n = min(got.n_ticks, timeline.n_ticks)
    np.testing.assert_allclose(got.fans[:n], timeline.fans[:n], atol=1e-6)


def test_a_recording_begun_mid_gop_gives_the_film_from_there(film):
    """Begun at 3.7 s, 0.3 s before the next keyframe (the scene's keyframes are 2 s apart): the frames
    before it cannot be decoded (the screen is black there, as a player shows it); the sound is there
    from 3.7 s. The figures of the matrix's broadcast row against the film from there, the clock
    wrapping on the way."""
    d, src, analysis, _ = film
    rec = as_recording(src, d / "mid_gop.ts", clock_s=WRAP_S - 6.0, begin_s=3.7)
    got = pipeline.analyse(rec)
    assert got.n_ticks == pytest.approx(203, abs=1)
    assert got.video.stats["frames"]["ticks_with_frame"] == pytest.approx(got.n_ticks - 3, abs=1)
    row = next(v for v in VARIANTS if v.name.startswith("broadcast recording"))
    assert row.suffix == ".ts" and row.start_s > 0
    fig = row_figures(pipeline.derive(cut_analysis(analysis, 3.7, got.n_ticks)), pipeline.derive(got),
                      Variant("mid-GOP", "start", start_s=3.7))
    assert misses(fig) == [], fig


def test_a_picture_whose_size_changes_mid_file_is_read_at_the_size_it_declares(film):
    """An adaptive stream's recording: the renditions' sizes in turn, 6 s each. Every frame comes at the
    size the stream declares (its first), so crops, proxies and flow pairs keep one geometry; the film
    gives what it gives at one size. Before, the bar search refused frames of two sizes (a ValueError)."""
    d, src, _, timeline = film
    rec = as_adaptive(src, d / "adaptive.ts", scales=(1.0, 0.5, 0.75))
    info = probe(rec)
    assert (info.video.width, info.video.height) == (320, 180)
    sizes = {(f.width, f.height) for f in iter_video(rec)}
    assert sizes == {(320, 180)}
    with av.open(str(rec)) as c:
        assert {(f.width, f.height) for f in c.decode(video=0)} == {(320, 180), (160, 90), (240, 136)}
    fig = row_figures(timeline, pipeline.generate(rec), Variant("adaptive", "picture"))
    assert misses(fig) == [], fig


def test_a_recording_whose_sound_changes_rate_for_a_break_reads_as_the_film(film):
    """The matrix's row of a channel's recording with an advertisement break at its own rate
    (``testing.broadcast.as_rate_break``): the file holds the sound at 48, 44.1 and 48 kHz in turn, and it
    meets the matrix's figures against the film, every onset in place."""
    d, src, _, timeline = film
    dur = probe(src).duration_s
    rec = as_rate_break(src, d / "rate_break.ts", break_s=(0.3 * dur, 0.6 * dur))
    with av.open(str(rec)) as c:
        rates = [(float(f.time), f.sample_rate) for f in c.decode(audio=0)]
    runs = [r for k, (_, r) in enumerate(rates) if k == 0 or r != rates[k - 1][1]]
    assert runs == [48000, 44100, 48000], runs
    assert abs(next(t for t, r in rates if r == 44100) - 0.3 * dur) < 0.1  # within a tick
    _same(timeline, pipeline.generate(rec))


def _joined(d, src, name: str, second_clock_s: float):
    """Two recordings of the film joined byte for byte (``cat a.ts b.ts``): the first on a clock at 100 s,
    the second at ``second_clock_s``."""
    a = as_recording(src, d / f"{name}_a.ts", clock_s=100.0)
    b = as_recording(src, d / f"{name}_b.ts", clock_s=second_clock_s)
    path = d / f"{name}.ts"
    path.write_bytes(a.read_bytes() + b.read_bytes())
    return path


@pytest.fixture(scope="module")
def continuous(film):
    """The two recordings on one running clock: the second begins where the first ends."""
    d, src, _, _ = film
    length = probe(as_recording(src, d / "length.ts", clock_s=100.0)).duration_s
    path = _joined(d, src, "continuous", 100.0 + length)
    return path, pipeline.generate(path)


@pytest.mark.parametrize("second_clock_s", [30.0, 5000.0, WRAP_S - 50.0], ids=["back", "on", "past_the_wrap"])
def test_joined_recordings_play_on_across_the_jump(film, continuous, second_clock_s):
    """The second recording's clock 70 s back, 81 minutes on, or a day on (FFmpeg takes a step back for its
    clock's wrap): the file plays on across the jump, the second recording from where the first ends, as a
    player plays them, and gives what the join on one running clock gives. Before, the step was taken as it stands: a timeline
    of 26.5 h, or of 81 minutes, for a film of 48 s."""
    d, src, _, _ = film
    path = _joined(d, src, f"joined_{int(second_clock_s)}", second_clock_s)
    info = probe(path)
    assert info.duration_s == pytest.approx(probe(continuous[0]).duration_s, abs=1e-3)
    assert info.clock.jump_positions and info.to_dict()["clock"]["jump_positions"]
    got, want = pipeline.generate(path), continuous[1]
    assert got.n_ticks == want.n_ticks
    for track in ("vibration", "temperature_c", "fans"):
        np.testing.assert_allclose(getattr(got, track), getattr(want, track), atol=1e-4)


def test_a_transport_streams_pictures_are_found_at_their_time(film, continuous):
    """FFmpeg seeks in a transport stream by a search over its bytes that stops near the time, not at the
    keyframe before it: a poster at 0.5 s showed the picture at 2 s (the next keyframe), and one in the
    last GOP none at all. ``media.clock`` keeps the keyframes' bytes: each picture is the film's own, on
    a joined recording's second half too."""
    d, src, _, _ = film
    rec = as_recording(src, d / "posters.ts", clock_s=100.0)
    assert probe(rec).clock.key_positions and "clock" not in probe(rec).to_dict()  # no jump: nothing to say
    ticks = [5, 45, 95, 118]
    want = posters.frames_at(_film(src), ticks, (160, 90))
    second = int(round(probe(rec).duration_s / TICK_S))  # the joined recording's second half
    for path, offset in ((rec, 0), (continuous[0], 0), (continuous[0], second)):
        got = posters.frames_at(_film(path), [t + offset for t in ticks], (160, 90))
        for w, g in zip(want, got):
            assert np.abs(w.astype(int) - g).mean() < 2.0


def _film(path):
    info = probe(path)
    return posters.Film(path, info, None, info.video.shown_aspect())


def test_a_channel_that_carries_nothing_beside_the_sound_costs_no_further_look(film, monkeypatch):
    """A recorder's audio description channel without a packet, beside the film's sound: the sound is read,
    and the file is opened once, not again with the longer look (which would read up to 1 GB at every
    open); a sound that comes late, alone, is looked for further."""
    d, src, _, _ = film
    rec = as_recording(src, d / "with_empty.ts")
    empty = d / "empty_channel.ts"
    with av.open(str(rec)) as c, av.open(str(empty), "w", format="mpegts") as out:
        streams = {s.index: out.add_stream_from_template(s) for s in (c.streams.video[0], c.streams.audio[0])}
        out.add_stream("mp2", rate=48000, layout="stereo")  # declared, never sent
        for p in c.demux(c.streams.video[0], c.streams.audio[0]):
            if p.size and p.dts is not None:
                p.stream = streams[p.stream.index]
                out.mux(p)
    opened = []
    real_open = av.open
    monkeypatch.setattr(av, "open", lambda *a, **k: opened.append(k.get("options")) or real_open(*a, **k))
    info = probe(empty)
    assert (info.audio.sample_rate, info.audio.channels) == (48000, 2) and info.audio.codec == "aac"
    assert opened and not any(opened)
    opened.clear()
    probe(as_recording(src, d / "late_alone.ts", sound_late_s=10.0))
    assert any(o for o in opened)


def _channel_sound(path, first: str, second: str, rates: tuple[int, int] = (48000, 48000)):
    """A channel's recording whose sound changes layout at 10 s (AC-3 ``first``, then ``second``, at ``rates``;
    a 5.1 part carries the sound in its centre, as a film's dialogue and effects sit there): a 220 Hz bed and
    a 60 Hz boom every 2 s from 1 s, over a still picture. MPEG-TS, 20 s."""
    parts = []
    for layout, rate, t0 in ((first, rates[0], 0.0), (second, rates[1], 10.0)):
        t = np.arange(int(round(t0 * rate)), int(round(t0 * rate)) + 10 * rate) / rate
        x = 0.02 * np.sin(2 * np.pi * 220 * t)
        for k in range(10):
            d = t - (1.0 + 2 * k)
            boom = (d >= 0) & (d < 0.3)
            x[boom] += 0.6 * np.sin(2 * np.pi * 60 * d[boom]) * np.exp(-d[boom] * 8)
        n = av.AudioLayout(layout).nb_channels
        channels = np.zeros((n, x.size), np.float32)
        channels[[0, 1] if n == 2 else [2]] = x
        parts.append((channels, layout, rate, t0))
    packets = ac3_packets(parts)
    with av.open(str(path), "w", format="mpegts") as out:
        video = out.add_stream("mpeg2video", rate=25)
        video.width, video.height, video.pix_fmt = 64, 36, "yuv420p"
        sound = out.add_stream("ac3", rate=rates[0], layout=first)
        items = [(float(p.pts * p.time_base), p, sound) for p in packets]
        still = av.VideoFrame.from_ndarray(np.full((36, 64, 3), 90, np.uint8), format="rgb24").reformat(format="yuv420p")
        for i in range(500):
            still.pts, still.time_base = i, Fraction(1, 25)
            items += [(float(p.pts * p.time_base), p, video) for p in video.encode(still)]
        items += [(float(p.pts * p.time_base), p, video) for p in video.encode(None)]
        for _, p, stream in sorted(items, key=lambda item: item[0]):
            p.stream = stream
            out.mux(p)
    return path


@pytest.mark.parametrize("first, second", [("stereo", "5.1"), ("5.1", "stereo")])
def test_a_sound_that_changes_layout_mid_stream_is_read_in_each(tmp_path, first, second):
    """Advertisements in stereo, then the film in 5.1, or the other way: each part downmixed by its own
    layout. Before, the first part's weights held for the whole stream: stereo then 5.1 lost the 5.1
    part's centre (its booms did not vibrate), and 5.1 then stereo raised an IndexError."""
    got = pipeline.generate(_channel_sound(tmp_path / f"{first}_{second}.ts", first, second))
    chair = got.vibration.max(axis=1)
    booms = [chair[int(round(s / TICK_S)):int(round(s / TICK_S)) + 4].max() for s in np.arange(1.0, 20.0, 2.0)]
    assert min(booms) >= 0.5, booms
    beds = [chair[int(round(s / TICK_S)) - 4:int(round(s / TICK_S))].max() for s in np.arange(3.0, 20.0, 2.0)]
    assert max(beds) == 0.0, beds


@pytest.mark.parametrize("rates", [(44100, 48000), (48000, 44100)])
def test_a_sound_that_changes_sample_rate_mid_stream_keeps_its_pitch_and_time(tmp_path, rates):
    """An advertisement at 44.1 kHz in a 48 kHz channel, or the other way (a stream's inserted sound keeps
    its own rate): each part is resampled from its own rate. Before, every frame was read at the stream's
    first rate: the other part's 220 Hz bed read 248 (or 188) Hz, with a gap (or a cut) in every frame."""
    path = _channel_sound(tmp_path / f"rates_{rates[0]}_{rates[1]}.ts", "stereo", "5.1", rates)
    x = read_audio(path)
    assert abs(x.size - 20 * 48000) < 0.01 * 20 * 48000
    for t0 in (3.3, 13.3):  # the bed between two booms, in each part
        bed = x[int(t0 * 48000):int((t0 + 0.5) * 48000)]
        peak = np.fft.rfftfreq(bed.size, 1 / 48000)[np.argmax(np.abs(np.fft.rfft(bed)))]
        assert abs(peak - 220.0) <= 2.0, (t0, peak)
        assert np.abs(bed).min() < 0.02 and (np.abs(bed) > 1e-6).mean() > 0.99  # no gaps of silence in it
    got = pipeline.generate(path)
    chair = got.vibration.max(axis=1)
    booms = [chair[int(round(s / TICK_S)):int(round(s / TICK_S)) + 4].max() for s in np.arange(1.0, 20.0, 2.0)]
    assert min(booms) >= 0.5, booms
    beds = [chair[int(round(s / TICK_S)) - 4:int(round(s / TICK_S))].max() for s in np.arange(3.0, 20.0, 2.0)]
    assert max(beds) == 0.0, beds
