"""Error metrics between timelines (autohaptics.metrics) and ``autohaptics compare``: known answers."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from autohaptics import metrics as M
from autohaptics.bench.common import machine, machine_line
from autohaptics.cli.main import main
from autohaptics.errors import ParameterError
from autohaptics.timeline import Timeline


def _tl(n: int, sha: str = "abc") -> Timeline:
    return Timeline.empty(n, source={"name": "x.mp4", "sha256": sha, "duration_s": n / 10})


# ------------------------------------------------------------------------ onsets
def test_onsets_mark_rises_from_zero_and_tick_zero_when_already_on():
    x = np.array([0.5, 0.5, 0.0, 0.2, 0.0, 0.0, 0.1])
    np.testing.assert_array_equal(np.flatnonzero(M.onsets(x)), [0, 3, 6])
    grid = np.zeros((5, 2))
    grid[2:4, 1] = 0.3
    np.testing.assert_array_equal(M.onsets(grid), [[0, 0], [0, 0], [0, 1], [0, 0], [0, 0]])


def test_onsets_reject_three_dimensional_input():
    with pytest.raises(ParameterError, match="shape"):
        M.onsets(np.zeros((3, 2, 2)))


@pytest.mark.parametrize("ref, test, tol, expected", [
    ([10], [11], 1, 1),
    ([10], [12], 1, 0),
    ([10], [12], 2, 1),
    ([10, 11], [11], 1, 1),  # one test onset serves one reference onset only
    ([10, 12], [11, 13], 1, 2),  # greedy earliest-free keeps both (11->10, 13->12)
    ([5, 6, 7], [4, 6, 8], 1, 3),
    ([], [3], 1, 0),
    ([3], [], 1, 0),
    ([30, 10, 20], [21, 9, 31], 1, 3),  # any order
])
def test_match_onsets(ref, test, tol, expected):
    assert M.match_onsets(np.array(ref), np.array(test), tolerance=tol) == expected
    # matching is symmetric in size
    assert M.match_onsets(np.array(test), np.array(ref), tolerance=tol) == expected


def test_onset_scores_known_answer():
    n = 40
    ref, test = np.zeros((n, 9)), np.zeros((n, 9))
    # A1: onsets at 5 and 20 in ref; test has 6 (match) and 30 (spurious)
    ref[5:8, 0] = 0.4
    ref[20:22, 0] = 0.9
    test[6:8, 0] = 0.4
    test[30, 0] = 0.2
    # A5: ref onset at 10, test onset at 12 (outside +-1) -> miss + spurious
    ref[10:15, 4] = 1.0
    test[12:15, 4] = 1.0
    s = M.onset_scores(ref, test)
    assert (s["matched"], s["ref_onsets"], s["test_onsets"]) == (1, 3, 3)
    assert s["precision"] == pytest.approx(1 / 3) and s["recall"] == pytest.approx(1 / 3)
    assert s["f1"] == pytest.approx(1 / 3)
    a1 = s["per_actuator"][0]
    assert (a1["matched"], a1["ref_onsets"], a1["test_onsets"]) == (1, 2, 2) and a1["f1"] == pytest.approx(0.5)
    assert s["per_actuator"][1] == {"precision": 1.0, "recall": 1.0, "f1": 1.0, "matched": 0, "ref_onsets": 0,
                                    "test_onsets": 0}
    assert M.onset_scores(ref, test, tolerance=2)["matched"] == 2


def test_prf_edge_cases():
    assert M.prf(0, 0, 0) == {"precision": 1.0, "recall": 1.0, "f1": 1.0}
    assert M.prf(0, 3, 0) == {"precision": 0.0, "recall": 0.0, "f1": 0.0}
    assert M.prf(0, 0, 2) == {"precision": 0.0, "recall": 0.0, "f1": 0.0}
    assert M.prf(2, 4, 2) == pytest.approx({"precision": 1.0, "recall": 0.5, "f1": 2 / 3})


# ------------------------------------------------------------------- MAE / fans
def test_mae_and_max_on_common_ticks():
    a = np.array([0.0, 0.5, 1.0, 1.0])
    b = np.array([0.1, 0.5, 0.7])
    assert M.mae(a, b) == pytest.approx((0.1 + 0.0 + 0.3) / 3)
    assert M.max_abs_error(a, b) == pytest.approx(0.3)
    assert M.mae(np.zeros(0), np.zeros(3)) == 0.0


def test_mae_rejects_mismatched_shapes_and_non_finite_values():
    with pytest.raises(ParameterError, match="shape"):
        M.mae(np.zeros((3, 9)), np.zeros((3, 8)))
    with pytest.raises(ParameterError, match="non-finite"):
        M.mae(np.zeros(3), np.array([0.0, np.nan, 0.0]))


def test_fan_iou_known_answer():
    a, b = np.zeros((4, 9, 17)), np.zeros((4, 9, 17))
    a[1, 0, 0:4] = 0.5  # 4 cells
    b[1, 0, 2:6] = 0.7  # 4 cells, 2 shared -> IoU 2/6
    a[2, 3, 3] = 1.0  # only ref -> IoU 0
    # tick 0 and 3: neither blows -> not counted
    r = M.fan_iou(a, b)
    assert r["ticks"] == 2 and r["ref_ticks_on"] == 2 and r["test_ticks_on"] == 1
    assert r["iou"] == pytest.approx((2 / 6 + 0) / 2)
    assert r["iou_pooled"] == pytest.approx(2 / 7)
    assert M.fan_iou(a, a)["iou"] == 1.0
    assert (r["ticks_both_on"], r["iou_both_on"]) == (1, pytest.approx(2 / 6))
    assert (r["ticks_precision"], r["ticks_recall"], r["ticks_f1"]) == (1.0, 0.5, pytest.approx(2 / 3))
    assert M.fan_iou(np.zeros((3, 9, 17)), np.zeros((3, 9, 17))) == {
        "iou": 1.0, "iou_pooled": 1.0, "ticks": 0, "ref_ticks_on": 0, "test_ticks_on": 0, "ticks_precision": 1.0,
        "ticks_recall": 1.0, "ticks_f1": 1.0, "ticks_both_on": 0, "iou_both_on": 1.0, "iou_tolerant": 1.0,
        "iou_tolerant_pooled": 1.0, "iou_tolerant_both_on": 1.0, "tolerance_cells": 1}
    # a level threshold: cells at 0.5 no longer count as on
    assert M.fan_iou(a, b, on_level=0.6)["ticks"] == 2


def test_tolerant_fan_iou_matches_cells_within_one_cell_in_eight_directions():
    a, b = np.zeros((5, 9, 17)), np.zeros((5, 9, 17))
    a[0, 4, 8] = b[0, 5, 9] = 1.0  # diagonal neighbours: exact IoU 0, tolerant 1
    a[1, 0, 0:4] = 0.5  # tick 1: ref cols 0-3, test cols 2-7 of row 0
    b[1, 0, 2:8] = 0.5  # union: cols 0..7; matched: ref cols 1..3, test cols 2..4
    a[2, 2, 2] = b[2, 2, 4] = 1.0  # two cells apart: unmatched at tolerance 1, matched at 2
    a[3, 8, 16] = 1.0  # only ref blows: nothing to match
    r = M.fan_iou(a, b)
    assert r["tolerance_cells"] == 1 and r["ticks"] == 4
    per_tick = [1.0, 4 / 8, 0.0, 0.0]  # tick 1: cols 1..4 of the union's 0..7 matched
    assert r["iou_tolerant"] == pytest.approx(np.mean(per_tick))
    assert r["iou_tolerant_pooled"] == pytest.approx((2 + 4 + 0 + 0) / (2 + 8 + 2 + 1))
    assert r["iou_tolerant_both_on"] == pytest.approx(np.mean(per_tick[:3]))
    assert r["iou"] == pytest.approx((0 + 2 / 8 + 0 + 0) / 4)
    assert M.fan_iou(a, b, tolerance=2)["iou_tolerant"] == pytest.approx(np.mean([1.0, 6 / 8, 1.0, 0.0]))
    exact = M.fan_iou(a, b, tolerance=0)
    assert exact["iou_tolerant"] == exact["iou"] and exact["iou_tolerant_pooled"] == exact["iou_pooled"]
    for bad in (-1, 18, 1.5, True):
        with pytest.raises(ParameterError, match="tolerance"):
            M.fan_iou(a, b, tolerance=bad)


# ------------------------------------------------------------------------ report
def test_compare_timelines_known_answer_and_different_lengths():
    ref, test = _tl(30), _tl(32)
    ref.vibration[10:13, 4] = 0.6
    test.vibration[11:13, 4] = 0.6  # onset one tick later: matched; MAE 0.6 / (30 * 9)
    test.temperature_c[:] = 34.0  # 1 C off everywhere (ref neutral 33)
    ref.fans[5, 4, 8] = 1.0
    test.fans[5, 4, 8] = 0.5
    ref.features["loudness"] = np.linspace(0, 1, 30)
    test.features["loudness"] = np.linspace(0, 1, 32)
    test.features["motion"] = np.zeros(32)
    r = M.compare_timelines(ref.validate(), test.validate())
    assert r["n_ticks"] == {"ref": 30, "test": 32, "common": 30, "difference": 2}
    assert r["same_source"] is True
    assert r["vibration"]["mae"] == pytest.approx(0.6 / (30 * 9), rel=1e-6)
    assert r["vibration"]["mae_per_actuator"]["A5"] == pytest.approx(0.6 / 30, rel=1e-6)
    assert r["vibration"]["chair_mae"] == pytest.approx(0.6 / 30, rel=1e-6)
    assert r["vibration"]["onsets"]["f1"] == 1.0
    assert r["temperature"]["mae_c"] == pytest.approx(1.0)
    assert r["fans"]["iou"] == 1.0 and r["fans"]["mae"] == pytest.approx(0.5 / (30 * 153))
    loud = np.abs(np.linspace(0, 1, 30) - np.linspace(0, 1, 32)[:30]).mean()
    assert r["features"] == {"loudness": pytest.approx(loud)}
    assert r["features_only_in"] == {"ref": [], "test": ["motion"]}
    h = M.headline(r)
    assert h["tick_difference"] == 2 and h["onset_f1"] == 1.0
    json.dumps(r)  # serialisable
    text = M.format_report(r)
    assert "difference +2" in text and "features only in test: motion" in text


def test_identical_timelines_have_zero_error():
    tl = _tl(20)
    tl.vibration[3:9] = 0.5
    tl.fans[4, :, :3] = 0.8
    r = M.compare_timelines(tl, tl.copy())
    h = M.headline(r)
    assert h == {"vibration_mae": 0.0, "onset_f1": 1.0, "onset_precision": 1.0, "onset_recall": 1.0,
                 "chair_onset_f1": 1.0, "chair_mae": 0.0, "temperature_mae_c": 0.0, "fan_iou": 1.0,
                 "fan_iou_tolerant": 1.0, "fan_ticks_f1": 1.0, "fan_iou_both_on": 1.0, "tick_difference": 0}


def test_chair_onsets_ignore_which_actuator_carries_the_event():
    ref, test = _tl(20), _tl(20)
    ref.vibration[5:9, 0] = 0.8  # an event on A1 ...
    test.vibration[5:9, 1] = 0.8  # ... the same event on A2
    ref.vibration[12:14, 4] = 0.5
    test.vibration[13:14, 3:6] = 0.5  # one tick late, spread over A4..A6
    r = M.compare_timelines(ref, test)
    assert r["vibration"]["onsets"]["f1"] == pytest.approx(2 * (1 / 4) * (1 / 2) / (1 / 4 + 1 / 2))
    assert r["vibration"]["chair_onsets"] == {"precision": 1.0, "recall": 1.0, "f1": 1.0, "matched": 2,
                                              "ref_onsets": 2, "test_onsets": 2, "tolerance_ticks": 1}


def test_different_sources_are_flagged():
    r = M.compare_timelines(_tl(3, "aaa"), _tl(3, "bbb"))
    assert r["same_source"] is False
    assert "different sources" in M.format_report(r)
    assert M.compare_timelines(_tl(3, ""), _tl(3, "bbb"))["same_source"] is None


# --------------------------------------------------------------------------- CLI
def test_cli_compare_text_and_json(tmp_path, capsys):
    ref, test = _tl(10), _tl(10)
    test.vibration[2:4, 0] = 0.5
    ref.save(tmp_path / "a.json")
    test.save(tmp_path / "b.json")
    assert main(["compare", str(tmp_path / "a.json"), str(tmp_path / "b.json")]) == 0
    out = capsys.readouterr().out
    assert "vibration: MAE" in out and "F1 0.000" in out
    assert main(["compare", str(tmp_path / "a.json"), str(tmp_path / "b.json"), "--json"]) == 0
    doc = json.loads(capsys.readouterr().out)
    assert doc["vibration"]["mae"] == pytest.approx(1.0 / 90, rel=1e-4)
    assert doc["vibration"]["onsets"]["test_onsets"] == 1


def test_cli_compare_errors_are_one_line_with_exit_code_2(tmp_path):
    _tl(5, "aaa").save(tmp_path / "a.json")
    _tl(5, "bbb").save(tmp_path / "b.json")
    (tmp_path / "bad.json").write_text("{not json")
    exe = [sys.executable, "-m", "autohaptics.cli.main", "compare"]
    cases = [
        ([str(tmp_path / "a.json"), str(tmp_path / "missing.json")], "no such file"),
        ([str(tmp_path / "a.json"), str(tmp_path / "bad.json")], "not a timeline JSON file"),
        ([str(tmp_path / "a.json"), str(tmp_path / "b.json")], "different source"),
    ]
    for args, msg in cases:
        r = subprocess.run(exe + args, capture_output=True, text=True)
        assert r.returncode == 2, r.stderr
        assert msg in r.stderr and "Traceback" not in r.stderr
        assert len(r.stderr.strip().splitlines()) == 1
    r = subprocess.run(exe + [str(tmp_path / "a.json"), str(tmp_path / "b.json"), "--any-source"],
                       capture_output=True, text=True)
    assert r.returncode == 0 and "warning: the two timelines come from different sources" in r.stdout


# ------------------------------------------------------- bench accuracy helpers
def test_bench_config_parsing():
    from autohaptics.bench.configs import Config, parse_config

    assert parse_config("dis:flow.method=dis,flow.proxy_width=320") == Config(
        "dis", "balanced", (("flow.method", "dis"), ("flow.proxy_width", "320")))
    assert parse_config("cheap:preset=fast,tracks=vibration,fans") == Config(
        "cheap", "fast", (("tracks", "vibration,fans"),))  # a piece without '=' continues the value
    assert parse_config("plain") == Config("plain", "balanced", ())
    for bad, msg in (("x:nosuch.knob=1", "unknown parameter"), ("x:preset=turbo", "unknown preset"),
                     (":a=1", "NAME:k=v"), ("x:,tracks", "expected k=v")):
        with pytest.raises(ParameterError, match=msg):
            parse_config(bad)


def test_pareto_front_known_answer():
    from autohaptics.bench.report import pareto_front

    pts = [(1.0, 0.5), (2.0, 0.2), (1.5, 0.6), (10.0, 0.0), (2.0, 0.3), (0.9, 0.9)]
    assert pareto_front(pts) == [5, 0, 1, 3]
    assert pareto_front([(1.0, 1.0), (1.0, 1.0)]) == [0, 1]  # ties dominate nothing


def test_stage_figures_from_stats():
    from autohaptics.bench.accuracy import analysis_stage_seconds, skip_shares, stage_seconds

    stats = {"audio": {"seconds": 1.5}, "video": {
        "seconds": 9.0, "decode_wait": {"seconds": 5.0}, "proxy": {"seconds": 1.0}, "flow": {"seconds": 0.5,
        "computed": 30, "ticks_computed": 30, "ticks_skipped": 10}, "saliency": {"seconds": 0.25, "computed": 4,
        "ticks_computed": 4, "ticks_skipped": 16, "ticks_held": 20}, "static": {"seconds": 0.1, "ticks_static": 7},
        "cuts": {"seconds": 0.0, "cuts": 2}, "frames": {"ticks": 40}}}
    assert analysis_stage_seconds(stats) == pytest.approx(1.5 + 1.0 + 0.5 + 0.25 + 0.1)
    sk = skip_shares(stats)
    assert sk["flow"] == {"computed": 30, "skipped": 10, "held": 0, "share_computed": 0.75, "seconds": 0.5, "calls": 30}
    assert (sk["saliency"]["skipped"], sk["saliency"]["held"]) == (16, 20)  # held: a stride's second ticks
    assert sk["saliency"]["share_computed"] == 0.1 and "depth" not in sk
    assert (sk["static_ticks"], sk["cuts"], sk["ticks"]) == (7, 2, 40)
    st_ = stage_seconds(stats)
    assert st_["video.decode_wait"] == 5.0 and st_["video"] == 9.0 and st_["audio"] == 1.5 and "video.frames" not in st_


def test_run_child_reports_the_childs_own_peak_memory():
    from autohaptics.bench.child import run_child

    small = run_child([sys.executable, "-c", "pass"])
    big = run_child([sys.executable, "-c", "import sys; b = bytearray(300 * 2**20); b[::4096] = b'x' * len(b[::4096]); "
                                           "print('done'); sys.exit(3)"])
    assert small.returncode == 0 and big.returncode == 3 and big.stdout.strip() == "done"
    assert small.peak_rss_mb < 60  # neither this (large) test process nor an earlier child counts
    assert 300 < big.peak_rss_mb < 360
    assert run_child([sys.executable, "-c", "import time; time.sleep(30)"], timeout_s=1).returncode == -9


def test_run_child_reports_the_childs_own_cpu_time():
    from autohaptics.bench.child import run_child

    spin = "import time; t = time.process_time()\nwhile time.process_time() - t < 0.3: pass"
    busy = run_child([sys.executable, "-c", spin])
    idle = run_child([sys.executable, "-c", "import time; time.sleep(0.3)"])
    assert busy.returncode == 0 and idle.returncode == 0
    assert 0.3 <= busy.cpu_s < busy.wall_s + 0.05  # user + system seconds of the child itself
    assert idle.cpu_s < 0.25 and idle.wall_s >= 0.3  # sleeping costs wall time, not CPU


@pytest.mark.slow
def test_bench_accuracy_end_to_end(tmp_path):
    """A 2 s synthetic clip through every configuration: table, verdicts, plot and JSON."""
    r = subprocess.run([sys.executable, "-m", "autohaptics.cli.main", "bench", "accuracy", "--synth", "64x36@24:2",
                        "--out", str(tmp_path), "--config", "dis-medium:flow.dis_preset=medium"],
                       capture_output=True, text=True, timeout=900)
    assert r.returncode == 0, r.stderr
    assert "skipping audit" in r.stdout and "balanced onset F1" in r.stdout
    assert "fast speed-up vs balanced (wall time)" in r.stdout and machine_line() in r.stdout
    doc = json.loads((tmp_path / "accuracy.json").read_text())
    assert doc["machine"] == machine()
    clip = doc["clips"][0]
    assert set(clip["configs"]) == {"reference", "balanced", "fast", "balanced-noskip", "dis-medium"}
    assert clip["configs"]["reference"]["error"]["vibration_mae"] == 0.0
    for c in clip["configs"].values():
        assert c["wall_s"] > 0 and c["peak_rss_mb"] > 50 and 0 <= c["error"]["fan_iou"] <= 1
    assert (tmp_path / Path(clip["plot"]).name).stat().st_size > 10_000
