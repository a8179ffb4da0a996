"""The repeat cadence of a frame-rate conversion and a flow pair's time (airflow/cadence.py), on
generated luma samples: a texture that moves one step per picture, shown at another rate."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from autohaptics.airflow.cadence import Cadence

RNG = np.random.default_rng(5)
TEXTURE = RNG.integers(0, 256, (36, 400)).astype(np.uint8)


def picture(k: int, step: int = 3) -> np.ndarray:
    """Picture ``k`` of a texture panning ``step`` columns a picture, as a 36 x 64 luma sample."""
    return TEXTURE[:, k * step:k * step + 64].copy()


def shown(content_fps: int, stream_fps: int, n: int) -> list[int]:
    """The picture each of ``n`` stream frames shows when ``content_fps`` is converted to
    ``stream_fps`` by repeating pictures."""
    return [int(j * content_fps // stream_fps) for j in range(n)]


def feed(cad: Cadence, pictures: list[int], fps: int, start: int = 0, **kw) -> list[float]:
    times = [(start + j) / fps for j in range(len(pictures))]
    for t, k in zip(times, pictures):
        cad.add(t, picture(k, **kw))
    return times


def test_a_25_to_30_conversion_is_a_cadence_and_every_pair_reads_its_picture_steps():
    pics = shown(25, 30, 90)
    cad = Cadence(1 / 30, 0.35)
    times = []
    for j, k in enumerate(pics):
        cad.add(j / 30, picture(k))
        times.append(j / 30)
        if j >= 2 and cad.period():
            steps = pics[j] - pics[j - 2]  # pictures' steps in the pair of frames two apart
            # the newest frame is placed by the cadence alone; each step lasts 1/25 s
            assert cad.pair_time(times[j - 2], times[j]) == pytest.approx(steps / 25), j
    assert cad.period() == 6
    assert cad.found == sum(1 for a, b in zip(pics, pics[1:]) if a == b) - 1  # all but the last, unjudged


def test_a_film_that_repeats_pictures_of_its_own_keeps_its_cadence_at_30_fps():
    """A 24 fps film made 25 fps by repeating one picture a second, then shown at 30 fps: twice a
    second the film's own repeat stands beside one of the conversion's. The cadence holds through
    them (before: each broke it for two periods, and the pairs read 1.2 x for 0.4-0.6 s a second)."""
    film = shown(24, 25, 100)  # 4 s at 25 fps: the 24 fps picture each of its frames shows
    frames = [j * 25 // 30 for j in range(120)]  # the 25 fps frame each 30 fps frame shows
    cad = Cadence(1 / 30, 0.35)
    timed = 0
    for j, f in enumerate(frames):
        cad.add(j / 30, picture(film[f]))
        if j >= 40:
            assert cad.period() == 6, j
            pictures = {film[g] for g in frames[j - 2:j + 1]}
            if frames[j] - frames[j - 2] == 2 and len(pictures) == 3:  # two steps, none the film's own repeat
                assert cad.pair_time((j - 2) / 30, j / 30) == pytest.approx(2 / 25), j
                timed += 1
    assert timed >= 40


def test_a_held_pair_is_timed_by_its_successor_as_judged():
    pics = shown(24, 30, 14)  # repeats at frames 1 (no frame before it to judge by), 6 and 11
    cad = Cadence(1 / 30, 0.35)
    times = feed(cad, pics, 30)
    assert cad.period() == 0 and cad.found == 2  # too few for a cadence: steps over the stream's intervals
    assert cad.pair_time(times[4], times[6]) == pytest.approx(1 / 30)  # frame 6 repeats 5
    assert cad.pair_time(times[7], times[9]) == pytest.approx(2 / 30)


def test_a_stretch_on_twos_reads_as_its_own_picture_rate():
    pics = [j // 2 for j in range(40)]  # 24 fps, each picture shown twice: a 12 fps picture
    cad = Cadence(1 / 24, 0.35)
    times = feed(cad, pics, 24)
    assert cad.period() == 2
    for a in range(30, 36):  # pairs two frames apart hold one step, 1/12 s, whichever frame they start on
        assert cad.pair_time(times[a], times[a + 2]) == pytest.approx(1 / 12)


def test_a_still_a_slow_or_an_uneven_picture_keeps_the_streams_time():
    for pics, step in (([0] * 40, 3), (list(range(40)), 1), ([int(j ** 1.5) for j in range(40)], 1)):
        cad = Cadence(1 / 24, 0.35)
        times = feed(cad, pics, 24, step=step)
        assert cad.found == 0
        assert cad.pair_time(times[10], times[12]) == pytest.approx(2 / 24)


def test_the_cadence_ends_where_a_repeat_it_places_is_not_one():
    cad = Cadence(1 / 30, 0.35)
    pics = shown(25, 30, 60)
    feed(cad, pics, 30)
    assert cad.period() == 6
    feed(cad, [pics[-1] + 1 + j for j in range(12)], 30, start=60)  # then a picture every frame
    assert cad.period() == 0


def test_off_or_without_a_frame_rate_the_pair_time_is_the_span():
    for cad in (Cadence(1 / 30, 0.0), Cadence(0.0, 0.35)):
        times = feed(cad, shown(25, 30, 40), 30)
        assert cad.found == 0
        assert cad.pair_time(times[4], times[6]) == pytest.approx(2 / 30)


@settings(max_examples=60, deadline=None)
@given(st.lists(st.integers(0, 40), min_size=3, max_size=80), st.floats(0.0, 1.0), st.integers(0, 79),
       st.integers(1, 5))
def test_a_pair_time_is_positive_and_never_longer_than_its_span(pics, ratio, a, span):
    cad = Cadence(1 / 30, ratio)
    times = feed(cad, pics, 30)
    a = min(a, len(times) - 1)
    b = min(a + span, len(times) - 1)
    t = cad.pair_time(times[a], times[b])
    assert 0 < t <= max(times[b] - times[a], 1e-3) + 1e-12
