"""The export registry, export_timeline on paths and streams, the export CLI and its benchmark."""

from __future__ import annotations

import argparse
import io
import json
import xml.etree.ElementTree as ET
import zipfile

import numpy as np
import pytest

from autohaptics.bench import export as bench_export
from autohaptics.bench.export import synthetic_timeline
from autohaptics.cli import export as cli_export
from autohaptics.cli import importer as cli_importer
from autohaptics.cli import main as cli_main
from autohaptics.cli.main import main
from autohaptics.errors import ParameterError
from autohaptics.formats import FORMATS, export_timeline, get_format
from autohaptics.timeline import Timeline


def _timeline(n: int = 300) -> Timeline:
    return synthetic_timeline(n, seed=7)


def _parses(fmt: str, data: bytes) -> None:
    if fmt in ("csv",):
        assert data.decode("utf-8").startswith("time_s,A1,")
    elif fmt in ("json", "hjif"):
        json.loads(data)
    elif fmt == "ahap":
        with zipfile.ZipFile(io.BytesIO(data)) as zf:
            for name in zf.namelist():
                if name.endswith((".ahap", ".json")):
                    json.loads(zf.read(name))
    else:
        ET.fromstring(data)


def test_registry_lists_the_five_formats():
    assert list(FORMATS) == ["csv", "json", "ahap", "hjif", "mpegv"]
    assert {f.suffix for f in FORMATS.values()} == {".csv", ".json", ".zip", ".hjif", ".xml"}
    assert [f.name for f in FORMATS.values() if f.binary] == ["ahap"]
    assert get_format("HJIF") is FORMATS["hjif"]
    with pytest.raises(ParameterError, match="unknown export format 'wav'; choose one of csv, json, ahap"):
        get_format("wav")


@pytest.mark.parametrize("fmt", list(FORMATS))
def test_path_and_binary_stream_exports_parse(tmp_path, fmt):
    tl = _timeline()
    spec = FORMATS[fmt]
    path = export_timeline(tl, fmt, tmp_path / f"out{spec.suffix}")
    assert path.is_file() and not (tmp_path / f"out{spec.suffix}.part").exists()
    _parses(fmt, path.read_bytes())
    buf = io.BytesIO()
    assert export_timeline(tl, fmt, buf) is None
    _parses(fmt, buf.getvalue())
    if not spec.binary:
        assert buf.getvalue() == path.read_bytes()


def test_options_are_checked_against_the_format():
    tl = _timeline(20)
    with pytest.raises(ParameterError, match="export format csv takes no option sharpness"):
        export_timeline(tl, "csv", io.StringIO(), sharpness=0.2)
    with pytest.raises(ParameterError, match=r"takes: date"):
        export_timeline(tl, "hjif", io.StringIO(), colour="red")


def test_an_invalid_timeline_leaves_no_file(tmp_path):
    tl = _timeline(20)
    tl.vibration[3, 2] = np.nan
    with pytest.raises(ParameterError, match="vibration"):
        export_timeline(tl, "csv", tmp_path / "bad.csv")
    assert list(tmp_path.iterdir()) == []


def test_a_plain_list_timeline_is_validated_and_exported():
    tl = Timeline.empty(5)
    tl.vibration = [[0.5] * 9] * 5  # lists, not arrays: converted by Timeline.validate
    buf = io.StringIO()
    export_timeline(tl, "csv", buf)
    assert buf.getvalue().split("\n")[1].startswith("0.0000,0.5000,0.5000")


def _cli() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog="autohaptics")
    sub = parser.add_subparsers(dest="command", required=True)
    cli_export.register(sub)
    return parser


@pytest.mark.parametrize("fmt", list(FORMATS))
def test_cli_export_every_format(tmp_path, capsys, fmt):
    src = _timeline(120).save(tmp_path / "in.json")
    out = tmp_path / f"out{FORMATS[fmt].suffix}"
    args = _cli().parse_args(["export", str(src), "--format", fmt, "-o", str(out)])
    assert args.func(args) == 0
    assert f"wrote {out} ({fmt}, 120 ticks" in capsys.readouterr().out
    _parses(fmt, out.read_bytes())


def test_cli_export_to_stdout_and_format_specific_options(tmp_path, capsysbinary):
    src = _timeline(40).save(tmp_path / "in.json")
    args = _cli().parse_args(["export", str(src), "-f", "mpegv", "-o", "-"])
    assert args.func(args) == 0
    ET.fromstring(capsysbinary.readouterr().out)
    args = _cli().parse_args(["export", str(src), "-f", "ahap", "--sharpness", "0.9", "-o", str(tmp_path / "a.zip")])
    assert args.func(args) == 0
    manifest = json.loads(zipfile.ZipFile(tmp_path / "a.zip").read("manifest.json"))
    assert manifest["sharpness"] == 0.9
    args = _cli().parse_args(["export", str(src), "-f", "ahap", "--meta", "-o", str(tmp_path / "b.zip")])
    with pytest.raises(ParameterError, match="--meta applies to --format csv only"):
        args.func(args)


def test_cli_errors_are_one_line(tmp_path, capsys, monkeypatch):
    # main()'s own error handling, over a parser holding just the export and import commands
    # (the full parser imports every command module of the package).
    def parser(command=None) -> argparse.ArgumentParser:
        p = argparse.ArgumentParser(prog="autohaptics")
        sub = p.add_subparsers(dest="command", required=True)
        cli_export.register(sub)
        cli_importer.register(sub)
        return p

    monkeypatch.setattr(cli_main, "build_parser", parser)
    rc = main(["export", str(tmp_path / "missing.json"), "--format", "csv", "-o", str(tmp_path / "x.csv")])
    err = capsys.readouterr().err
    assert rc == 2 and err.count("\n") == 1 and "missing.json: no such file" in err
    bad = tmp_path / "bad.csv"
    bad.write_text("time_s,A1\n0.0,0.5\n", encoding="utf-8")
    rc = main(["import", str(bad), "-o", str(tmp_path / "x.json")])
    err = capsys.readouterr().err
    assert rc == 2 and err.count("\n") == 1 and "missing columns A2, A3" in err


def test_bench_export_prints_time_and_memory_per_format(capsys):
    parser = argparse.ArgumentParser()
    sub = parser.add_subparsers(dest="bench", required=True)
    bench_export.register(sub)
    args = parser.parse_args(["export", "--hours", "0.02"])
    assert args.func(args) == 0
    out = capsys.readouterr().out
    assert "timeline: 720 ticks" in out
    assert "peak_rss_MiB" in out and "wall_s" in out
    for fmt in FORMATS:
        assert any(line.split()[:1] == [fmt] for line in out.splitlines()), fmt


def test_synthetic_timeline_is_deterministic_and_film_like():
    a, b = synthetic_timeline(3000, seed=3), synthetic_timeline(3000, seed=3)
    np.testing.assert_array_equal(a.vibration, b.vibration)
    assert (a.vibration == 0).all(axis=1).any()  # silent stretches
    assert (a.fans > 0).any() and (a.fans == 0).all(axis=(1, 2)).any()
    assert np.unique(a.temperature_c).size > 10
    assert np.array_equal(np.round(a.vibration, 4), a.vibration)  # already on the 4-decimal grid
