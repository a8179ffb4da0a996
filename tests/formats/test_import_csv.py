"""Importing timeline CSV/JSON: round trips, and errors that name the row and the column."""

from __future__ import annotations

import argparse
import io
import json

import numpy as np
import pytest

from autohaptics.bench.export import synthetic_timeline
from autohaptics.cli import export as cli_export
from autohaptics.cli import importer as cli_importer
from autohaptics.errors import ParameterError
from autohaptics.formats import export_timeline
from autohaptics.formats.csv import CSV_COLUMNS, write_csv_sidecar
from autohaptics.formats.importing import (
    MAX_PROBLEMS,
    ImportProblem,
    TimelineImportError,
    csv_meta_path,
    import_timeline,
    parse_timeline,
    read_csv,
)
from autohaptics.timeline import Timeline

COL = {name: i for i, name in enumerate(CSV_COLUMNS)}


def _timeline(n: int = 80, seed: int = 5) -> Timeline:
    return synthetic_timeline(n, seed=seed)


def _csv_lines(tl: Timeline) -> list[str]:
    buf = io.StringIO()
    export_timeline(tl, "csv", buf)
    return buf.getvalue().split("\n")[:-1]


def _set_cell(lines: list[str], row: int, column: str, text: str) -> None:
    """Overwrite one cell; ``row`` counts data rows from 1 (line ``row`` after the header)."""
    cells = lines[row].split(",")
    cells[COL[column]] = text
    lines[row] = ",".join(cells)


def _problems(text: str) -> TimelineImportError:
    with pytest.raises(TimelineImportError) as info:
        parse_timeline(text, name="t.csv")
    return info.value


# --------------------------------------------------------------------------- round trips
def test_csv_round_trip_from_path_bytes_and_lines(tmp_path):
    tl = _timeline(300)
    path = export_timeline(tl, "csv", tmp_path / "movie.csv")
    text = path.read_text(encoding="utf-8")
    for back in (import_timeline(path), parse_timeline(text.encode()), read_csv(io.StringIO(text))):
        assert back.n_ticks == tl.n_ticks
        np.testing.assert_allclose(back.vibration, tl.vibration, atol=1e-3)
        np.testing.assert_allclose(back.temperature_c, tl.temperature_c, atol=1e-3)
        np.testing.assert_allclose(back.fans, tl.fans, atol=1e-3)
    imported = import_timeline(path)
    assert imported.source == {"name": "movie.csv", "duration_s": 30.0, "video": None, "audio": None}
    assert imported.generator["mode"] == "imported"


def test_json_round_trip_from_path_and_bytes(tmp_path):
    tl = _timeline(120)
    tl.extra["edits"] = [{"track": "vibration", "actuator": "A3", "from_s": 1.0, "to_s": 2.0, "value": 0.4}]
    path = export_timeline(tl, "json", tmp_path / "movie.json")
    for back in (import_timeline(path), parse_timeline(path.read_bytes())):
        np.testing.assert_allclose(back.vibration, tl.vibration, atol=1e-3)
        np.testing.assert_allclose(back.temperature_c, tl.temperature_c, atol=1e-3)
        np.testing.assert_allclose(back.fans, tl.fans, atol=1e-3)
        assert back.extra["edits"] == tl.extra["edits"]


def test_columns_in_another_order_bom_crlf_and_blank_lines_are_accepted():
    tl = _timeline(30)
    lines = _csv_lines(tl)
    table = [line.split(",") for line in lines]
    perm = list(reversed(range(len(CSV_COLUMNS))))
    shuffled = [",".join(row[i] for i in perm) for row in table]
    text = "\ufeff" + "\r\n".join(shuffled[:10] + [""] + shuffled[10:]) + "\r\n\r\n"
    back = parse_timeline(text.encode("utf-8"))
    np.testing.assert_allclose(back.vibration, tl.vibration, atol=1e-4)
    np.testing.assert_allclose(back.fans, tl.fans, atol=1e-4)


def test_sidecar_next_to_the_csv_is_picked_up(tmp_path):
    tl = _timeline(50)
    tl.source = {"name": "trailer.webm", "duration_s": 5.0, "video": None, "audio": None}
    tl.generator["params"] = {"temp_low": 20.0, "temp_high": 45.0, "thermal": {"neutral_c": 21.5}}
    tl.temperature_c[:10] = 21.5  # the device's neutral point: the chair plays it from tick 0
    path = export_timeline(tl, "csv", tmp_path / "trailer.csv")
    with open(csv_meta_path(path), "w", encoding="utf-8") as fh:
        write_csv_sidecar(tl, fh)
    back = import_timeline(path)
    assert back.source["name"] == "trailer.webm"
    assert back.temp_range == (20.0, 45.0)
    with pytest.raises(TimelineImportError, match=r"column temperature_c: 21.5 is outside 30..55"):
        import_timeline(path, meta=None)


def test_sidecar_with_another_tick_count_is_rejected(tmp_path):
    tl = _timeline(50)
    path = export_timeline(tl, "csv", tmp_path / "a.csv")
    side = io.StringIO()
    write_csv_sidecar(_timeline(40), side)
    with pytest.raises(TimelineImportError, match="n_ticks=40 but the file has 50 data rows"):
        import_timeline(path, meta=json.loads(side.getvalue()))
    with pytest.raises(ParameterError, match="not an autohaptics CSV sidecar"):
        import_timeline(path, meta={"format": "something else"})


# --------------------------------------------------------------------------- errors
def test_a_cell_that_is_not_a_number_names_row_and_column():
    lines = _csv_lines(_timeline())
    _set_cell(lines, 12, "fan_r3_c4", "abc")
    err = _problems("\n".join(lines))
    assert str(err) == "t.csv: row 12, column fan_r3_c4: 'abc' is not a number"
    assert err.problems == [ImportProblem(12, "fan_r3_c4", "'abc' is not a number")]


def test_values_outside_their_range_name_row_and_column():
    lines = _csv_lines(_timeline())
    _set_cell(lines, 40, "A3", "1.7")
    _set_cell(lines, 41, "fan_r0_c0", "-0.2000")
    _set_cell(lines, 42, "temperature_c", "61.0000")
    err = _problems("\n".join(lines))
    text = str(err)
    assert "row 40, column A3: 1.7 is outside 0..1" in text
    assert "row 41, column fan_r0_c0: -0.2 is outside 0..1" in text
    assert "row 42, column temperature_c: 61 is outside 30..55" in text
    assert [(p.row, p.column) for p in err.problems] == [(40, "A3"), (41, "fan_r0_c0"), (42, "temperature_c")]


def test_non_finite_values_are_refused():
    lines = _csv_lines(_timeline())
    _set_cell(lines, 3, "A9", "nan")
    _set_cell(lines, 4, "fan_r8_c16", "inf")
    text = str(_problems("\n".join(lines)))
    assert "row 3, column A9: 'nan' is not a finite number" in text
    assert "row 4, column fan_r8_c16: 'inf' is not a finite number" in text


def test_time_off_the_grid_or_not_the_next_tick():
    lines = _csv_lines(_timeline())
    _set_cell(lines, 5, "time_s", "0.4500")
    _set_cell(lines, 9, "time_s", "0.9000")
    text = str(_problems("\n".join(lines)))
    assert "row 5, column time_s: 0.45 is not on the 100 ms grid" in text
    assert "row 9, column time_s: expected 0.8, got 0.9" in text


def test_missing_unexpected_and_repeated_columns():
    lines = _csv_lines(_timeline(10))
    header = lines[0].split(",")
    no_last = [",".join(line.split(",")[:-1]) for line in lines]
    assert "missing column fan_r8_c16" in str(_problems("\n".join(no_last)))
    renamed = ",".join(header[:-1] + ["wind"])
    text = str(_problems("\n".join([renamed] + lines[1:])))
    assert "missing column fan_r8_c16" in text and "unexpected column wind" in text
    extra = [lines[0] + ",comment"] + [line + ",x" for line in lines[1:]]
    assert "unexpected column comment" in str(_problems("\n".join(extra)))
    twice = ",".join(header[:2] + ["A1"] + header[3:])
    text = str(_problems("\n".join([twice] + lines[1:])))
    assert "column A1: column appears twice" in text and "missing column A2" in text


def test_a_row_with_the_wrong_number_of_fields():
    lines = _csv_lines(_timeline(10))
    lines[3] = ",".join(lines[3].split(",")[:-1])
    assert str(_problems("\n".join(lines))) == "t.csv: row 3: expected 164 fields, got 163"


def test_empty_file_and_header_only():
    assert "the file is empty" in str(_problems(""))
    assert "no data rows" in str(_problems(",".join(CSV_COLUMNS) + "\n"))


def test_many_problems_stop_after_the_limit():
    lines = _csv_lines(_timeline(60))
    for row in range(1, 50):
        _set_cell(lines, row, "A1", "x")
    err = _problems("\n".join(lines))
    assert len(err.problems) == MAX_PROBLEMS
    assert f"stopped after the first {MAX_PROBLEMS}" in str(err)
    assert [p.row for p in err.problems] == list(range(1, MAX_PROBLEMS + 1))


def test_bad_json_and_missing_file(tmp_path):
    with pytest.raises(ParameterError, match=r"^upload: timeline is not valid JSON"):
        parse_timeline(b"{ not json")
    with pytest.raises(ParameterError, match="no such file"):
        import_timeline(tmp_path / "nope.csv")
    with pytest.raises(ParameterError, match="not UTF-8"):
        parse_timeline(b"\xff\xfe\x00bad")


# --------------------------------------------------------------------------- command line
def _parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog="autohaptics")
    sub = parser.add_subparsers(dest="command", required=True)
    cli_export.register(sub)
    cli_importer.register(sub)
    return parser


def test_cli_import_writes_a_timeline_json(tmp_path, capsys):
    tl = _timeline(70)
    csv_path = export_timeline(tl, "csv", tmp_path / "in.csv")
    out = tmp_path / "out.json"
    args = _parser().parse_args(["import", str(csv_path), "-o", str(out)])
    assert args.func(args) == 0
    assert "wrote" in capsys.readouterr().out
    back = Timeline.load(out)
    np.testing.assert_allclose(back.vibration, tl.vibration, atol=1e-3)


def test_cli_export_csv_with_meta_then_import_uses_it(tmp_path, capsys):
    tl = _timeline(40)
    tl.source = {"name": "scene.mkv", "duration_s": 4.0, "video": None, "audio": None}
    src = tl.save(tmp_path / "scene.json")
    parser = _parser()
    args = parser.parse_args(["export", str(src), "--format", "csv", "--meta", "-o", str(tmp_path / "scene.csv")])
    assert args.func(args) == 0
    assert (tmp_path / "scene.meta.json").is_file()
    args = parser.parse_args(["import", str(tmp_path / "scene.csv"), "-o", str(tmp_path / "back.json")])
    assert args.func(args) == 0
    assert "metadata from" in capsys.readouterr().out
    assert Timeline.load(tmp_path / "back.json").source["name"] == "scene.mkv"


def test_cli_import_error_names_row_and_column(tmp_path):
    lines = _csv_lines(_timeline(30))
    _set_cell(lines, 12, "fan_r3_c4", "abc")
    bad = tmp_path / "bad.csv"
    bad.write_text("\n".join(lines) + "\n", encoding="utf-8")
    args = _parser().parse_args(["import", str(bad), "-o", str(tmp_path / "x.json")])
    with pytest.raises(TimelineImportError, match=r"bad.csv: row 12, column fan_r3_c4: 'abc' is not a number"):
        args.func(args)
    assert not (tmp_path / "x.json").exists()
