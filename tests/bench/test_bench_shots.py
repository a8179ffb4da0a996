"""``autohaptics bench shots`` end to end on a short film: the film's own boundaries, the answers
it times, a second run reusing the generated project."""

from __future__ import annotations

import argparse
import json

from autohaptics.bench import shots as bench


def test_the_film_knows_its_boundaries(tmp_path):
    _, truth = bench.write_film(tmp_path / "f.mp4", 40.0, 3.6, write=False)
    assert [t for t, _ in truth] == [36 * k + 1 for k in range(1, 12)]
    assert [k for _, k in truth][4] == "dissolve" and [k for _, k in truth][6] == "fade"


def test_bench_shots_prints_its_figures_and_reuses_the_project(tmp_path, capsys):
    args = argparse.Namespace(work=str(tmp_path), hours=0.02, shot_s=3.6, repeat=2)
    assert bench.run(args) == 0
    out = json.loads((tmp_path / "bench_shots.json").read_text())
    assert out["truth"] == 19 and out["recall_2"] >= 0.9 and out["precision_2"] >= 0.9
    assert out["boundaries_kept_by_commit"] and out["posters"] == 10 and out["picture_cache_mb"] > 0
    assert out["similar_picked"] == out["group_ops"] == out["shots"] - 1 and 0 <= out["similar_distance_300th"] <= 1
    assert out["ahead_posters"] >= out["shots"] and out["ahead_tiles"] > 0 and out["tile_step1_kb"] > 0
    assert out["generate_s"] > 0 and "first_ms" in capsys.readouterr().out
    assert bench.run(args) == 0  # the generated project is reused: no job
    assert json.loads((tmp_path / "bench_shots.json").read_text())["generate_s"] is None
