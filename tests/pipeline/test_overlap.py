"""The audio pass beside the video pass (a forked child, the saliency decisions in frame order):
the same analysis as one pass after the other, its errors and cancellation, the queue that holds
the analysed frames until the audio says which ticks need saliency, and the file's hash computed
beside the passes."""

from __future__ import annotations

import dataclasses
import os
import signal
import threading
import time

import numpy as np
import psutil
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from autohaptics import testing as synth
from autohaptics.errors import CancelledError, MediaError
from autohaptics.params import GenerateParams
import importlib
from autohaptics.pipeline import analyse
from autohaptics.pipeline import saliency_queue
from autohaptics.pipeline.child import Child
from autohaptics.pipeline.saliency_queue import LaterMask, SaliencyQueue

analyse_module = importlib.import_module("autohaptics.pipeline.analyse")  # the package exports the function


@pytest.fixture(scope="module")
def film(tmp_path_factory):
    return synth.write_scene(tmp_path_factory.mktemp("overlap") / "av.mp4", synth.sample_scene(),
                             width=320, height=180, fps=24)


@pytest.fixture(autouse=True)
def no_child_left():
    """Every test here leaves no child process of its own behind, running or unreaped."""
    before = {p.pid for p in psutil.Process().children()}
    yield
    left = [p for p in psutil.Process().children() if p.pid not in before]
    assert not left, f"child processes left: {left}"


def _same(a, b) -> None:
    assert a.stats["video"].keys() == b.stats["video"].keys()
    for name in ("audio", "video"):
        x, y = getattr(a, name), getattr(b, name)
        pairs = x.items() if isinstance(x, dict) else x.arrays().items()
        for key, value in pairs:
            other = y[key] if isinstance(y, dict) else getattr(y, key)
            np.testing.assert_array_equal(value, other, err_msg=f"{name}.{key}")


@pytest.mark.parametrize("waiting_bytes", [None, 1])
def test_the_passes_side_by_side_give_the_analysis_of_one_after_the_other(film, monkeypatch, waiting_bytes):
    """With 1 byte of room every analysed frame before the audio's mask is weighed at once."""
    side = analyse(film, GenerateParams())
    assert "audio" in side.stats and side.video.saliency_mask.any() and not side.video.saliency_mask.all()
    if waiting_bytes is not None:
        monkeypatch.setattr(saliency_queue, "MAX_WAITING_BYTES", waiting_bytes)
        side = analyse(film, GenerateParams())
    monkeypatch.setattr(analyse_module, "can_fork", lambda: False)
    _same(side, analyse(film, GenerateParams()))


@pytest.mark.parametrize("motion_weight", [0.0, 0.4])
def test_a_late_mask_gives_the_same_analysis(film, monkeypatch, motion_weight):
    """The audio's mask comes after the video pass has analysed frames beyond the room for their
    proxies (a long film's): without saliency's motion cue those frames are weighed at once, some
    for nothing; with it (each frame's map depends on the one weighed before) the pass waits for
    the mask. Either way the analysis is the one of the passes in turn."""
    params = GenerateParams()
    params = dataclasses.replace(params, saliency=dataclasses.replace(params.saliency, motion_weight=motion_weight))
    parent, real = os.getpid(), analyse_module._audio_pass

    def late_audio(*args, **kwargs):
        if os.getpid() != parent:
            time.sleep(1.5)  # the video pass of the 320 x 180 film runs ahead meanwhile
        return real(*args, **kwargs)

    monkeypatch.setattr(analyse_module, "_audio_pass", late_audio)
    monkeypatch.setattr(saliency_queue, "MAX_WAITING_BYTES", 1)
    side = analyse(film, params)
    sal = side.video.stats["saliency"]
    if motion_weight == 0.0:
        assert sal["weighed_ahead"] > 0 and 0 < sal["unused"] < sal["weighed_ahead"]
    else:
        assert sal["weighed_ahead"] == 0 == sal["unused"]
    monkeypatch.setattr(analyse_module, "can_fork", lambda: False)
    alone = analyse(film, params)
    assert alone.video.stats["saliency"]["weighed_ahead"] == 0
    _same(side, alone)


def test_an_audio_failure_stops_the_analysis_with_its_own_error(film, monkeypatch):
    def broken(*args, **kwargs):
        raise MediaError("the sound cannot be decoded")

    monkeypatch.setattr(analyse_module, "_audio_pass", broken)  # the forked child runs this one
    t0 = time.monotonic()
    with pytest.raises(MediaError, match="the sound cannot be decoded"):
        analyse(film, GenerateParams())
    assert time.monotonic() - t0 < 30


def test_a_killed_child_leaves_the_passes_to_run_in_turn(film, monkeypatch):
    """A child killed from outside (out of memory, an operator) is no failure of the film: the
    passes run again one after the other, with the same analysis."""
    parent, real = os.getpid(), analyse_module._audio_pass

    def dies_in_the_child(*args, **kwargs):
        if os.getpid() != parent:
            os.kill(os.getpid(), signal.SIGKILL)
        return real(*args, **kwargs)

    expected = analyse(film, GenerateParams())
    monkeypatch.setattr(analyse_module, "_audio_pass", dies_in_the_child)
    _same(expected, analyse(film, GenerateParams()))


def test_a_cancel_stops_both_passes(film, monkeypatch):
    slow = analyse_module._audio_pass

    def slow_audio(*args, **kwargs):
        time.sleep(60)  # the child is still busy when the cancel comes
        return slow(*args, **kwargs)

    monkeypatch.setattr(analyse_module, "_audio_pass", slow_audio)
    cancel = threading.Event()
    threading.Timer(0.5, cancel.set).start()
    t0 = time.monotonic()
    with pytest.raises(CancelledError):
        analyse(film, GenerateParams(), cancel=cancel)
    assert time.monotonic() - t0 < 10


def test_progress_goes_one_way_and_ends_done(film):
    seen = []
    analyse(film, GenerateParams(), progress=lambda stage, f: seen.append(f))
    assert seen == sorted(seen) and seen[-1] == 1.0 and len(seen) > 3


def test_a_child_sends_progress_and_its_value_back():
    got = []
    with Child(lambda report: [report(i / 4) for i in range(5)] and os.getpid(),
               on_progress=got.append) as child:
        pid = child.result()
    assert pid != os.getpid() and got == [0.0, 0.25, 0.5, 0.75, 1.0]


def test_the_child_never_finalises_the_parents_garbage(tmp_path):
    """The parent's objects are frozen across the fork: a reference cycle that is garbage in the
    parent (e.g. a decoded frame, whose FFmpeg threads live only in the parent) is finalised there,
    never by a collection in the child."""
    import gc

    log = tmp_path / "finalised"

    class Node:
        def __del__(self):
            with open(log, "a") as f:
                f.write(f"{os.getpid()}\n")

    enabled = gc.isenabled()
    gc.disable()  # the cycle stays uncollected until the child has run
    try:
        a, b = Node(), Node()
        a.other, b.other = b, a
        del a, b
        with Child(lambda report: gc.collect() >= 0 and os.getpid()) as child:
            child_pid = child.result()
        assert not log.exists() or str(child_pid) not in log.read_text().split()
        gc.collect()
    finally:
        if enabled:
            gc.enable()
    assert log.read_text().split() == [str(os.getpid())] * 2


def _frame(k: int) -> np.ndarray:
    return np.full((2, 2, 3), k % 256, np.uint8)


def _weigh(width: int, rgb: np.ndarray, luma) -> int:
    """A frame's stand-in weights: its own value (the tick it was made for, mod 256)."""
    return int(rgb[0, 0, 0])


def _decisions(need, stride: int, ticks: list[int], later_at: int | None, max_bytes: int | None,
               ahead: bool = False):
    """The frames a queue commits, in order, each with the weights of its own frame, the mask given
    up front or set after ``later_at`` frames; and the queue."""
    committed = []
    mask = LaterMask() if later_at is not None else need
    queue = SaliencyQueue(mask, _weigh, lambda k, weights: committed.append((k, weights)),
                          stride=stride, max_bytes=max_bytes, ahead=ahead)
    for i, k in enumerate(ticks):
        if later_at is not None and i == later_at:
            mask.set(need)
        queue.add(k, 2, _frame(k), None)
    if later_at is not None and later_at >= len(ticks):
        threading.Timer(0.05, mask.set, args=(need,)).start()  # set only while finish waits
    queue.finish(len(need))
    return committed, queue


@settings(max_examples=200, deadline=None)
@given(data=st.data(), stride=st.integers(1, 4), n=st.integers(1, 60))
def test_the_queue_decides_alike_whenever_the_mask_comes(data, stride, n):
    """A frame is committed when a tick from it up to the next analysed frame needs saliency,
    whether the mask is known up front, comes after some frames, or only at the end; and when the
    waiting frames outgrow their room the queue waits for the mask instead (set by another thread),
    or, ``ahead``, weighs them at once: the same frames get the same weights, in the same order."""
    need = np.array(data.draw(st.lists(st.booleans(), min_size=n, max_size=n)), bool)
    starts = list(range(0, n, stride))
    ticks = sorted(data.draw(st.sets(st.sampled_from(starts), min_size=1)))
    up_front, _ = _decisions(need, stride, ticks, None, None)
    expected = [(k, k % 256) for i, k in enumerate(ticks)
                if need[k:max(ticks[i + 1] if i + 1 < len(ticks) else n, k + stride)].any()]
    assert up_front == expected
    later_at = data.draw(st.integers(0, len(ticks)))
    assert _decisions(need, stride, ticks, later_at, None)[0] == expected
    committed, queue = _decisions(need, stride, ticks, later_at, 1, ahead=True)
    assert committed == expected
    # every frame that came before the mask was weighed then; those it did not need were spent
    assert queue.weighed_ahead == min(later_at, len(ticks)) and queue.unused == queue.weighed_ahead - sum(
        1 for k, _ in expected if ticks.index(k) < later_at)
    mask = LaterMask()
    threading.Timer(0.02, mask.set, args=(need,)).start()
    committed = []
    queue = SaliencyQueue(mask, _weigh, lambda k, weights: committed.append((k, weights)), stride=stride, max_bytes=1)
    for k in ticks:
        queue.add(k, 2, _frame(k), None)
    queue.finish(n)
    assert committed == expected


def test_a_queue_that_weighs_ahead_never_waits_for_the_mask():
    """Frames beyond the room are weighed at once and the video pass goes on: the mask is set only
    after every frame was added (a queue that waited would be cancelled instead)."""
    mask, cancel = LaterMask(), threading.Event()
    timer = threading.Timer(30.0, cancel.set)
    timer.start()
    try:
        weighed = []
        queue = SaliencyQueue(mask, lambda w, rgb, luma: weighed.append(int(rgb[0, 0, 0])) or len(weighed),
                              lambda k, weights: None, max_bytes=3 * _frame(0).nbytes, ahead=True, cancel=cancel)
        for k in range(100):
            queue.add(k, 2, _frame(k), None)
        assert mask.value is None and not cancel.is_set()
        # at most the room's worth of frames waits with its proxies at any time
        assert len(weighed) >= 100 - 4 and queue.weighed_ahead == len(weighed)
        mask.set(np.zeros(100, bool))
        queue.finish(100)
        assert queue.unused == queue.weighed_ahead
    finally:
        timer.cancel()


def test_a_mask_abandoned_by_a_failed_pass_stops_the_queue():
    mask = LaterMask()
    queue = SaliencyQueue(mask, lambda *a: None, lambda *a: None, max_bytes=1)
    threading.Timer(0.05, mask.close).start()
    with pytest.raises(saliency_queue.AbandonedMask):
        queue.add(0, 2, np.zeros((2, 2, 3), np.uint8), None)
        queue.add(1, 2, np.zeros((2, 2, 3), np.uint8), None)


def test_the_hash_of_the_file_runs_beside_the_passes(film, monkeypatch):
    """The video pass starts while the file's SHA-256 is still being computed (a film of tens of GB
    takes a minute to hash), and the analysis still carries the file's own hash."""
    import hashlib

    video_started, seen = threading.Event(), []
    real_hash, real_pass = analyse_module.file_sha256, analyse_module._video_pass

    def slow_hash(path, **kwargs):
        seen.append(video_started.wait(20))  # True: the pass began before the hash ended
        return real_hash(path, **kwargs)

    def video_pass(*args, **kwargs):
        video_started.set()
        return real_pass(*args, **kwargs)

    monkeypatch.setattr(analyse_module, "file_sha256", slow_hash)
    monkeypatch.setattr(analyse_module, "_video_pass", video_pass)
    result = analyse(film, GenerateParams())
    assert seen == [True]
    assert result.sha256 == hashlib.sha256(film.read_bytes()).hexdigest()
    assert result.stats["hash"]["seconds"] >= 0


def test_a_failed_analysis_stops_the_hash(film, monkeypatch):
    """An analysis that fails leaves no hashing thread behind: it stops at its next chunk."""
    chunks = []

    def endless_hash(path, *, stop, **kwargs):
        while not stop.wait(0.01):
            chunks.append(1)
        return ""

    def broken(*args, **kwargs):
        while not chunks:
            time.sleep(0.01)
        raise MediaError("the picture cannot be decoded")

    monkeypatch.setattr(analyse_module, "file_sha256", endless_hash)
    monkeypatch.setattr(analyse_module, "_passes", broken)
    with pytest.raises(MediaError, match="cannot be decoded"):
        analyse(film, GenerateParams())
    assert not [t for t in threading.enumerate() if t.name == "autohaptics-hash"]
