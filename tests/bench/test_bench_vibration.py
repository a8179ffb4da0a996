"""``autohaptics bench vibration``: the share of ticks that vibrate per clip, default against thesis."""

from __future__ import annotations

import json

import pytest

from autohaptics.cli.main import main
from autohaptics.testing import sounds, write_scene


def test_bench_vibration_prints_default_thesis_and_density(tmp_path, capsys):
    clip = write_scene(tmp_path / "speech.wav", sounds.speech(duration_s=12.0))
    out = tmp_path / "vib.json"
    # 0.2: the words of the clip's first 3-4 s are resumed speech (novelty 0), which leaves about 0.26-0.34
    # of its ticks any novelty for a density to rank
    assert main(["bench", "vibration", str(clip), "--density", "0.2", "--json", str(out)]) == 0
    printed = capsys.readouterr().out
    assert "speech.wav" in printed and "density 0.2" in printed
    (r,) = json.loads(out.read_text())["clips"]
    assert r["ticks"] == 120 and r["duration_s"] == pytest.approx(12.0)
    assert r["default"] <= 0.2 < 0.4 < r["thesis"]  # speech: the default stays still, the thesis buzzes
    assert abs(r["density"] - 0.2) <= 0.03
    assert "met" in printed.splitlines()[2]


def test_bench_vibration_rejects_a_bad_density_and_a_missing_file(tmp_path, capsys):
    assert main(["bench", "vibration", str(tmp_path / "none.mp4")]) == 2
    assert "no such file" in capsys.readouterr().err
    assert main(["bench", "vibration", str(tmp_path / "none.mp4"), "--density", "2"]) == 2
