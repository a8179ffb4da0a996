"""The date an export carries: one option (``date``, ``--date``), else $SOURCE_DATE_EPOCH, else now.

No export depends on the day it is made once its date is given: the same timeline gives the same
bytes (zip stamps included) under any clock, including a clock really moved (libfaketime).
"""

from __future__ import annotations

import datetime
import io
import json
import os
import shutil
import subprocess
import sys
import zipfile
from pathlib import Path

import pytest

from autohaptics.bench.export import synthetic_timeline
from autohaptics.cli.main import main
from autohaptics.errors import ParameterError
from autohaptics.formats import FORMATS, export_timeline
from autohaptics.formats.common import DATE_ENV, export_time

# two instants a year and a half apart, at different hours, in UTC
_EPOCHS = {"2025-03-04": 1741098896, "2026-09-30": 1790800000}


def _export(fmt: str, **options) -> bytes:
    buf = io.BytesIO()
    export_timeline(synthetic_timeline(80, seed=3), fmt, buf, **options)
    return buf.getvalue()


def _dates(fmt: str, data: bytes) -> set[str]:
    """Every date the export carries, as ISO strings (zip stamps included)."""
    if fmt == "hjif":
        return {json.loads(data)["date"]}
    if fmt == "ahap":
        zf = zipfile.ZipFile(io.BytesIO(data))
        found = {datetime.datetime(*i.date_time).date().isoformat() for i in zf.infolist()}
        found.add(json.loads(zf.read("manifest.json"))["created"])
        for name in zf.namelist():
            if name.endswith(".ahap"):
                found.add(json.loads(zf.read(name))["Metadata"]["Created"])
        return found
    return set()


@pytest.mark.parametrize("fmt", list(FORMATS))
def test_a_given_date_makes_the_same_bytes_under_any_clock(fmt, monkeypatch):
    outputs = []
    for epoch in _EPOCHS.values():
        monkeypatch.setenv(DATE_ENV, str(epoch))
        outputs.append(_export(fmt, **({"date": "2024-02-29"} if "date" in FORMATS[fmt].options else {})))
    assert outputs[0] == outputs[1]
    assert _dates(fmt, outputs[0]) <= {"2024-02-29"}


@pytest.mark.parametrize("fmt", list(FORMATS))
def test_every_format_that_carries_a_date_takes_it_from_the_option(fmt, monkeypatch):
    """A format whose bytes follow the clock must take ``date``; one that takes it must carry it."""
    outputs = {}
    for day, epoch in _EPOCHS.items():
        monkeypatch.setenv(DATE_ENV, str(epoch))
        outputs[day] = _export(fmt)
        assert _dates(fmt, outputs[day]) <= {day}
    takes = "date" in FORMATS[fmt].options
    assert (len(set(outputs.values())) > 1) == takes
    if takes:
        assert _dates(fmt, outputs["2025-03-04"]) == {"2025-03-04"}


def test_without_date_or_epoch_an_export_is_dated_now(monkeypatch):
    monkeypatch.delenv(DATE_ENV, raising=False)
    before = datetime.datetime.now() - datetime.timedelta(seconds=2)
    got = export_time()
    assert before <= got <= datetime.datetime.now() + datetime.timedelta(seconds=2)
    assert export_time("2027-01-31") == datetime.datetime(2027, 1, 31)


@pytest.mark.parametrize("bad", ["2026-13-01", "2026-02-30", "tomorrow", "20260101", "2026-1-1", ""])
def test_a_malformed_date_is_one_clear_error(bad, tmp_path, capsys):
    with pytest.raises(ParameterError, match="YYYY-MM-DD"):
        _export("hjif", date=bad)
    src = tmp_path / "t.json"
    synthetic_timeline(20, seed=1).save(src)
    assert main(["export", str(src), "--format", "ahap", "-o", str(tmp_path / "o.zip"), "--date", bad]) == 2
    assert "YYYY-MM-DD" in capsys.readouterr().err
    assert not (tmp_path / "o.zip").exists()


def test_a_malformed_epoch_is_one_clear_error(monkeypatch):
    monkeypatch.setenv(DATE_ENV, "yesterday")
    with pytest.raises(ParameterError, match=DATE_ENV):
        _export("ahap")


def test_the_cli_date_applies_to_every_format(tmp_path, monkeypatch):
    """``--date`` is accepted whatever the format; the formats without a date ignore it."""
    monkeypatch.setenv(DATE_ENV, str(_EPOCHS["2026-09-30"]))
    src = tmp_path / "t.json"
    synthetic_timeline(30, seed=2).save(src)
    for fmt in FORMATS:
        out = tmp_path / f"o.{fmt}"
        assert main(["export", str(src), "--format", fmt, "-o", str(out), "--date", "2023-07-08"]) == 0
        assert _dates(fmt, out.read_bytes()) <= {"2023-07-08"}


@pytest.mark.slow
def test_the_export_goldens_hold_with_the_clock_a_year_ahead(tmp_path):
    """The golden export check in a process whose clock libfaketime sets a year and a day ahead, at 23:30."""
    faketime = shutil.which("faketime")
    if faketime is None:
        pytest.fail("faketime not found on PATH: install it with `apt-get install faketime`")
    tests = Path(__file__).resolve().parents[1]
    script = (
        "import datetime, json, pathlib, sys\n"
        f"sys.path.insert(0, {str(tests)!r})\n"
        "import goldens\n"
        "stored = json.loads((goldens.GOLDEN / 'exports.json').read_text())\n"
        "work = pathlib.Path(sys.argv[1])\n"
        "same = all(goldens.export_digests(goldens.load_golden(*c), work) == stored[goldens.case_name(*c)]\n"
        "           for c in goldens.EXPORT_CASES)\n"
        "print(json.dumps({'today': datetime.date.today().isoformat(), 'same': same}))\n"
    )
    env = {k: v for k, v in os.environ.items() if k != DATE_ENV}
    ahead = datetime.date.today() + datetime.timedelta(days=366)
    argv = [faketime, "-f", f"@{ahead.isoformat()} 23:30:00", sys.executable, "-c", script, str(tmp_path)]
    proc = subprocess.run(argv, capture_output=True, text=True, env=env, timeout=600)
    assert proc.returncode == 0, proc.stderr[-2000:]
    got = json.loads(proc.stdout.strip().splitlines()[-1])
    assert got["today"] == ahead.isoformat(), got  # the clock really moved
    assert got["same"], "an export golden differs with the clock a year ahead"
