"""The video pass's flow pairs (``pipeline.pairs``): flows computed beside the pass give the analysis
of flows computed at once, the pairs are stored in the order they came, a failure in the worker
reaches the pass, and the worker ends with it."""

from __future__ import annotations

import threading

import numpy as np
import pytest

from autohaptics import testing as synth
from autohaptics.airflow import cuts, depth
from autohaptics.airflow.fans import AirflowParams
from autohaptics.airflow.flow import FlowParams
from autohaptics.airflow.pair import PairParams, pair_motion
from autohaptics.errors import CancelledError
from autohaptics.params import GenerateParams, apply_overrides
from autohaptics.pipeline import pairs, video_pass
from autohaptics.pipeline.pairs import PairJudge
from autohaptics.media import probe
from autohaptics.timebase import n_ticks


@pytest.fixture(scope="module")
def film(tmp_path_factory):
    return synth.write_scene(tmp_path_factory.mktemp("pairs") / "moving.mp4", synth.sample_scene(),
                             width=320, height=180, fps=24, audio=False)


def _flow_threads() -> list[threading.Thread]:
    return [t for t in threading.enumerate() if t.name == "autohaptics-flow"]


def _pass(path, params: GenerateParams, **kw):
    info = probe(path)
    n = n_ticks(info.duration_s)
    return video_pass(info, n, params=params, need_saliency=np.zeros(n, bool), need_flow=True, need_colour=True, **kw)


@pytest.mark.parametrize("analysis", ["tick", "every"])
def test_flows_beside_the_pass_give_the_analysis_of_flows_computed_at_once(film, monkeypatch, analysis):
    """'every' judges several pairs per tick: their sums are added in the same order either way."""
    params = apply_overrides(GenerateParams(), {"video.analysis": analysis})
    got = {}
    for beside in (False, True, None):
        monkeypatch.setattr(PairJudge, "beside", beside)
        got[beside] = _pass(film, params)
    at_once = got[False]
    assert at_once.flow_mask.any() and at_once.depth_mask.any() and at_once.static.any()
    for beside in (True, None):
        for key, value in at_once.arrays().items():
            np.testing.assert_array_equal(value, got[beside].arrays()[key], err_msg=f"{beside}: {key}")
        assert got[beside].stats["flow"]["computed"] == at_once.stats["flow"]["computed"] > 0
    assert not _flow_threads()


def _moving(seed: int, shift: int) -> np.ndarray:
    texture = np.random.default_rng(seed).integers(0, 256, (90, 200), dtype=np.uint8)
    return np.ascontiguousarray(texture[:, shift:shift + 160])


def test_pairs_are_stored_in_the_order_they_came_whether_or_not_their_flow_waits():
    params = PairParams(flow=FlowParams(), airflow=AirflowParams(), cuts=cuts.CutParams(), depth=depth.DepthParams(),
                        floor=0.0, skip=True)
    rgb = np.zeros((90, 160, 3), np.uint8)
    still = _moving(1, 0)
    pairs_in = [(k, _moving(k, 0), _moving(k, 1 + k % 5)) if k % 3 else (k, still, still.copy()) for k in range(24)]
    expected = [(k, pair_motion(a, b, rgb, None, lambda: None, 0.04, params=params)) for k, a, b in pairs_in]
    stored = []
    judge = PairJudge(params, lambda k, res: stored.append((k, res)), timer=lambda name, fn, *a, **kw: fn(*a, **kw),
                      luma_signature=cuts.frame_signature)
    for i, (k, a, b) in enumerate(pairs_in):
        judge.add(k, a, b, rgb, None, lambda: None, 0.04, ahead=i % 4 != 3)  # most beside, some at once
        assert sum(e[2] is not None for e in judge._order) <= pairs.MOST_WAITING
    judge.finish()
    assert [k for k, _ in stored] == [k for k, _ in expected]
    for (_, got), (_, want) in zip(stored, expected):
        assert (got.cut, got.static, got.score) == (want.cut, want.static, want.score)
        np.testing.assert_array_equal(got.cells, want.cells)
        np.testing.assert_array_equal(got.near, want.near)
    assert any(not r.static for _, r in stored) and any(r.static for _, r in stored)
    assert not _flow_threads()


def test_a_failure_in_the_worker_reaches_the_pass_and_the_worker_ends(film, monkeypatch):
    def broken(*args, **kwargs):
        raise MemoryError("no room for the flow")

    monkeypatch.setattr(PairJudge, "beside", True)
    monkeypatch.setattr(pairs, "optical_flow", broken)
    with pytest.raises(MemoryError, match="no room for the flow"):
        _pass(film, GenerateParams())
    for t in _flow_threads():
        t.join(5)
    assert not _flow_threads()


def test_a_pass_cancelled_while_flows_wait_leaves_no_worker(film, monkeypatch):
    monkeypatch.setattr(PairJudge, "beside", True)
    cancel = threading.Event()
    started = []

    def progress(stage, fraction):
        started.extend(_flow_threads())
        if fraction > 0.3:
            cancel.set()

    with pytest.raises(CancelledError):
        _pass(film, GenerateParams(), cancel=cancel, progress=progress)
    assert started  # the worker ran when the cancel came
    for t in _flow_threads():
        t.join(5)
    assert not _flow_threads()
