"""ChairPlayer and push against the compiled virtual chair: the chair's log must hold the
timeline's frames (after comfort and clamps), in order, consecutive; seek, pause, STOP, the
latency offset and ranges behave."""

from __future__ import annotations

import math
import threading

import numpy as np
import pytest

from autohaptics.chair import ChairLink, ChairPlayer, Comfort, VirtualChair, push
from autohaptics.errors import CancelledError, DeviceError, ParameterError
from autohaptics.timeline import Timeline

ARMRESTS = (2, 6)  # A3, A7


@pytest.fixture
def link(chair):
    lk = ChairLink(chair.device)
    lk.connect()
    yield lk
    lk.close()


def _timeline(n: int, seed: int = 0) -> Timeline:
    rng = np.random.default_rng(seed)
    tl = Timeline.empty(n)
    tl.vibration[:] = rng.random((n, 9))
    tl.fans[:] = rng.random((n, 9, 17)) * (rng.random((n, 9, 17)) > 0.5)
    tl.temperature_c[:] = rng.uniform(30.0, 55.0, n)
    return tl.validate()


def _expected(tl: Timeline, k: int, intensity: float, muted_motors=(), neutral=33.0, lo=18.0, hi=40.0):
    """The documented quantisation, written out independently of autohaptics.chair.comfort."""
    vib = tl.vibration[k].astype(np.float64) * intensity
    motors = [0 if i in muted_motors else int(math.floor(min(max(v, 0.0), 1.0) * 255 + 0.5)) for i, v in enumerate(vib)]
    fans = [int(math.floor(min(max(v * intensity, 0.0), 1.0) * 255 + 0.5)) for v in tl.fans[k].astype(np.float64).ravel()]
    t = min(max(neutral + intensity * (float(tl.temperature_c[k]) - neutral), lo), hi)
    return motors, fans, int(math.floor(t * 100 + 0.5))


def _ticks(chair: VirtualChair) -> list[int]:
    return [e["tick"] for e in chair.frames()]


def _wait_stops(chair: VirtualChair, n: int) -> None:
    """The chair has processed everything up to the n-th STOP (frames before it are logged)."""
    chair.wait_for(lambda e: e["ev"] == "stop", count=n)


def _missing(ticks: list[int], start: int) -> int:
    """Ticks absent from a segment that should run from ``start``; the segment must be strictly
    increasing (no duplicates, in order). Under normal timing this is 0; after a stall of the
    host the player jumps ahead and counts the jump in ``ticks_skipped``, so the tests check
    that every missing tick is accounted for there."""
    assert ticks and ticks[0] >= start
    assert all(b > a for a, b in zip(ticks, ticks[1:])), ticks
    return (ticks[0] - start) + sum(b - a - 1 for a, b in zip(ticks, ticks[1:]))


def _segments(ticks: list[int], min_jump: int = 50) -> list[list[int]]:
    """Split where a seek moved the tick backwards or far ahead."""
    out = [[ticks[0]]]
    for a, b in zip(ticks, ticks[1:]):
        if b <= a or b - a > min_jump:
            out.append([])
        out[-1].append(b)
    return out


def test_stream_holds_the_timeline_after_comfort_and_clamps(link, chair):
    tl = _timeline(15)
    comfort = Comfort(intensity=0.7, mute=frozenset({"armrests"}))
    status = push(link, tl, comfort=comfort)
    assert status.state == "ended" and status.frames_sent + status.ticks_skipped == 15
    stop = chair.wait_for(lambda e: e["ev"] == "stop")
    frames = chair.frames()
    ticks = [e["tick"] for e in frames]
    assert _missing(ticks, 0) == status.ticks_skipped  # in order, no duplicates, gaps only if stalled
    assert ticks[-1] == 14 or status.ticks_skipped > 0
    assert [e["seq"] for e in frames] == list(range(1, len(frames) + 1))
    for e in frames:
        motors, fans, temp_cc = _expected(tl, e["tick"], 0.7, ARMRESTS)
        assert e["motors"] == motors
        assert e["fans"] == fans
        assert e["temp_target_cc"] == temp_cc
        assert 1800 <= e["temp_target_cc"] <= 4000
    assert stop["t_ms"] > frames[-1]["t_ms"] and stop["motors"] == [0] * 9


def test_heat_mute_sends_neutral_and_full_scale_is_exact(link, chair):
    tl = _timeline(4, seed=3)
    tl.vibration[0] = 1.0
    tl.temperature_c[:] = 55.0
    push(link, tl, comfort=Comfort(mute=frozenset({"heat", "fans"})))
    _wait_stops(chair, 1)
    frames = chair.frames()
    assert frames[0]["tick"] == 0 and frames[0]["motors"] == [255] * 9
    assert all(e["temp_target_cc"] == 3300 and e["fans"] == [0] * 153 for e in frames)
    push(link, tl)  # unmuted: 55 C is clamped to the chair's 40 C maximum
    _wait_stops(chair, 2)
    assert [e["temp_target_cc"] for e in chair.frames()[len(frames):]] == [4000] * len(chair.frames()[len(frames):])
    assert len(chair.frames()) > len(frames)


def test_seek_jumps_and_ticks_stay_consecutive(link, chair):
    tl = _timeline(300, seed=1)
    with ChairPlayer(link, tl) as player:
        player.play(0.0)
        chair.wait_for(lambda e: e["ev"] == "frame" and e["tick"] >= 3)
        player.seek(12.0)
        chair.wait_for(lambda e: e["ev"] == "frame" and e["tick"] >= 124)
        player.seek(2.0)  # backwards
        chair.wait_for(lambda e: e["ev"] == "frame" and 22 <= e["tick"] < 100)
        player.pause()
        skipped = player.status().ticks_skipped
    _wait_stops(chair, 1)
    segments = _segments(_ticks(chair))
    assert len(segments) == 3 and segments[0][-1] < 20
    missing = sum(_missing(seg, start) for seg, start in zip(segments, (0, 120, 20)))
    assert missing == skipped  # 0 under normal timing
    assert chair.read_log()[-1]["ev"] == "stop"  # pause turned the outputs off


def test_pause_holds_and_play_resumes_from_the_same_place(link, chair):
    tl = _timeline(300, seed=2)
    with ChairPlayer(link, tl) as player:
        player.play(5.0)
        chair.wait_for(lambda e: e["ev"] == "frame" and e["tick"] >= 53)
        player.pause()
        paused_at = player.position_s
        stop = chair.wait_for(lambda e: e["ev"] == "stop")
        n_before = len(chair.frames())
        assert player.wait(0.0)  # not playing
        assert player.state == "paused" and player.position_s == paused_at
        threading.Event().wait(0.4)  # paused: nothing is sent, the chair stays off
        assert len(chair.frames()) == n_before
        before = _ticks(chair)
        player.play()
        chair.wait_for(lambda e: e["ev"] == "frame" and e["t_ms"] > stop["t_ms"] and e["tick"] >= before[-1] + 2)
        player.pause()
        skipped = player.status().ticks_skipped
    after = _ticks(chair)[n_before:]
    resume_tick = math.floor(paused_at / 0.1 + 1e-9)  # play() resumes at the paused position
    assert resume_tick >= before[-1]
    assert _missing(before, 50) + _missing(after, resume_tick) == skipped  # 0 under normal timing
    assert [e["ev"] for e in chair.read_log()].count("safe") == 0  # STOP, not the watchdog


def test_stop_turns_everything_off_at_once(link, chair):
    tl = Timeline.empty(200)
    tl.vibration[:] = 1.0
    tl.fans[:] = 1.0
    tl.temperature_c[:] = 40.0
    with ChairPlayer(link, tl) as player:
        player.play(0.0)
        chair.wait_for(lambda e: e["ev"] == "frame" and e["tick"] >= 3)
        player.stop()
        assert player.state == "stopped"
        stop = chair.wait_for(lambda e: e["ev"] == "stop")
        threading.Event().wait(0.25)  # more than two ticks: a frame sent after STOP would show
    st = link.request_status()  # answered after every earlier byte: the log is complete up to here
    assert st.safe and st.stopped
    log = chair.read_log()
    i = log.index(stop)
    assert log[i - 1]["ev"] == "frame" and log[i - 1]["motors"] == [255] * 9  # on until the STOP ...
    assert stop["motors"] == [0] * 9 and stop["fans"] == [0] * 153 and stop["temp_target_cc"] == 3300
    assert all(e["ev"] != "frame" for e in log[i:])  # ... and nothing after it


@pytest.mark.parametrize("offset_ms,first_tick", [(300, 23), (-300, 17), (0, 20)])
def test_latency_offset_shifts_the_tick_sent(link, chair, offset_ms, first_tick):
    tl = _timeline(100, seed=4)
    with ChairPlayer(link, tl, latency_offset_ms=offset_ms) as player:
        player.play(2.0)
        chair.wait_for(lambda e: e["ev"] == "frame")
        player.pause()
        status = player.status()
    assert status.latency_offset_ms == offset_ms
    assert first_tick <= _ticks(chair)[0] <= first_tick + status.ticks_skipped  # == unless the host stalled


def test_latency_offset_and_positions_are_validated(link):
    with pytest.raises(ParameterError, match="-500..500 ms"):
        ChairPlayer(link, latency_offset_ms=600)
    with ChairPlayer(link) as player:
        with pytest.raises(ParameterError, match="no timeline loaded"):
            player.play(0.0)
        with pytest.raises(ParameterError, match="-500..500 ms"):
            player.set_latency_offset_ms(float("nan"))
        with pytest.raises(ParameterError, match="position"):
            player.seek(-1.0)


def test_push_range_and_end_of_timeline(link, chair):
    tl = _timeline(20, seed=5)
    status = push(link, tl, start_s=0.5, end_s=1.2)
    assert status.state == "ended" and status.frames_sent + status.ticks_skipped == 7
    _wait_stops(chair, 1)
    first = _ticks(chair)
    assert _missing(first, 5) == status.ticks_skipped and first[-1] <= 11
    with ChairPlayer(link, tl) as player:
        player.play(1.5)
        assert player.wait(3.0) and player.state == "ended"
        assert player.position_s == pytest.approx(2.0)
        status = player.status()
    _wait_stops(chair, 2)
    second = _ticks(chair)[len(first):]
    assert _missing(second, 15) == status.ticks_skipped and second[-1] <= 19
    assert status.frames_sent + status.ticks_skipped == 5
    assert chair.read_log()[-1]["ev"] == "stop"


def test_push_errors_and_cancel(link, chair, sim_binary):
    tl = _timeline(50, seed=6)
    with pytest.raises(ParameterError, match="push range is empty"):
        push(link, tl, start_s=3.0, end_s=2.0)
    cancel = threading.Event()
    timer = threading.Timer(0.35, cancel.set)
    timer.start()
    with pytest.raises(CancelledError):
        push(link, tl, cancel=cancel)
    timer.join()
    assert chair.wait_for(lambda e: e["ev"] == "stop")
    assert 2 <= len(chair.frames()) < 50
    closed = ChairLink(link.port)
    with pytest.raises(DeviceError, match="not connected"):
        push(closed, tl)


def test_status_snapshot_is_json_ready(link):
    import json

    tl = _timeline(3)
    with ChairPlayer(link, tl, comfort=Comfort(intensity=0.5)) as player:
        player.play(0.0)
        player.wait(2.0)
        d = player.status().to_dict()
    json.dumps(d)
    assert d["state"] == "ended" and d["frames_sent"] + d["ticks_skipped"] == 3 and d["error"] is None
    assert d["comfort"] == {"intensity": 0.5, "mute": []}
    assert d["link"]["connected"] and d["link"]["capabilities"]["name"] == "virtual-chair"
