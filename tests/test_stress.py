"""Stress suite: bad and odd media through ``autohaptics generate`` (inputs: tests/stress_inputs.py).

Every input gives either a valid timeline (all values finite and in range, n_ticks ==
ceil(duration / 0.1), plus the case's known answer) or a clear error: exit code 2 and exactly
one line on stderr, ``autohaptics: error: ...`` naming the problem (an "internal error" line, a
traceback or a crashed process is a bug). Inputs are generated into a session folder; nothing
is committed.

Known bugs are marked xfail(strict=True) with the reason: the test flips to a failure the
moment the bug is fixed, so the mark gets removed.
"""

from __future__ import annotations

import math
import os
import subprocess
import sys

import numpy as np
import pytest

from autohaptics.temperature import ThermalParams
from autohaptics.timeline import NORMALISED_FEATURES, Timeline
from stress_inputs import CASES, Worker, case, expected_ticks, long_film

BUGS: dict[str, str] = {}  # case name -> reason, for a known bug not yet fixed (xfail, strict)


def _params():
    out = []
    for c in CASES:
        marks = [pytest.mark.xfail(strict=True, reason=BUGS[c.name])] if c.name in BUGS else []
        out.append(pytest.param(c, id=c.name, marks=marks))
    return out


@pytest.fixture(scope="session")
def stress_dir(tmp_path_factory):
    return tmp_path_factory.mktemp("stress_inputs")


@pytest.fixture(scope="session")
def worker():
    w = Worker()
    yield w
    w.close()


def check_timeline(tl: Timeline, duration_s: float | None = None) -> None:
    """Every value finite and in range; n_ticks == ceil(duration / 0.1)."""
    n = tl.n_ticks
    assert n == expected_ticks(tl.source["duration_s"]), (n, tl.source["duration_s"])
    if duration_s is not None:
        assert abs(tl.source["duration_s"] - duration_s) <= 0.1, (tl.source["duration_s"], duration_s)
    lo, hi = tl.temp_range
    assert (lo, hi) == ThermalParams().range_c  # the default mapping's range: the device's
    for name, arr, a, b in (("vibration", tl.vibration, 0.0, 1.0), ("fans", tl.fans, 0.0, 1.0),
                            ("temperature_c", tl.temperature_c, lo, hi)):
        assert arr.shape[0] == n, name
        assert np.isfinite(arr).all(), f"{name} holds a non-finite value"
        assert arr.min() >= a and arr.max() <= b, (name, float(arr.min()), float(arr.max()))
    for name, values in tl.features.items():
        assert values.shape == (n,), name
        assert np.isfinite(values).all(), f"feature {name} holds a non-finite value"
        if name in NORMALISED_FEATURES:
            assert values.min() >= 0 and values.max() <= 1, name


@pytest.mark.parametrize("case", _params())
def test_stress_input(case, stress_dir, worker, tmp_path):
    path = case.build(stress_dir)
    out = tmp_path / "timeline.json"
    r = worker.run(["generate", str(path), "-o", str(out), "--quiet", *case.args])
    assert r["rc"] is not None, f"{case.name}: CRASH, {r['crash']}:\n{r['stderr']}"
    lines = r["stderr"].strip().splitlines()
    if case.expect == "error":
        assert r["rc"] == 2, f"{case.name}: expected an error, got exit code {r['rc']}: {r['stderr']}"
        assert len(lines) == 1, f"{case.name}: expected one line on stderr, got:\n{r['stderr']}"
        assert lines[0].startswith("autohaptics: error: "), lines[0]
        assert case.message in lines[0], lines[0]
        assert not out.exists()
    else:
        assert r["rc"] == 0, f"{case.name}: expected a timeline, got exit code {r['rc']}: {r['stderr']}"
        assert "Traceback" not in r["stderr"]
        tl = Timeline.load(out)  # validates shapes, finiteness and ranges once more
        check_timeline(tl, case.duration_s)
        if case.check is not None:
            case.check(tl)


def test_every_kind_is_covered():
    names = [c.name for c in CASES]
    assert len(names) == len(set(names))
    assert len(CASES) >= 30
    assert {c.expect for c in CASES} == {"timeline", "error"}


def test_errors_through_a_real_process(stress_dir, tmp_path):
    """The worker emulates the command line; two errors also go through a real ``autohaptics`` process:
    exit code 2, one line on stderr (FFmpeg's own log lines would show up here)."""
    inputs = [(case("truncated_webm_50pct"), "truncated or damaged file"),
              (case("zero_length_streams_mkv"), "not a readable media file")]
    procs = []
    for c, _ in inputs:
        path = c.build(stress_dir)
        cmd = [sys.executable, "-m", "autohaptics.cli.main", "generate", str(path), "-o", str(tmp_path / "t.json")]
        procs.append(subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True))
    for (c, msg), p in zip(inputs, procs):
        _, err = p.communicate(timeout=300)
        assert p.returncode == 2, err
        lines = err.strip().splitlines()
        assert len(lines) == 1 and lines[0].startswith("autohaptics: error: ") and msg in lines[0], err


# ------------------------------------------------------------------ the 2-hour film
@pytest.fixture(scope="session")
def two_hour_film(tmp_path_factory):
    return long_film(tmp_path_factory.mktemp("long") / "film_2h_64x36.mp4")


TWO_HOUR_PRESETS = ("balanced", "fast")


@pytest.fixture(scope="session")
def two_hour_runs(two_hour_film, tmp_path_factory) -> dict:
    """``generate`` of the 2-hour film once per preset, the presets side by side in their own
    processes (each child's peak RSS is its own, measured through ``wait4``): preset -> (result,
    timeline path). On two cores side by side took 437 s, one after the other 393 + 208 s."""
    from concurrent.futures import ThreadPoolExecutor

    from autohaptics.bench.child import run_child

    d = tmp_path_factory.mktemp("two_hour_runs")

    def run(preset: str):
        out = d / f"{preset}.json"
        return run_child([sys.executable, "-m", "autohaptics.cli.main", "generate", str(two_hour_film), "-o",
                          str(out), "--quiet", "--preset", preset]), out

    with ThreadPoolExecutor(len(TWO_HOUR_PRESETS)) as pool:
        return dict(zip(TWO_HOUR_PRESETS, pool.map(run, TWO_HOUR_PRESETS)))


@pytest.mark.slow
@pytest.mark.parametrize("preset", TWO_HOUR_PRESETS)
def test_two_hour_film_in_bounded_memory(two_hour_runs, preset):
    r, out = two_hour_runs[preset]
    print(f"\n2-hour 64x36 film, preset {preset}: peak RSS {r.peak_rss_mb:.0f} MiB, wall {r.wall_s:.0f} s")
    assert r.returncode == 0, r.stderr
    tl = Timeline.load(out)
    check_timeline(tl, 7200.0)
    assert tl.n_ticks == 72_000
    assert tl.vibration.any() and tl.fans.any()
    assert math.isclose(tl.source["duration_s"], 7200.0, abs_tol=0.1)
    os.remove(out)
    assert r.peak_rss_mb < RSS_CEILING_MB, f"peak RSS {r.peak_rss_mb:.0f} MiB (docs/BENCHMARKS.md, '2-hour film')"
    if r.peak_rss_mb >= 400:
        pytest.xfail(f"peak RSS {r.peak_rss_mb:.0f} MiB >= the 400 MB target; known: {RSS_MISS}")


# The 400 MB target: 307 MiB where the shared libraries' files have been out of the page cache for a
# while, 391 MiB right after a fresh install (the kernel's fault-around maps more of a freshly written
# library; the pipeline drops clean library pages between its passes, heap.release_library_pages,
# which took these from 387 and 467-501 MiB). With so little margin a peak at or above 400 MiB is
# recorded as an expected failure; above the ceiling the test fails as a regression.
RSS_CEILING_MB = 480
RSS_MISS = ("file-backed library pages count in RSS and depend on the page cache; "
            "docs/BENCHMARKS.md, '2-hour film'")
