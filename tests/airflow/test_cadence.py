"""The repeat cadence of a frame-rate conversion and a flow pair's time (airflow/cadence.py), on
generated luma samples: a texture that moves one step per picture, shown at another rate."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from autohaptics.airflow.cadence import MAX_STEP_FRAMES, REACH, WAIT_S, Cadence

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


def judged_pairs(content_fps: int, stream_fps: float, seconds: float, span: int, pics: list[int] | None = None):
    """Feed a conversion of ``content_fps`` to ``stream_fps`` (or the pictures ``pics`` of the content
    at that rate) and yield, for each pair of frames ``span`` apart that holds a step, once it is settled
    (``Cadence.settled_s``, as the video pass holds a pair; the last ones after ``finish``): its first
    frame's time and its time over its picture steps' time."""
    pics = pics or [int(j * content_fps // stream_fps) for j in range(int(seconds * stream_fps))]
    n = len(pics)
    cad = Cadence(1 / stream_fps, 0.35)
    held = []
    for j, k in enumerate(pics):
        cad.add(j / stream_fps, picture(k, step=1))
        if j >= span and pics[j] > pics[j - span]:
            held.append((j - span, j))
        if j == n - 1:
            cad.finish()
        while held and (j == n - 1 or held[0][1] / stream_fps <= cad.settled_s):
            a, b = held.pop(0)
            steps = (pics[b] - pics[a]) / content_fps
            yield a / stream_fps, cad.pair_time(a / stream_fps, b / stream_fps) / steps


@pytest.mark.parametrize("content_fps,stream_fps", [(25, 30), (24, 30), (25, 50), (24, 50),
                                                    (24, 60000 / 1001), (24, 120)])
def test_a_conversion_times_every_pair_by_its_picture_steps(content_fps, stream_fps):
    """One repeat a period (25 -> 30), runs of two with a three now and then (24 -> 50), of two and
    three in turn (24 -> 59.94) or of five (24 -> 120): once the history holds enough judged frames,
    every pair reads its picture steps' own time (before: runs were not told, and a pair that ended on
    a picture's first frame at 59.94 fps read 1/60 s for a step of 1/24 s: 2.5 x the motion)."""
    for span in (2, 3):  # the first frames aside: no step before them to judge them by
        pairs = [(t, r) for t, r in judged_pairs(content_fps, stream_fps, 4.0, span) if t >= 0.1]
        assert len(pairs) > 20 and all(0.92 <= r <= 1.08 for _, r in pairs), (span, pairs)
        # from 1 s on the mean step is taken over MEAN_STEPS of the picture's steps
        assert all(0.96 <= r <= 1.04 for t, r in pairs if t >= 1.0), (span, pairs)


def test_a_picture_held_is_no_cadence_and_the_step_after_it_lasts_the_hold():
    """A 24 -> 30 fps conversion whose third second holds each picture for 5 frames (a codec keeps a
    still, grainy shot's pictures between key frames 5 frames apart while the picture moves a little):
    the step after a hold lasts the hold, over which its picture's motion gathered, and the hold's runs
    stay out of the mean step, so the conversion after it reads its own steps at once (taken into the
    mean, they made it climb towards 5 intervals and linger over the next 24 steps; the code before fails)."""
    conv = shown(24, 30, 150)
    pics = conv[:60] + [conv[60 + 5 * (j // 5)] for j in range(30)] + conv[90:]
    for span in (2, 3):
        pairs = [(t, r) for t, r in judged_pairs(24, 30, 0, span, pics) if t >= 1.0]
        assert sum(2.0 <= t < 3.0 for t, _ in pairs) >= 6 and sum(t >= 3.0 for t, _ in pairs) > 20, span
        assert all(0.96 <= r <= 1.04 for _, r in pairs), (span, pairs)


def test_a_repeat_every_25th_frame_is_a_picture_held():
    """24 -> 25 fps (one repeat in 25 frames, under MIN_REPEATS) reads as a picture held now and then
    in a stream of its own rate: a repeat lasts nothing, each step its own interval (4 % short)."""
    cad = Cadence(1 / 25, 0.35)
    pairs = [(t, r) for t, r in judged_pairs(24, 25, 4.0, 2) if t >= 0.1]
    assert pairs and all(0.95 <= r <= 1.0 + 1e-9 for _, r in pairs), pairs
    feed(cad, shown(24, 25, 100), 25)
    assert cad.found == 3 and cad.step_s() == pytest.approx(1 / 25)


def test_a_film_that_repeats_pictures_of_its_own_is_timed_by_its_own_steps_at_30_fps():
    """A 24 fps film made 25 fps by repeating one picture a second, then shown at 30 fps: twice a
    second the film's own repeat stands beside one of the conversion's. Both are repeats, and each
    of the film's steps lasts its 1/24 s."""
    film = [j * 24 // 25 for j in range(100)]  # 4 s at 25 fps: the 24 fps picture each of its frames shows
    frames = [film[j * 25 // 30] for j in range(120)]  # the film's picture each 30 fps frame shows
    cad = Cadence(1 / 30, 0.35)
    timed = 0
    for j, k in enumerate(frames):
        cad.add(j / 30, picture(k, step=1))
        a, b = j - REACH - 2, j - REACH
        if j >= 40 and frames[b] > frames[a]:
            assert cad.pair_time(a / 30, b / 30) == pytest.approx((frames[b] - frames[a]) / 24, rel=0.05), j
            timed += 1
    assert timed >= 60
    repeats = sum(1 for a, b in zip(frames[:-1], frames[1:]) if a == b)
    # the first frames have no step before them to be judged by, the last ones none after them yet
    assert repeats - 4 <= cad.found <= repeats


def test_a_pair_is_timed_by_its_successor_as_judged():
    pics = shown(24, 30, 18)  # repeats at frames 6 and 11 (and 1: no step before it to judge it by)
    cad = Cadence(1 / 30, 0.35)
    times = feed(cad, pics[:10], 30)
    assert cad.judged == 0 and cad.settled_s == times[9 - REACH]  # nothing judged: nothing to wait for
    times += feed(cad, pics[10:13], 30, start=10)
    # frames judged, but fewer than MIN_STEPS whole runs: pairs wait up to WAIT_S for the mean step
    assert cad.judged and cad.settled_s == pytest.approx(times[12 - REACH] - WAIT_S)
    times += feed(cad, pics[13:], 30, start=13)
    assert cad.found == 2 and cad.settled_s == times[17 - REACH]
    # each step lasts the mean step (whole runs of the picture: 9 frames in 7), a repeat nothing
    step = cad.step_s()
    assert step == pytest.approx(9 / 7 / 30)
    assert cad.pair_time(times[4], times[6]) == pytest.approx(step)  # frame 6 repeats 5
    assert cad.pair_time(times[6], times[8]) == pytest.approx(2 * step)
    # frames not judged yet (fewer than REACH frames after them): each counts its own interval
    assert cad.pair_time(times[14], times[16]) == pytest.approx(2 / 30)


def test_a_stretch_on_twos_reads_as_its_own_picture_rate():
    pics = [j // 2 for j in range(40)]  # 24 fps, each picture shown twice: a 12 fps picture
    cad = Cadence(1 / 24, 0.35)
    times = feed(cad, pics, 24)
    for a in range(26, 32):  # pairs two frames apart hold one step, 1/12 s, whichever frame they start on
        assert cad.pair_time(times[a], times[a + 2]) == pytest.approx(1 / 12, rel=0.05)


def test_a_cut_or_a_flash_among_the_steps_makes_no_repeats():
    """The level a frame is judged by passes over the largest difference around it: the frames of a
    slow pan after a cut (or around a flash) are steps, not repeats beside the cut's difference."""
    pics = [picture(j, step=1) for j in range(30)] + [255 - picture(j, step=1) for j in range(30, 60)]
    pics[45] = np.full_like(pics[45], 255)  # a flash
    cad = Cadence(1 / 60, 0.35)
    for j, p in enumerate(pics):
        cad.add(j / 60, p)
    assert cad.found == 0
    assert cad.pair_time(40 / 60, 42 / 60) == pytest.approx(2 / 60)


def test_action_beside_a_cut_and_a_flash_makes_no_repeats():
    """Differences of a few grey levels are motion, not coding noise, even where a cut (140) and a
    bright flash (44) within reach on either side make them small beside those (16.4-17.3 s of the
    Sintel trailer: three such frames read as repeats, and its lightning's motion 0.6 x)."""
    diffs = [0, 0, 0, 0, 140, 7, 7, 11, 10, 16, 20, 22, 44, 12, 11, 26, 35, 34, 17, 14, 19, 11]
    levels = np.cumsum([(-1) ** j * d for j, d in enumerate(diffs)]) + 60  # a uniform grey going up and down, 60..233
    cad = Cadence(1 / 24, 0.35)
    for j, v in enumerate(levels):
        cad.add(j / 24, np.full((36, 64), v, np.uint8))
    cad.finish()
    assert cad.judged > 10 and cad.found == 0


def test_a_picture_that_slows_down_or_speeds_up_makes_no_repeats():
    """A pan that drops from 8 columns a frame to 1 (a camera that stops), or rises from 1 to 8: the
    small steps have no large one on one side within reach, so they are steps (judged against the
    largest difference before a frame alone, ten of them read as repeats after the drop)."""
    for steps in ([8] * 20 + [1] * 30, [1] * 30 + [8] * 20):
        cad = Cadence(1 / 24, 0.35)
        feed(cad, list(np.cumsum([0] + steps)), 24, step=1)
        assert cad.found == 0, steps[0]


def test_a_still_a_slow_or_an_uneven_picture_keeps_the_streams_time():
    for pics, step in (([0] * 40, 3), (list(range(40)), 1), ([int(j ** 1.5) for j in range(40)], 1)):
        cad = Cadence(1 / 24, 0.35)
        times = feed(cad, pics, 24, step=step)
        assert cad.found == 0
        assert cad.pair_time(times[10], times[12]) == pytest.approx(2 / 24)


def test_a_picture_at_its_own_rate_after_a_conversion_reads_the_streams_time_again():
    cad = Cadence(1 / 30, 0.35)
    pics = shown(25, 30, 60)
    feed(cad, pics, 30)
    assert cad.step_s() == pytest.approx(1.2 / 30, rel=0.04)
    times = feed(cad, [pics[-1] + 1 + j for j in range(70)], 30, start=60)  # then a picture every frame
    assert cad.step_s() == pytest.approx(1 / 30)
    assert cad.pair_time(times[60], times[62]) == pytest.approx(2 / 30)


def test_a_variable_rate_stream_keeps_its_own_intervals():
    """Frames 0.8-1.4 nominal intervals apart, a picture held one frame longer now and then (a 24 fps
    film made 25 fps, then recorded at a variable rate): a step lasts its own interval, a repeat
    nothing (the mean step of a constant-rate conversion would stretch every step by 8 frames in 7)."""
    rng = np.random.default_rng(2)
    times = np.cumsum(rng.uniform(0.8, 1.4, 60)) / 24
    pics = [j - j // 8 for j in range(60)]  # frames 8, 16, ... repeat the frame before
    cad = Cadence(1 / 24, 0.35, variable=True)
    for t, k in zip(times, pics):
        cad.add(float(t), picture(k, step=1))
    assert cad.found >= 4 and cad.judged > 40
    for a in (38, 40, 44):  # pairs of 3 frames, one of them a repeat (frames 40 and 48) or none
        steps = sum(times[j] - times[j - 1] for j in range(a + 1, a + 4) if pics[j] != pics[j - 1])
        assert cad.pair_time(times[a], times[a + 3]) == pytest.approx(steps), a


def test_off_or_without_a_frame_rate_the_pair_time_is_the_span():
    for cad in (Cadence(1 / 30, 0.0), Cadence(0.0, 0.35)):
        times = feed(cad, shown(25, 30, 40), 30)
        assert cad.found == 0
        assert cad.pair_time(times[4], times[6]) == pytest.approx(2 / 30)


@settings(max_examples=60, deadline=None)
@given(st.lists(st.tuples(st.integers(0, 40), st.integers(1, 8)), min_size=3, max_size=40), st.floats(0.0, 1.0),
       st.integers(0, 79), st.integers(1, 5))
def test_a_pair_time_is_positive_and_at_most_the_longest_step_per_frame_of_its_span(runs, ratio, a, span):
    """Pictures shown for 1-8 frames each: runs of repeats, pictures held among them (the step after a hold
    lasts the hold, and a run is judged whole only with a step within ``REACH`` frames of each repeat)."""
    pics = [k for k, n in runs for _ in range(n)][:80]
    cad = Cadence(1 / 30, ratio)
    times = feed(cad, pics, 30)
    a = min(a, len(times) - 1)
    b = min(a + span, len(times) - 1)
    t = cad.pair_time(times[a], times[b])
    assert 0 < t <= max(times[b] - times[a], 1e-3) * MAX_STEP_FRAMES + 1e-12
