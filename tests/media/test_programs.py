"""A recording of a whole multiplex (``testing.broadcast.as_multiplex``): the programmes of a transport stream
read from its tables (``media.programs``), and the film read from one programme, its picture, its sound and
its clock, whatever the other programmes carry."""

from __future__ import annotations

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from autohaptics import pipeline
from autohaptics import testing as synth
from autohaptics.bench.matrix import misses, row_figures
from autohaptics.bench.variants import Variant
from autohaptics.media import probe
from autohaptics.media.programs import crc32_mpeg, program_pids
from autohaptics.testing.broadcast import (OTHER_BOOMS_S, as_multiplex, as_recording, other_channel, section_packets,
                                           table_section)
from autohaptics.testing.scenes import material_scene
from autohaptics.timebase import TICK_S


@pytest.fixture(scope="module")
def films(tmp_path_factory):
    """The film (the matrix's scene, 18 s, stereo) and another channel's programme (14 s, its 5.1 sound
    booming between the film's impacts)."""
    d = tmp_path_factory.mktemp("multiplex")
    film = synth.write_scene(d / "film.mp4", material_scene(18.0), width=320, height=180, fps=25)
    channel = other_channel(d / "other.mp4", 14.0)
    return d, film, channel


def test_the_tables_crc_is_mpeg2s():
    assert crc32_mpeg(b"123456789") == 0x0376E6E7  # the check value of CRC-32/MPEG-2
    section = b"\x00\xb0\x0d\x00\x01\xc1\x00\x00\x00\x01\xf0\x00"
    assert crc32_mpeg(section + crc32_mpeg(section).to_bytes(4, "big")) == 0


def test_tables_across_packets_are_gathered(tmp_path):
    """A programme map longer than a packet (a broadcaster's, with many descriptors) read from two, the
    association table's network entry left out, a packet's adaptation field skipped; a map for a
    programme the table does not list is not a programme."""
    pat = table_section(0x00, 1, b"\x00\x00\xe0\x10" + b"\x00\x05\xf0\x00" + b"\x00\x07\xf1\x00")  # network, 5, 7
    info = bytes([0x0A, 200]) + b"x" * 200  # 202 bytes of programme descriptors
    es = b"\x1b\xe1\x00\xf0\x00" + b"\x81\xe1\x01\xf0\x03\x05\x01\x00"  # H.264 0x100, AC-3 0x101
    pmt5 = table_section(0x02, 5, b"\xe1\x00" + (0xF000 | len(info)).to_bytes(2, "big") + info + es)
    pmt7 = table_section(0x02, 7, b"\xe1\x20\xf0\x00" + b"\x1b\xe1\x20\xf0\x00")
    stray = table_section(0x02, 9, b"\xe1\x40\xf0\x00" + b"\x1b\xe1\x40\xf0\x00")
    filler = b"".join(bytes([0x47, 0x1F, 0xFF, 0x10]) + b"\xff" * 184 for _ in range(12))
    data = filler + section_packets(0, pat, adaptation=7) + section_packets(0x1000, pmt5) \
        + section_packets(0x1200, stray) + section_packets(0x1100, pmt7)
    assert len(section_packets(0x1000, pmt5)) == 2 * 188
    path = tmp_path / "tables.ts"
    path.write_bytes(data + filler)
    assert program_pids(path) == {5: (0x100, 0x101), 7: (0x120,)}


@settings(max_examples=200, deadline=None)
@given(st.binary(max_size=4000), st.integers(0, 3), st.sampled_from((188, 192, 204)),
       st.lists(st.tuples(st.integers(0, 10**6), st.integers(0, 255)), max_size=20))
def test_any_bytes_give_programmes_or_none_never_an_error(tmp_path_factory, noise, pid_pick, size, flips):
    """Bytes that look like transport packets (sync bytes in place, anything between), or a real table's
    packets with any bytes changed: a programme map of packet ids, possibly empty, never an error."""
    pids = (0, 0x1000, 0x1100, 0x1FFF)[pid_pick]
    body = bytearray()
    for k in range(0, len(noise) + 1, 184):
        head = bytes([0x47, 0x40 | pids >> 8, pids & 0xFF, 0x10 | k % 16])
        body += (b"\0" * (size - 188) if size == 192 else b"") + head + noise[k:k + 184].ljust(184, b"\xff")
        body += b"\0" * (size - 188) if size == 204 else b""
    pat = table_section(0x00, 1, b"\x00\x05\xf0\x00")
    pmt = table_section(0x02, 5, b"\xe1\x00\xf0\x00" + b"\x1b\xe1\x00\xf0\x00")
    tables = bytearray((section_packets(0, pat) + section_packets(0x1000, pmt)) * 6)
    for at, value in flips:
        tables[at % len(tables)] = value
    path = tmp_path_factory.mktemp("noise") / "noise.ts"
    for data in (bytes(body) * (12 * size // len(body) + 1), bytes(tables)):  # ten packets or more
        path.write_bytes(data)
        got = program_pids(path)
        assert isinstance(got, dict)
        assert all(isinstance(n, int) and all(0 <= pid <= 0x1FFF for pid in pids_) for n, pids_ in got.items())
    if not flips:
        assert got == {5: (0x100,)}


def test_the_programmes_are_read_from_the_tables(films):
    """Three programmes, in the table's order, each with its picture's and sound's packet ids; the same
    bytes as a Blu-ray's M2TS (a 4-byte time before each packet) read the same; a damaged first copy of
    the association table is passed over for the next; one programme and a file that is not a transport
    stream."""
    d, film, other = films
    mux = as_multiplex([film, other, film], d / "three.ts")
    got = program_pids(mux)
    assert list(got) == [1, 2, 3]
    assert got == {1: (0x100, 0x101), 2: (0x120, 0x121), 3: (0x140, 0x141)}
    data = mux.read_bytes()
    m2ts = d / "three.m2ts"
    m2ts.write_bytes(b"".join(b"\0\0\0\0" + data[i:i + 188] for i in range(0, len(data), 188)))
    assert program_pids(m2ts) == got
    first_pat = next(i for i in range(0, len(data), 188) if data[i + 1] & 0x1F == 0 and data[i + 2] == 0)
    damaged = bytearray(data)
    damaged[first_pat + 13] ^= 0xFF  # the first programme number of the first copy
    (d / "damaged.ts").write_bytes(bytes(damaged))
    assert program_pids(d / "damaged.ts") == got
    assert program_pids(as_recording(film, d / "one.ts")) == {1: (0x100, 0x101)}
    assert program_pids(film) == {}


@pytest.mark.parametrize("clocks_s", [(3600.0, 0.0), (0.0, 7200.0)], ids=["other_earlier", "other_later"])
def test_a_multiplex_is_read_as_its_first_programmes_film(films, clocks_s):
    """The film is the first programme: its picture, its sound (not the other channel's 5.1, though it
    has more channels) and its own clock, an hour after or two before the other's. Before, the picture
    was the film's and the sound the other channel's, the two clocks joined: 3648 s of timeline for the
    18 s film (the other's clock earlier) or 48 s (later), vibrating at the other's booms."""
    d, film, other = films
    mux = as_multiplex([film, other], d / f"mux_{int(clocks_s[0])}.ts", clocks_s=clocks_s)
    own, info = probe(film), probe(mux)
    assert (info.video.index, info.audio.index) == (0, 1)
    assert (info.video.width, info.audio.channels) == (320, 2)
    assert info.start_s == pytest.approx(clocks_s[0], abs=0.1)
    assert info.duration_s == pytest.approx(own.duration_s, abs=0.1)
    want, got = pipeline.generate(film), pipeline.generate(mux)
    assert abs(want.n_ticks - got.n_ticks) <= 1
    fig = row_figures(want, got, Variant("multiplex", "codec"))
    assert misses(fig) == [] and fig["onset_f1"] == 1.0, fig
    for t in OTHER_BOOMS_S:  # the other channel's booms fall between the film's: nothing there
        k = int(round(t / TICK_S))
        assert got.vibration[k:k + 3].max() == pytest.approx(want.vibration[k:k + 3].max(), abs=0.05)


def test_a_radio_programme_ahead_of_the_film_is_passed_over(films):
    """A multiplex whose first programme is a radio station (sound only, 5.1): the film is the first
    programme with a picture, and its sound is its own, not the radio's."""
    d, film, other = films
    radio = synth.write_scene(d / "radio.m4a", material_scene(12.0), channels=6)
    mux = as_multiplex([radio, film], d / "radio_first.ts", clocks_s=(0.0, 600.0))
    info = probe(mux)
    assert (info.video.width, info.audio.channels) == (320, 2)
    assert info.start_s == pytest.approx(600.0, abs=0.1)
    assert info.duration_s == pytest.approx(probe(film).duration_s, abs=0.1)
