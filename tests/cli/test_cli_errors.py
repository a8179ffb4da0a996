"""The CLI cases of issue 17: each is one line on stderr, exit status 2, naming the path the user
gave (never a temporary ``.part`` file or a traceback), and leaves no file behind."""

from __future__ import annotations

import os
import stat
from pathlib import Path

import pytest

from autohaptics.cli.main import main
from autohaptics.testing import Scene, Segment, Tone, write_scene
from autohaptics.timeline import Timeline

from stress_inputs import CASES


def one_line(capsys) -> str:
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and err.startswith("autohaptics: error: "), err
    assert "Traceback" not in err and ".part" not in err and "internal error" not in err, err
    return err


@pytest.fixture(scope="module")
def film(tmp_path_factory) -> Path:
    """A generated 1 s clip (a red picture, a 60 Hz tone): every command that reads media accepts it."""
    scene = Scene(duration_s=1.0, background=(Segment(0.0, 1.0, (150, 60, 40)),),
                  audio=(Tone(0.2, 0.8, 60.0, level_dbfs=-14.0),), name="cli errors")
    return write_scene(tmp_path_factory.mktemp("cli-film") / "film.mp4", scene, width=64, height=36, fps=5,
                       quality="low", sample_rate=24000)


@pytest.fixture
def timeline_json(tmp_path) -> Path:
    path = tmp_path / "t.json"
    path.write_text(Timeline.empty(20).validate().to_json())
    return path


def test_features_refuses_a_truncated_file_like_generate_naming_it_as_given(tmp_path, capsys, monkeypatch):
    case = next(c for c in CASES if c.name == "truncated_mp4_faststart_50pct")
    (tmp_path / "films").mkdir()
    built = case.build(tmp_path / "films")
    monkeypatch.chdir(tmp_path)
    given = str(built.relative_to(tmp_path))  # relative: the line must not name the resolved path
    for argv in (["features", given, "-o", "features.json"], ["generate", given, "-o", "t.json", "--quiet"]):
        assert main(argv) == 2, argv
        line = one_line(capsys)
        assert line.startswith(f"autohaptics: error: {given}: ") and case.message in line, line
    assert not (tmp_path / "features.json").exists() and not (tmp_path / "t.json").exists()


def commands(film: Path, timeline: Path, out: str) -> dict[str, list[str]]:
    """Every command that writes one output file, writing ``out``."""
    return {"generate": ["generate", str(film), "-o", out, "--quiet"],
            "features": ["features", str(film), "-o", out],
            "import": ["import", str(timeline), "-o", out],
            "export": ["export", str(timeline), "-f", "csv", "-o", out]}


@pytest.mark.parametrize("command", ["generate", "features", "import", "export"])
@pytest.mark.parametrize("where, message", [
    ("missing/out.json", "the output folder {root}/missing does not exist"),
    ("afile/out.json", "the output folder {root}/afile is not a folder"),
    ("locked/out.json", "cannot write here (Permission denied)"),
    ("", "is a folder; give a file name"),
])
def test_an_output_that_cannot_be_written_names_the_path_given(tmp_path, film, timeline_json, capsys, command,
                                                               where, message):
    (tmp_path / "afile").write_text("x")
    locked = tmp_path / "locked"
    locked.mkdir()
    locked.chmod(stat.S_IRUSR | stat.S_IXUSR)
    try:
        out = str(tmp_path / where) if where else str(tmp_path)
        if where.startswith("locked") and os.access(locked, os.W_OK):  # root writes anywhere but in /sys
            if not Path("/sys/kernel").is_dir():
                pytest.skip("running as root without /sys: no folder refuses a write")
            out = "/sys/autohaptics-out.json"
        assert main(commands(film, timeline_json, out)[command]) == 2
        err = one_line(capsys)
        assert err.startswith(f"autohaptics: error: {out}: ") and message.format(root=tmp_path) in err, err
        assert not list(locked.iterdir()) and not list(tmp_path.rglob("*.part"))
        assert (tmp_path / "afile").read_text() == "x" and not (tmp_path / "missing").exists()
    finally:
        locked.chmod(stat.S_IRWXU)


def test_import_of_a_folder_names_that_folder(tmp_path, capsys):
    folder = tmp_path / "timelines"
    folder.mkdir()
    assert main(["import", str(folder), "-o", str(tmp_path / "t.json")]) == 2
    err = one_line(capsys)
    assert err.startswith(f"autohaptics: error: {folder}: is a folder"), err
    assert "no such file" not in err.lower() and "t.json" not in err, err
    assert not (tmp_path / "t.json").exists()


@pytest.mark.parametrize("assignment, name", [("intensity=5", "'intensity'"), ("flow=x", "'flow'"),
                                              ("thermal.x=1", "'thermal.x'"), ("lfe_gain_db=1e400", "lfe_gain_db")])
def test_generate_refuses_a_bad_parameter_by_name(tmp_path, film, capsys, assignment, name):
    out = tmp_path / "t.json"
    assert main(["generate", str(film), "-o", str(out), "--set", assignment]) == 2
    assert name in one_line(capsys)
    assert not out.exists()
