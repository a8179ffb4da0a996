"""``autohaptics style learn|show``, ``generate --style`` and ``batch --style``: what they write, and
bad input as one line on stderr with exit status 2."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from autohaptics import pipeline
from autohaptics.batch import run_batch
from autohaptics.cli.main import main
from autohaptics.style import Style, load, save
from autohaptics.testing import Scene, Segment, Tone, write_scene
from autohaptics.testing.designers import Designer, edit
from autohaptics.timeline import Timeline


def one_line(capsys) -> str:
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and err.startswith("autohaptics: error: "), err
    assert "Traceback" not in err and "internal error" not in err, err
    return err


@pytest.fixture(scope="module")
def film(tmp_path_factory) -> Path:
    """A 2 s clip: a red picture turning blue, two 60 Hz tones."""
    scene = Scene(duration_s=2.0, background=(Segment(0.0, 1.0, (150, 60, 40)), Segment(1.0, 2.0, (40, 60, 150))),
                  audio=(Tone(0.2, 0.6, 60.0, level_dbfs=-14.0), Tone(1.2, 1.6, 60.0, level_dbfs=-10.0)),
                  name="style cli")
    return write_scene(tmp_path_factory.mktemp("style-cli") / "film.mp4", scene, width=64, height=36, fps=5,
                       quality="low", sample_rate=24000)


@pytest.fixture(scope="module")
def cached(film, tmp_path_factory) -> tuple[Path, Path]:
    """The film's analysis cache and a warm designer's edited timeline of it."""
    folder = tmp_path_factory.mktemp("style-cache")
    analysis = pipeline.analyse(film)
    analysis.save(folder / "film.npz")
    edited = edit(Designer("warm", "", temp_offset_c=2.0, gain=0.5), analysis, one_offs=0)
    edited.save(folder / "edited.json")
    return folder / "film.npz", folder / "edited.json"


@pytest.mark.parametrize("source", ["media", "cache"])
def test_learn_show_and_generate_with_a_style(film, cached, tmp_path, capsys, source):
    out = tmp_path / "warm.style.json"
    first = str(film) if source == "media" else str(cached[0])
    assert main(["style", "learn", first, str(cached[1]), "-o", str(out)]) == 0
    style = load(out)
    assert style.name == "warm.style" and style.temperature_offset_c == pytest.approx(2.0, abs=0.05)
    capsys.readouterr()
    assert main(["style", "show", str(out)]) == 0
    shown = capsys.readouterr().out
    assert "offset +2" in shown and "A1" in shown and "fans" in shown
    plain, styled = tmp_path / "plain.json", tmp_path / "styled.json"
    assert main(["generate", str(film), "-o", str(plain), "--quiet"]) == 0
    assert main(["generate", str(film), "-o", str(styled), "--quiet", "--style", str(out)]) == 0
    a, b = Timeline.load(plain), Timeline.load(styled)
    assert b.generator["style"]["name"] == "warm.style" and "style" not in a.generator
    assert b.temperature_c.mean() > a.temperature_c.mean() + 1.5


def test_batch_with_a_style_redoes_films_made_in_another_style(film, tmp_path):
    warm, cool = Style(temperature_offset_c=1.0), Style(temperature_offset_c=-1.0)
    out = tmp_path / "out"
    statuses = [run_batch([film], out, style=style).results[0].status for style in (warm, warm, cool, None)]
    assert statuses == ["done", "skipped", "done", "done"]
    (out / "batch-manifest.json").unlink()  # judged from the timeline itself: made without a style
    assert run_batch([film], out, style=warm).results[0].status == "done"
    assert run_batch([film], out, style=warm).results[0].status == "skipped"
    tl = Timeline.load(out / "film.timeline.json")
    assert tl.generator["style"]["temperature"]["offset_c"] == 1.0


def test_batch_cli_takes_a_style(film, tmp_path):
    path = save(Style(temperature_offset_c=1.5), tmp_path / "s.json")
    assert main(["batch", str(film), "-o", str(tmp_path / "o"), "--quiet", "--style", str(path)]) == 0
    assert Timeline.load(tmp_path / "o" / "film.timeline.json").generator["style"]["temperature"]["offset_c"] == 1.5


def _bad_files(tmp: Path) -> dict[str, Path]:
    files = {"not_json": "{", "analysis_override": json.dumps({"format": "autohaptics.style", "version": 1,
                                                                "overrides": {"video.stride": 2}}),
             "curve": json.dumps({"format": "autohaptics.style", "version": 1, "fans": [0, 1]})}
    out = {}
    for name, text in files.items():
        out[name] = tmp / f"{name}.json"
        out[name].write_text(text)
    out["missing"] = tmp / "missing.json"
    return out


@pytest.mark.parametrize("which, words", [("not_json", "not a style file"), ("analysis_override", "analysed again"),
                                          ("curve", "fans must be a list"), ("missing", "cannot read")])
@pytest.mark.parametrize("command", ["show", "generate", "batch"])
def test_a_bad_style_file_is_one_line_and_exit_2(film, tmp_path, capsys, which, words, command):
    path = _bad_files(tmp_path)[which]
    argv = {"show": ["style", "show", str(path)],
            "generate": ["generate", str(film), "-o", str(tmp_path / "t.json"), "--style", str(path)],
            "batch": ["batch", str(film), "-o", str(tmp_path / "b"), "--style", str(path), "--quiet"]}[command]
    assert main(argv) == 2
    err = one_line(capsys)
    assert words in err and path.name in err
    assert not (tmp_path / "t.json").exists() and not (tmp_path / "b").exists()


def test_bad_learn_input_is_one_line_and_exit_2(film, cached, tmp_path, capsys):
    npz, edited = cached
    out = str(tmp_path / "s.json")
    other = Timeline.empty(7).validate()
    other.save(tmp_path / "short.json")
    (tmp_path / "junk.npz").write_bytes(b"not an npz")
    cases = [(["style", "learn", str(npz), "-o", out], "odd count"),
             (["style", "learn", str(npz), str(tmp_path / "short.json"), "-o", out], "not a timeline of this film"),
             (["style", "learn", str(tmp_path / "junk.npz"), str(edited), "-o", out], "not an analysis cache"),
             (["style", "learn", str(npz), str(edited), "-o", out, "--preset", "fast"], "other analysis-time"),
             (["style", "learn", str(npz), str(tmp_path / "none.json"), "-o", out], "none.json")]
    for argv, words in cases:
        assert main(argv) == 2, argv
        assert words in one_line(capsys), argv
    assert not Path(out).exists()


def test_an_identity_style_file_generates_the_preset_exactly(film, tmp_path):
    path = save(Style(), tmp_path / "identity.json")
    assert main(["generate", str(film), "-o", str(tmp_path / "a.json"), "--quiet"]) == 0
    assert main(["generate", str(film), "-o", str(tmp_path / "b.json"), "--quiet", "--style", str(path)]) == 0
    a, b = Timeline.load(tmp_path / "a.json"), Timeline.load(tmp_path / "b.json")
    for name in ("vibration", "temperature_c", "fans"):
        np.testing.assert_array_equal(getattr(a, name), getattr(b, name))
