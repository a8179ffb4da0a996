"""MPEG-V SEM export: namespaced well-formed XML, effects only on changes, per-tick decode."""

from __future__ import annotations

import io
import xml.etree.ElementTree as ET

import numpy as np

from autohaptics.bench.export import synthetic_timeline
from autohaptics.formats import export_timeline
from autohaptics.formats.mpegv import AH_NS, LOCATION_CS, SEDL_NS, SI_NS, XSI_NS, fan_location
from autohaptics.layout import ACTUATOR_IDS, FAN_COLS, FAN_ROWS
from autohaptics.timeline import Timeline

SEV_TYPES = {"sev:VibrationType", "sev:TemperatureType", "sev:WindType"}


def _timeline(n: int = 900, seed: int = 21) -> Timeline:
    tl = synthetic_timeline(n, seed=seed)
    tl.vibration[:, 3] = 0.0
    tl.vibration[100:400, 3] = 0.25  # A4: one on, one off
    tl.fans[n - 10:, 4, 8] = 0.5  # still on at the end
    tl.source["name"] = "a -- b <c> & d.mp4"  # must not break the XML comment
    return tl


def _export(tl: Timeline) -> ET.Element:
    buf = io.StringIO()
    export_timeline(tl, "mpegv", buf)
    return ET.fromstring(buf.getvalue().encode("utf-8"))


def _a(el: ET.Element, ns: str, name: str) -> str | None:
    return el.get(f"{{{ns}}}{name}")


def decode_sem(root: ET.Element, n_ticks: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Per-tick (vibration, temperature, fans): each channel holds its last effect's value from
    its pts on; activate="false" means 0 (temperature: NaN)."""
    scale = int(_a(root, SI_NS, "timeScale"))
    vib = np.zeros((n_ticks, 9))
    temp = np.full(n_ticks, np.nan)
    fans = np.zeros((n_ticks, FAN_ROWS, FAN_COLS))
    for eff in root.iter(f"{{{SEDL_NS}}}Effect"):
        k = round(int(_a(eff, SI_NS, "pts")) * 10 / scale)
        active = eff.get("activate") == "true"
        kind = _a(eff, XSI_NS, "type")
        if kind == "sev:TemperatureType":
            temp[k:] = float(eff.get("intensity-value")) if active else np.nan
            continue
        lo, hi = (float(x) for x in eff.get("intensity-range", "0 100").split())
        level = (float(eff.get("intensity-value")) - lo) / (hi - lo) if active else 0.0
        if kind == "sev:VibrationType":
            vib[k:, ACTUATOR_IDS.index(_a(eff, AH_NS, "actuator"))] = level
        else:
            r, c = _a(eff, AH_NS, "fan")[1:].split("c")
            fans[k:, int(r), int(c)] = level
    return vib, temp, fans


def test_root_is_a_namespaced_sem_with_a_timescale():
    root = _export(_timeline())
    assert root.tag == f"{{{SEDL_NS}}}SEM"
    assert _a(root, SI_NS, "timeScale") == "1000"
    children = list(root)
    assert children and all(c.tag == f"{{{SEDL_NS}}}Effect" for c in children)


def test_every_effect_has_the_documented_attributes():
    root = _export(_timeline())
    last_pts = -1
    for eff in root:
        kind = _a(eff, XSI_NS, "type")
        assert kind in SEV_TYPES
        pts = int(_a(eff, SI_NS, "pts"))
        assert pts % 100 == 0 and pts >= last_pts
        last_pts = pts
        assert eff.get("activate") in ("true", "false")
        if eff.get("activate") == "true":
            lo, hi = (float(x) for x in eff.get("intensity-range").split())
            assert lo <= float(eff.get("intensity-value")) <= hi
        if kind == "sev:VibrationType":
            assert _a(eff, AH_NS, "actuator") in ACTUATOR_IDS
            assert eff.get("location").startswith(LOCATION_CS + ":")
        if kind == "sev:WindType":
            r, c = (int(x) for x in _a(eff, AH_NS, "fan")[1:].split("c"))
            assert eff.get("location") == f"{LOCATION_CS}:{fan_location(r, c)}"
    assert fan_location(0, 0) == "left:top:front" and fan_location(8, 16) == "right:bottom:front"


def test_all_tracks_decode_back_to_their_ticks():
    tl = _timeline()
    vib, temp, fans = decode_sem(_export(tl), tl.n_ticks)
    np.testing.assert_allclose(vib, tl.vibration, atol=1e-4)
    np.testing.assert_allclose(temp, tl.temperature_c, atol=1e-4)
    np.testing.assert_allclose(fans, tl.fans, atol=1e-4)


def test_effects_only_where_something_changes():
    tl = _timeline()
    root = _export(tl)
    n = tl.n_ticks
    levels = np.concatenate([tl.vibration, tl.fans.reshape(n, -1)], axis=1)
    q = np.rint(levels * 10_000)
    changes = int(np.count_nonzero(q[0])) + int(np.count_nonzero(q[1:] != q[:-1]))
    qt = np.rint(tl.temperature_c * 10_000)
    temp_changes = 1 + int(np.count_nonzero(qt[1:] != qt[:-1]))
    still_on = 1 + int(np.count_nonzero(q[-1]))  # temperature and every active channel end at n
    assert len(list(root)) == changes + temp_changes + still_on
    a4 = [(int(_a(e, SI_NS, "pts")), e.get("activate"))
          for e in root if _a(e, AH_NS, "actuator") == "A4"]
    assert a4 == [(10_000, "true"), (40_000, "false")]
    ends = [e for e in root if int(_a(e, SI_NS, "pts")) == n * 100]
    assert all(e.get("activate") == "false" for e in ends)
    assert any(_a(e, AH_NS, "fan") == "r4c8" for e in ends)


def test_a_constant_timeline_costs_a_few_effects():
    tl = Timeline.empty(36_000)
    root = _export(tl)
    kinds = [(_a(e, XSI_NS, "type"), e.get("activate"), _a(e, SI_NS, "pts")) for e in root]
    assert kinds == [("sev:TemperatureType", "true", "0"), ("sev:TemperatureType", "false", "3600000")]
    tl.vibration[:, 0] = 0.5
    assert len(list(_export(tl))) == 4
