"""The CLI cases of issue 17: each is one line on stderr, exit status 2, naming the path the user
gave (never a temporary ``.part`` file or a traceback), and leaves no file behind."""

from __future__ import annotations

import os
import stat
from pathlib import Path

import pytest

from autohaptics.cli.main import main
from autohaptics.timeline import Timeline

from shared_data import shared_clip
from stress_inputs import CASES

CLIP = "bbb_1s_1280x720_vp8_vorbis.webm"


def one_line(capsys) -> str:
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and err.startswith("autohaptics: error: "), err
    assert "Traceback" not in err and ".part" not in err and "internal error" not in err, err
    return err


@pytest.fixture
def timeline_json(tmp_path) -> Path:
    path = tmp_path / "t.json"
    path.write_text(Timeline.empty(20).validate().to_json())
    return path


def test_features_refuses_a_truncated_file_like_generate(tmp_path, capsys):
    case = next(c for c in CASES if c.name == "truncated_mp4_faststart_50pct")
    film, out = case.build(tmp_path), tmp_path / "features.json"
    for argv in (["features", str(film), "-o", str(out)], ["generate", str(film), "-o", str(tmp_path / "t.json")]):
        assert main(argv) == 2, argv
        assert case.message in one_line(capsys)
    assert not out.exists() and not (tmp_path / "t.json").exists()


@pytest.mark.parametrize("where, message", [
    ("missing/out.csv", "the output folder {root}/missing does not exist"),
    ("afile/out.csv", "the output folder {root}/afile is not a folder"),
    ("locked/out.csv", "cannot write here (Permission denied)"),
    ("", "is a folder; give a file name"),
])
def test_an_output_that_cannot_be_written_names_the_path_given(tmp_path, timeline_json, capsys, where, message):
    (tmp_path / "afile").write_text("x")
    locked = tmp_path / "locked"
    locked.mkdir()
    locked.chmod(stat.S_IRUSR | stat.S_IXUSR)
    try:
        out = str(tmp_path / where) if where else str(tmp_path)
        if where.startswith("locked") and os.access(locked, os.W_OK):  # root writes anywhere but in /sys
            if not Path("/sys/kernel").is_dir():
                pytest.skip("running as root without /sys: no folder refuses a write")
            out = "/sys/autohaptics-out.csv"
        assert main(["export", str(timeline_json), "-f", "csv", "-o", out]) == 2
        err = one_line(capsys)
        assert out in err and message.format(root=tmp_path) in err, err
        assert not list(locked.iterdir())
    finally:
        locked.chmod(stat.S_IRWXU)


def test_import_of_a_folder_says_so(tmp_path, capsys):
    assert main(["import", str(tmp_path), "-o", str(tmp_path / "t.json")]) == 2
    err = one_line(capsys)
    assert str(tmp_path) in err and "folder" in err and "no such file" not in err.lower(), err


@pytest.mark.parametrize("assignment, name", [("intensity=5", "'intensity'"), ("flow=x", "'flow'"),
                                              ("thermal.x=1", "'thermal.x'"), ("lfe_gain_db=1e400", "lfe_gain_db")])
def test_generate_refuses_a_bad_parameter_by_name(tmp_path, capsys, assignment, name):
    out = tmp_path / "t.json"
    assert main(["generate", str(shared_clip(CLIP)), "-o", str(out), "--set", assignment]) == 2
    assert name in one_line(capsys)
    assert not out.exists()
