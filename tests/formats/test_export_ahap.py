"""AHAP export: zip layout, documented keys, 30 s event chaining, curve limits, per-tick decode."""

from __future__ import annotations

import datetime
import io
import json
import stat
import zipfile

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from autohaptics.bench.export import synthetic_timeline
from autohaptics.errors import ParameterError
from autohaptics.formats import export_timeline
from autohaptics.formats.ahap import CURVE_MAX_POINTS, EVENT_MAX_S, pattern_chunks
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


def decode_pattern(doc: dict, n_ticks: int, *, wins: str = "last") -> np.ndarray:
    """Per-tick level of one AHAP pattern, read as a player would: event intensity x the
    HapticIntensityControl curve value (Core Haptics' default control is 1).

    An event plays over [Time, Time + EventDuration). A curve gives a value from its first to its
    last control point inclusive, linear in between. Where several curves (or events) give a value
    at one instant, ``wins`` = "first" takes the one that comes first in the file, "last" the one
    that comes last: Apple documents neither, so an exported file must read the same both ways.
    A tick inside an event that no curve covers, after some curve has started, fails: the file
    would rely on an undocumented hold.
    """
    assert wins in ("first", "last")
    t = np.arange(n_ticks) / 10
    eps = 1e-9
    intensity = np.full(n_ticks, np.nan)
    control = np.full(n_ticks, np.nan)
    first_curve = np.inf
    for item in doc["Pattern"]:
        if "Event" in item:
            ev = item["Event"]
            params = {p["ParameterID"]: p["ParameterValue"] for p in ev["EventParameters"]}
            cover = (t >= ev["Time"] - eps) & (t < ev["Time"] + ev["EventDuration"] - eps)
            value = np.full(n_ticks, float(params["HapticIntensity"]))
            target = intensity
        else:
            c = item["ParameterCurve"]
            assert c["ParameterID"] == "HapticIntensityControl"
            xs = np.array([c["Time"] + p["Time"] for p in c["ParameterCurveControlPoints"]])
            ys = np.array([p["ParameterValue"] for p in c["ParameterCurveControlPoints"]])
            first_curve = min(first_curve, xs[0])
            cover = (t >= xs[0] - eps) & (t <= xs[-1] + eps)
            value = np.interp(t, xs, ys)
            target = control
        if wins == "first":
            cover &= np.isnan(target)
        target[cover] = value[cover]
    on = ~np.isnan(intensity)
    uncovered = on & np.isnan(control) & (t >= first_curve - eps)
    assert not uncovered.any(), f"ticks {np.flatnonzero(uncovered)[:5]} lie after a curve ended"
    control[np.isnan(control)] = 1.0
    return np.where(on, np.nan_to_num(intensity) * control, 0.0)


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
            silent = entry["active_ticks"] == 0  # the one event of a silent actuator plays nothing
            assert params == {"HapticIntensity": 0.0 if silent else 1.0, "HapticSharpness": 0.3}
        for c in curves:
            assert c["ParameterID"] == "HapticIntensityControl"
            pts = c["ParameterCurveControlPoints"]
            assert 2 <= len(pts) <= CURVE_MAX_POINTS
            times = [p["Time"] for p in pts]
            assert times[0] == 0 and times == sorted(times)
            assert all(0.0 <= p["ParameterValue"] <= 1.0 for p in pts)


@pytest.mark.parametrize("wins", ["first", "last"])
def test_every_actuator_decodes_back_to_its_ticks(wins):
    tl = _timeline()
    zf = _export(tl)
    for i, aid in enumerate(ACTUATOR_IDS):
        decoded = decode_pattern(json.loads(zf.read(f"{aid}.ahap")), tl.n_ticks, wins=wins)
        np.testing.assert_allclose(decoded, tl.vibration[:, i], atol=1e-4, err_msg=aid)


def _long_runs_timeline(seed: int, n: int = 1600) -> Timeline:
    """Runs longer than 30 s, per-tick changing and steady, random levels, one silent actuator."""
    rng = np.random.default_rng(seed)
    tl = Timeline.empty(n)

    def busy(m: int) -> np.ndarray:
        return np.round(rng.uniform(0.02, 1.0, m), 4)

    tl.vibration[20:540, 0] = busy(520)  # 52 s, a new level every tick (crosses 30 s at tick 320)
    tl.vibration[10:1400, 1] = 0.6  # 139 s steady
    # A3 silent for the whole film
    env = busy(n)
    env[rng.random(n) < 0.3] = 0.0
    tl.vibration[:, 3] = env  # random levels with random gaps
    tl.vibration[:610, 4] = busy(610)  # from the very first tick, 61 s busy
    tl.vibration[610:1000, 4] = 0.25  # then steady in the same run
    tl.vibration[100:400, 5] = busy(300)  # exactly one 30 s event
    tl.vibration[401:1001, 5] = busy(600)  # exactly two, a tick later
    tl.vibration[1000:, 6] = busy(n - 1000)  # on until the end of the film
    tl.vibration[100:1300, 7] = np.repeat(busy(24), 50)  # steps every 5 s, joints mid-step
    tl.vibration[:, 8] = busy(n)  # 160 s, no gap at all
    return tl


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_long_runs_read_the_same_whichever_simultaneous_curve_wins(seed):
    tl = _long_runs_timeline(seed)
    zf = _export(tl)
    for i, aid in enumerate(ACTUATOR_IDS):
        doc = json.loads(zf.read(f"{aid}.ahap"))
        events = [item["Event"] for item in doc["Pattern"] if "Event" in item]
        assert len(events) >= 1, aid  # AHAP: a pattern holds one or more events
        for wins in ("first", "last"):
            decoded = decode_pattern(doc, tl.n_ticks, wins=wins)
            np.testing.assert_allclose(decoded, tl.vibration[:, i], atol=0.02, err_msg=f"{aid} {wins}")
        # and the reason: no instant gets two different values from two curves
        at: dict[float, set] = {}
        for item in doc["Pattern"]:
            if "ParameterCurve" in item:
                c = item["ParameterCurve"]
                for p in c["ParameterCurveControlPoints"]:
                    at.setdefault(round(c["Time"] + p["Time"], 6), set()).add(p["ParameterValue"])
        assert all(len(values) == 1 for values in at.values()), aid


def test_a_silent_actuator_is_one_event_that_plays_nothing():
    tl = _timeline()
    zf = _export(tl)
    doc = json.loads(zf.read("A2.ahap"))
    (item,) = doc["Pattern"]
    ev = item["Event"]
    params = {p["ParameterID"]: p["ParameterValue"] for p in ev["EventParameters"]}
    assert ev["EventType"] == "HapticContinuous" and ev["Time"] == 0 and ev["EventDuration"] == EVENT_MAX_S
    assert params["HapticIntensity"] == 0
    entry = next(f for f in json.loads(zf.read("manifest.json"))["files"] if f["actuator"] == "A2")
    assert entry["active_ticks"] == 0 and entry["events"] == 1 and entry["curves"] == 0
    short = _export(Timeline.empty(50))  # a film shorter than 30 s: the event lasts the film
    for aid in ACTUATOR_IDS:
        (item,) = json.loads(short.read(f"{aid}.ahap"))["Pattern"]
        assert item["Event"]["EventDuration"] == 5.0
        np.testing.assert_array_equal(decode_pattern(json.loads(short.read(f"{aid}.ahap")), 50), 0.0)


def test_zip_entries_are_readable_and_carry_the_export_time(monkeypatch):
    monkeypatch.delenv("SOURCE_DATE_EPOCH", raising=False)
    before = datetime.datetime.now().replace(microsecond=0) - datetime.timedelta(seconds=2)
    zf = _export(_timeline())
    after = datetime.datetime.now() + datetime.timedelta(seconds=2)
    for info in zf.infolist():
        assert info.create_system == 3, info.filename  # Unix, so the mode bits are honoured
        assert info.external_attr >> 16 == stat.S_IFREG | 0o644, info.filename
        assert before <= datetime.datetime(*info.date_time) <= after, info.filename


def test_long_stretches_are_chained():
    zf = _export(_timeline())
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


# pieces of a track: off, one held level, or a new level every tick (seeded), up to 70 s each
_pieces = st.lists(st.tuples(st.sampled_from(["off", "held", "busy"]), st.integers(1, 10_000),
                             st.integers(1, 700)), min_size=1, max_size=5)


def _track(pieces) -> np.ndarray:
    parts = []
    for kind, v, m in pieces:
        if kind == "busy":
            parts.append(np.random.default_rng(v).integers(1, 10_001, m))
        else:
            parts.append(np.full(m, 0 if kind == "off" else v))
    return np.concatenate(parts).astype(np.int64)


@settings(max_examples=60, deadline=None)
@given(_pieces)
def test_any_track_decodes_exactly_whichever_curve_wins(pieces):
    q = _track(pieces)
    doc = json.loads("".join(pattern_chunks(q, actuator="A5", title="t", created="2024-01-01")))
    assert any("Event" in item for item in doc["Pattern"])
    for item in doc["Pattern"]:
        if "Event" in item:
            assert item["Event"]["EventDuration"] <= EVENT_MAX_S
        else:
            assert len(item["ParameterCurve"]["ParameterCurveControlPoints"]) <= CURVE_MAX_POINTS
    for wins in ("first", "last"):
        np.testing.assert_allclose(decode_pattern(doc, q.shape[0], wins=wins), q / 10_000, atol=1e-9)
