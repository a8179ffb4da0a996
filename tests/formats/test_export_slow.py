"""A 2-hour timeline (72,000 ticks) exported in every format: it completes and the output parses.

No timing here: ``autohaptics bench export`` prints the time and memory figures.
"""

from __future__ import annotations

import json
import xml.etree.ElementTree as ET
import zipfile

import numpy as np
import pytest

from autohaptics.bench.export import synthetic_timeline
from autohaptics.formats import FORMATS, export_timeline
from autohaptics.formats.hjif import MAX_EFFECT_KEYFRAMES, MAX_EFFECT_MS
from autohaptics.formats.mpegv import SEDL_NS
from autohaptics.formats.importing import import_timeline
from autohaptics.timeline import Timeline

N_TICKS = 72_000


@pytest.fixture(scope="module")
def two_hours() -> Timeline:
    return synthetic_timeline(N_TICKS, seed=0)


@pytest.mark.slow
@pytest.mark.parametrize("fmt", list(FORMATS))
def test_two_hour_export_completes_and_parses(tmp_path, two_hours, fmt):
    path = export_timeline(two_hours, fmt, tmp_path / f"two-hours{FORMATS[fmt].suffix}")
    assert path.stat().st_size > 0
    if fmt in ("csv", "json"):
        back = import_timeline(path)
        assert back.n_ticks == N_TICKS
        np.testing.assert_allclose(back.vibration, two_hours.vibration, atol=1e-3)
        np.testing.assert_allclose(back.temperature_c, two_hours.temperature_c, atol=1e-3)
        np.testing.assert_allclose(back.fans, two_hours.fans, atol=1e-3)
    elif fmt == "ahap":
        with zipfile.ZipFile(path) as zf:
            assert len([n for n in zf.namelist() if n.endswith(".ahap")]) == 9
            for name in zf.namelist():
                if name.endswith(".ahap"):
                    assert any("Event" in item for item in json.loads(zf.read(name))["Pattern"])
                elif name.endswith(".json"):
                    json.loads(zf.read(name))
    elif fmt == "hjif":
        doc = json.loads(path.read_text(encoding="utf-8"))
        assert [len(p["channels"]) for p in doc["perceptions"]] == [9, 1, 153]
        ids = [c["id"] for p in doc["perceptions"] for c in p["channels"]]
        assert len(set(ids)) == len(ids)
        effects = [e for p in doc["perceptions"] for c in p["channels"] for e in c["bands"][0]["effects"]]
        assert max(e["keyframes"][-1]["relative_position"] for e in effects) <= MAX_EFFECT_MS
        assert max(len(e["keyframes"]) for e in effects) <= MAX_EFFECT_KEYFRAMES
    else:
        effects = sum(1 for _, el in ET.iterparse(path) if el.tag == f"{{{SEDL_NS}}}Effect")
        assert effects > 0
