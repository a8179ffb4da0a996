"""Native JSON export: the timeline file itself, lossless to 4 decimals including extra keys."""

from __future__ import annotations

import io
import json

import numpy as np

from autohaptics.bench.export import synthetic_timeline
from autohaptics.formats import export_timeline
from autohaptics.timeline import FORMAT, Timeline


def _timeline() -> Timeline:
    tl = synthetic_timeline(600, seed=2)
    tl.features["loudness"] = np.round(np.linspace(0, 1, 600), 4).astype(np.float32)
    tl.extra["edits"] = [{"track": "fans", "row": 2, "col": 3, "from_s": 3.0, "to_s": 4.5, "value": 0.0}]
    tl.extra["markers"] = [{"t": 12.3, "label": "explosion"}]
    return tl


def test_json_export_is_the_timeline_file(tmp_path):
    tl = _timeline()
    path = export_timeline(tl, "json", tmp_path / "t.json")
    doc = json.loads(path.read_text(encoding="utf-8"))
    assert doc["format"] == FORMAT and doc["version"] == 1 and doc["n_ticks"] == 600
    back = Timeline.load(path)
    np.testing.assert_allclose(back.vibration, tl.vibration, atol=5e-5)
    np.testing.assert_allclose(back.temperature_c, tl.temperature_c, atol=5e-5)
    np.testing.assert_allclose(back.fans, tl.fans, atol=5e-5)
    np.testing.assert_allclose(back.features["loudness"], tl.features["loudness"], atol=5e-5)
    assert back.extra == tl.extra
    assert back.source == tl.source and back.generator == tl.generator


def test_stream_and_path_give_the_same_bytes(tmp_path):
    tl = _timeline()
    path = export_timeline(tl, "json", tmp_path / "t.json")
    text, binary = io.StringIO(), io.BytesIO()
    export_timeline(tl, "json", text)
    export_timeline(tl, "json", binary)
    assert path.read_bytes() == text.getvalue().encode("utf-8") == binary.getvalue()
