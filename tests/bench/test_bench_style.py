"""``autohaptics bench style`` runs end to end and prints one row per simulated designer."""

from __future__ import annotations

from autohaptics.cli.main import main
from autohaptics.testing.designers import DESIGNERS

from shared_data import shared_clip


def test_bench_style_prints_a_row_per_designer(tmp_path, capsys):
    shared_clip("sintel_trailer_480x204_h264_aac.mp4")  # skips with the command that provides it
    assert main(["bench", "style", "--work", str(tmp_path)]) == 0
    out = capsys.readouterr().out
    assert "unedited films learn the identity: 5 of 5" in out
    rows = [line.split()[0] for line in out.splitlines()]
    assert all(d.name in rows for d in DESIGNERS)
