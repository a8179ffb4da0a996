"""CSV export: header, fixed decimals, streaming writes, sidecar, round trip through the importer."""

from __future__ import annotations

import csv
import io
import json
import re

import numpy as np
import pytest

from autohaptics.bench.export import synthetic_timeline
from autohaptics.formats import export_timeline
from autohaptics.formats.csv import CSV_COLUMNS, sidecar_dict, write_csv, write_csv_sidecar
from autohaptics.formats.importing import import_timeline, parse_timeline
from autohaptics.layout import FAN_COLS, FAN_ROWS


def _timeline(n: int = 1500, seed: int = 11):
    tl = synthetic_timeline(n, seed=seed)
    tl.vibration[:200] = 0.0  # a silent opening
    tl.vibration[300:700, 4] = 0.3333  # a long constant stretch
    tl.fans[50:60, 0, 0] = 1.0  # top-left fan
    tl.fans[50:60, FAN_ROWS - 1, FAN_COLS - 1] = 0.25  # bottom-right fan
    tl.extra["markers"] = [{"t": 1.5, "label": "door slam"}]
    return tl


def _export_text(tl) -> str:
    buf = io.StringIO()
    export_timeline(tl, "csv", buf)
    return buf.getvalue()


def test_header_names_every_column_in_order():
    rows = list(csv.reader(io.StringIO(_export_text(_timeline(30)))))
    header = rows[0]
    assert len(header) == 1 + 9 + 1 + FAN_ROWS * FAN_COLS == 164
    assert header[:11] == ["time_s", "A1", "A2", "A3", "A4", "A5", "A6", "A7", "A8", "A9", "temperature_c"]
    assert header[11] == "fan_r0_c0" and header[12] == "fan_r0_c1"
    assert header[11 + FAN_COLS] == "fan_r1_c0"
    assert header[-1] == f"fan_r{FAN_ROWS - 1}_c{FAN_COLS - 1}"
    assert tuple(header) == CSV_COLUMNS


def test_one_row_per_tick_with_four_decimals_and_no_comment_lines():
    tl = _timeline(250)
    text = _export_text(tl)
    lines = text.split("\n")
    assert lines[-1] == "" and len(lines) == 1 + tl.n_ticks + 1  # header, ticks, final newline
    assert not any(line.startswith("#") for line in lines)
    fixed = re.compile(r"^-?\d+\.\d{4}$")
    for line in lines[1:-1]:
        cells = line.split(",")
        assert len(cells) == 164
        assert all(fixed.match(c) for c in cells), line[:80]
    assert lines[1].startswith("0.0000,") and lines[2].startswith("0.1000,")
    assert lines[tl.n_ticks].startswith(f"{(tl.n_ticks - 1) / 10:.4f},")


def test_values_match_the_tracks_cell_by_cell():
    tl = _timeline(400)
    rows = list(csv.reader(io.StringIO(_export_text(tl))))[1:]
    data = np.array(rows, dtype=np.float64)
    np.testing.assert_allclose(data[:, 0], np.arange(tl.n_ticks) / 10, atol=1e-9)
    np.testing.assert_allclose(data[:, 1:10], tl.vibration, atol=5e-5)
    np.testing.assert_allclose(data[:, 10], tl.temperature_c, atol=5e-5)
    np.testing.assert_allclose(data[:, 11:].reshape(-1, FAN_ROWS, FAN_COLS), tl.fans, atol=5e-5)
    assert data[55, 11] == 1.0 and data[55, -1] == 0.25


class _RecordingStream(io.StringIO):
    def __init__(self):
        super().__init__()
        self.sizes: list[int] = []

    def write(self, s: str) -> int:
        self.sizes.append(len(s))
        return super().write(s)


def test_writes_in_blocks_not_one_string():
    tl = _timeline(3000)
    stream = _RecordingStream()
    write_csv(tl, stream)
    total = sum(stream.sizes)
    assert len(stream.sizes) >= 5  # header + several row blocks
    assert max(stream.sizes) < total / 4


def test_sidecar_keeps_the_metadata_out_of_the_csv():
    tl = _timeline(40)
    tl.source = {"name": "clip.mp4", "duration_s": 4.0, "video": None, "audio": None}
    buf = io.StringIO()
    write_csv_sidecar(tl, buf)
    doc = json.loads(buf.getvalue())
    assert doc == json.loads(json.dumps(sidecar_dict(tl)))
    assert doc["format"] == "autohaptics.timeline.csv-meta" and doc["n_ticks"] == 40
    assert doc["source"]["name"] == "clip.mp4"
    assert doc["columns"] == list(CSV_COLUMNS)
    assert doc["extra"]["markers"][0]["label"] == "door slam"
    assert "clip.mp4" not in _export_text(tl)


@pytest.mark.parametrize("seed", [1, 2, 3])
def test_exported_csv_imports_back_within_1e3(tmp_path, seed):
    tl = _timeline(1200, seed=seed)
    path = export_timeline(tl, "csv", tmp_path / "t.csv")
    back = import_timeline(path)
    assert back.n_ticks == tl.n_ticks
    np.testing.assert_allclose(back.vibration, tl.vibration, atol=1e-3)
    np.testing.assert_allclose(back.temperature_c, tl.temperature_c, atol=1e-3)
    np.testing.assert_allclose(back.fans, tl.fans, atol=1e-3)


def test_round_trip_through_bytes_restores_metadata_from_the_sidecar():
    tl = _timeline(60)
    # a device whose neutral point is 25 C: the chair plays 25 C from the first tick
    tl.generator["params"] = {"temp_low": 20.0, "temp_high": 40.0, "thermal": {"neutral_c": 25.0}}
    tl.temperature_c[:] = 25.0  # inside 20..40 but outside the default 30..55
    side = io.StringIO()
    write_csv_sidecar(tl, side)
    data = _export_text(tl).encode()
    back = parse_timeline(data, meta=json.loads(side.getvalue()))
    assert back.temp_range == (20.0, 40.0)
    assert back.extra["markers"] == tl.extra["markers"]
    np.testing.assert_allclose(back.temperature_c, 25.0)
