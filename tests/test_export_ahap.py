"""AHAP export: zip layout, documented keys, 30 s event chaining, curve limits, per-tick decode."""

from __future__ import annotations

import io
import json
import zipfile

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from autohaptics.bench.export import synthetic_timeline
from autohaptics.errors import ParameterError
from autohaptics.export import export_timeline
from autohaptics.export.ahap import CURVE_MAX_POINTS, EVENT_MAX_S, pattern_chunks
from autohaptics.layout import ACTUATOR_IDS
from autohaptics.timeline import Timeline


def _timeline(n: int = 1200, seed: int = 4) -> Timeline:
    tl = synthetic_timeline(n, seed=seed)
    tl.vibration[:, 0] = 0.0
    tl.vibration[100:550, 0] = 0.75  # 45 s constant: two chained events (30 s + 15 s)
    tl.vibration[:, 1] = 0.0  # A2 silent throughout
    tl.vibration[:, 2] = 0.0
    tl.vibration[200:260, 2] = (500 + 150 * np.arange(60)) / 10_000  # an exact ramp 0.05..0.935
    tl.vibration[300:340, 2] = np.round(np.random.default_rng(9).uniform(0.1, 1.0, 40), 4)  # busy
    return tl


def _export(tl: Timeline, **options) -> zipfile.ZipFile:
    buf = io.BytesIO()
    export_timeline(tl, "ahap", buf, **options)
    return zipfile.ZipFile(io.BytesIO(buf.getvalue()))


def decode_pattern(doc: dict, n_ticks: int) -> np.ndarray:
    """Per-tick intensity of one AHAP pattern: event intensity x HapticIntensityControl curve.

    Events cover [Time, Time + EventDuration); the curve in force at time t is the one that started
    last at or before t, linear between its control points (Core Haptics' default control is 1).
    """
    on = np.zeros(n_ticks, dtype=bool)
    level = np.zeros(n_ticks)
    curves = []
    for item in doc["Pattern"]:
        if "Event" in item:
            ev = item["Event"]
            params = {p["ParameterID"]: p["ParameterValue"] for p in ev["EventParameters"]}
            a = round(ev["Time"] * 10)
            b = round((ev["Time"] + ev["EventDuration"]) * 10)
            on[a:b] = True
            level[a:b] = params["HapticIntensity"]
        else:
            c = item["ParameterCurve"]
            xs = [c["Time"] + p["Time"] for p in c["ParameterCurveControlPoints"]]
            ys = [p["ParameterValue"] for p in c["ParameterCurveControlPoints"]]
            curves.append((c["Time"], xs, ys))
    curves.sort(key=lambda c: c[0])
    control = np.ones(n_ticks)
    t = np.arange(n_ticks) / 10
    starts = np.array([c[0] for c in curves])
    for k in np.flatnonzero(on):
        i = np.searchsorted(starts, t[k] + 1e-9, side="right") - 1
        if i >= 0:
            _, xs, ys = curves[i]
            assert t[k] <= xs[-1] + 1e-9, f"tick {k} lies after the end of the curve in force"
            control[k] = np.interp(t[k], xs, ys)
    return np.where(on, level * control, 0.0)


def test_zip_holds_nine_patterns_a_manifest_and_a_readme():
    zf = _export(_timeline())
    names = zf.namelist()
    assert sorted(names) == sorted([f"{a}.ahap" for a in ACTUATOR_IDS] + ["manifest.json", "README.txt"])
    manifest = json.loads(zf.read("manifest.json"))
    assert manifest["format"] == "autohaptics.ahap-set" and manifest["n_ticks"] == 1200
    assert [f["actuator"] for f in manifest["files"]] == list(ACTUATOR_IDS)
    assert {f["zone"] for f in manifest["files"]} == {"back", "armrests", "seat"}
    assert "A3.ahap  left armrest" in zf.read("README.txt").decode()


def test_documented_keys_and_limits():
    zf = _export(_timeline(), sharpness=0.3)
    manifest = json.loads(zf.read("manifest.json"))
    for entry in manifest["files"]:
        doc = json.loads(zf.read(entry["file"]))
        assert doc["Version"] == 1.0
        assert doc["Metadata"]["Actuator"] == entry["actuator"]
        assert {"Project", "Created", "Description"} <= set(doc["Metadata"])
        events = [i["Event"] for i in doc["Pattern"] if "Event" in i]
        curves = [i["ParameterCurve"] for i in doc["Pattern"] if "ParameterCurve" in i]
        assert len(events) == entry["events"] and len(curves) == entry["curves"]
        for ev in events:
            assert ev["EventType"] == "HapticContinuous"
            assert 0 < ev["EventDuration"] <= EVENT_MAX_S
            params = {p["ParameterID"]: p["ParameterValue"] for p in ev["EventParameters"]}
            assert params == {"HapticIntensity": 1.0, "HapticSharpness": 0.3}
        for c in curves:
            assert c["ParameterID"] == "HapticIntensityControl"
            pts = c["ParameterCurveControlPoints"]
            assert 2 <= len(pts) <= CURVE_MAX_POINTS
            times = [p["Time"] for p in pts]
            assert times[0] == 0 and times == sorted(times)
            assert all(0.0 <= p["ParameterValue"] <= 1.0 for p in pts)


def test_every_actuator_decodes_back_to_its_ticks():
    tl = _timeline()
    zf = _export(tl)
    for i, aid in enumerate(ACTUATOR_IDS):
        decoded = decode_pattern(json.loads(zf.read(f"{aid}.ahap")), tl.n_ticks)
        np.testing.assert_allclose(decoded, tl.vibration[:, i], atol=1e-4, err_msg=aid)


def test_silence_has_no_events_and_long_stretches_are_chained():
    zf = _export(_timeline())
    assert json.loads(zf.read("A2.ahap"))["Pattern"] == []
    a1 = json.loads(zf.read("A1.ahap"))
    events = [i["Event"] for i in a1["Pattern"] if "Event" in i]
    assert [(e["Time"], e["EventDuration"]) for e in events] == [(10.0, 30.0), (40.0, 15.0)]
    curve_times = [i["ParameterCurve"]["Time"] for i in a1["Pattern"] if "ParameterCurve" in i]
    assert curve_times == [10.0, 40.0]  # one curve per event: a constant needs two points


def test_busy_stretches_chain_curves_of_at_most_16_points():
    zf = _export(_timeline())
    a3 = json.loads(zf.read("A3.ahap"))
    curves = [i["ParameterCurve"] for i in a3["Pattern"] if "ParameterCurve" in i]
    assert len(curves) >= 3
    for prev, nxt in zip(curves, curves[1:]):
        last = prev["ParameterCurveControlPoints"][-1]
        first = nxt["ParameterCurveControlPoints"][0]
        if abs(prev["Time"] + last["Time"] - nxt["Time"]) < 1e-9:  # chained within one event
            assert first["ParameterValue"] == last["ParameterValue"]
    ramp = [c for c in curves if c["Time"] == 20.0]
    assert len(ramp) == 1 and len(ramp[0]["ParameterCurveControlPoints"]) == 3  # ramp, then hold


def test_sharpness_must_be_in_range_and_ahap_needs_a_binary_stream():
    with pytest.raises(ParameterError, match="sharpness"):
        _export(Timeline.empty(50), sharpness=1.5)
    with pytest.raises(ParameterError, match="binary"):
        export_timeline(Timeline.empty(50), "ahap", io.StringIO())


_runs = st.lists(st.tuples(st.one_of(st.just(0), st.integers(1, 10_000)), st.integers(1, 420)),
                 min_size=1, max_size=6)


@settings(max_examples=60, deadline=None)
@given(_runs)
def test_any_run_pattern_decodes_exactly(runs):
    q = np.repeat([v for v, _ in runs], [m for _, m in runs]).astype(np.int64)
    doc = json.loads("".join(pattern_chunks(q, actuator="A5", title="t", created="2024-01-01")))
    for item in doc["Pattern"]:
        if "Event" in item:
            assert item["Event"]["EventDuration"] <= EVENT_MAX_S
        else:
            assert len(item["ParameterCurve"]["ParameterCurveControlPoints"]) <= CURVE_MAX_POINTS
    np.testing.assert_allclose(decode_pattern(doc, q.shape[0]), q / 10_000, atol=1e-9)
