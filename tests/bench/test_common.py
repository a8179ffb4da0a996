"""What every benchmark records of the machine it ran on (bench/common.py), and ``bench pipeline``'s
figures file: the same clip's figures differ between CPUs (docs/BENCHMARKS.md, "Stop 51")."""

from __future__ import annotations

import hashlib
import json
import os
from pathlib import Path

import av
import pytest

from autohaptics import testing as synth
from autohaptics.bench.common import environment, machine, machine_line
from autohaptics.cli.main import main

CPUINFO = Path("/proc/cpuinfo")


def _cpuinfo_lines() -> list[tuple[str, str]]:
    return [(k.strip(), v.strip()) for k, _, v in (line.partition(":") for line in CPUINFO.read_text().splitlines())]


def test_machine_adds_the_cpu_the_cores_and_ffmpeg_to_the_environment():
    m = machine()
    env = environment()
    assert {k: m[k] for k in env} == env
    assert m["cores"] == os.cpu_count() >= 1
    assert m["ffmpeg"] == av.ffmpeg_version_info and m["av"] == av.__version__
    assert isinstance(m["cpu"], str) and m["cpu"]
    json.dumps(m)  # it goes into every figures file as it is


@pytest.mark.skipif(not CPUINFO.is_file(), reason="no /proc/cpuinfo")
def test_the_cpu_is_the_model_name_and_its_flags_hash_is_their_sorted_set():
    lines = _cpuinfo_lines()
    assert machine()["cpu"] == next(v for k, v in lines if k == "model name")
    flags = next(v for k, v in lines if k == "flags").split()
    assert environment()["cpu_flags_sha256"] == hashlib.sha256(" ".join(sorted(flags)).encode()).hexdigest()[:16]


def test_machine_line_names_the_cpu_cores_and_ffmpeg():
    m = {**machine(), "cpu": "Some CPU @ 2.0GHz", "cores": 2, "ffmpeg": "8.1.2", "av": "18.1.0"}
    assert machine_line(m) == "machine: Some CPU @ 2.0GHz, 2 cores; FFmpeg 8.1.2, PyAV 18.1.0"
    assert machine_line({**m, "cpu": None}).startswith(f"machine: {m['machine']}, 2 cores")


def test_bench_pipeline_prints_and_saves_the_machine(tmp_path, capsys):
    scene = synth.Scene(1.0, background=(synth.Segment(0, 1, (90, 120, 160)),), audio=(synth.Tone(0.2, 0.6, 50.0, -12.0),))
    clip = synth.write_scene(tmp_path / "clip.mp4", scene, width=64, height=36, fps=24)
    assert main(["bench", "pipeline", str(clip), "--repeat", "1", "--out", str(tmp_path / "out")]) == 0
    assert machine_line() in capsys.readouterr().out
    doc = json.loads((tmp_path / "out" / "pipeline_clip_balanced.json").read_text())
    assert doc["machine"] == machine() and doc["process_ratio"] > 0
