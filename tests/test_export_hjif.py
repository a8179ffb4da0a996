"""MPEG-I haptics (.hjif) export: documented keys, perceptions/channels, sparse keyframes, decode."""

from __future__ import annotations

import io
import json

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from autohaptics.bench.export import synthetic_timeline
from autohaptics.export import export_timeline
from autohaptics.export._common import breakpoints
from autohaptics.export.hjif import ACTUATOR_MASK, TEMPERATURE_MASK, WIND_MASK
from autohaptics.layout import ACTUATOR_IDS, FAN_COLS, FAN_ROWS
from autohaptics.timeline import Timeline


def _timeline(n: int = 1500, seed: int = 8) -> Timeline:
    tl = synthetic_timeline(n, seed=seed)
    tl.vibration[:, 0] = 0.0
    tl.vibration[200:800, 0] = 0.5  # one minute constant
    tl.vibration[:, 6] = 0.0  # A7 silent
    tl.vibration[n - 30:, 8] = 0.8  # on until the very end
    tl.fans[:] = 0.0
    tl.fans[100:150, 2, 5] = 0.6
    tl.fans[400:402, 8, 16] = 1.0
    return tl


def _export(tl: Timeline, **options) -> dict:
    buf = io.StringIO()
    export_timeline(tl, "hjif", buf, **options)
    return json.loads(buf.getvalue())


def decode_channel(channel: dict, n_ticks: int, timescale: int) -> np.ndarray:
    """Per-tick amplitude of one channel: linear between keyframes inside an effect, 0 outside."""
    out = np.zeros(n_ticks)
    t = np.arange(n_ticks) * timescale / 10  # tick starts in timescale units
    for band in channel["bands"]:
        for eff in band["effects"]:
            xs = np.array([eff["position"] + k["relative_position"] for k in eff["keyframes"]], float)
            ys = np.array([k["amplitude_modulation"] for k in eff["keyframes"]], float)
            inside = (t >= xs[0]) & (t <= xs[-1])
            out[inside] = np.interp(t[inside], xs, ys)
    return out


def test_top_level_keys_and_timescale():
    doc = _export(_timeline(), date="2024-05-06")
    assert list(doc) == ["version", "profile", "level", "date", "description", "timescale", "avatars",
                         "perceptions", "syncs"]
    assert doc["version"] == "2023" and doc["profile"] == "Main" and doc["level"] == 2
    assert doc["date"] == "2024-05-06" and doc["timescale"] == 1000
    assert doc["avatars"] == [] and doc["syncs"] == []


def test_one_perception_per_modality_with_one_channel_per_actuator_or_fan():
    doc = _export(_timeline())
    mods = [p["perception_modality"] for p in doc["perceptions"]]
    assert mods == ["Vibrotactile", "Temperature", "Wind"]
    assert [p["id"] for p in doc["perceptions"]] == [0, 1, 2]
    vib, temp, wind = doc["perceptions"]
    assert len(vib["channels"]) == 9 and len(temp["channels"]) == 1 and len(wind["channels"]) == FAN_ROWS * FAN_COLS
    for p in doc["perceptions"]:
        assert {"id", "avatar_id", "description", "perception_modality", "reference_devices",
                "effect_library", "channels"} <= set(p)
        ids = [c["id"] for c in p["channels"]]
        assert ids == list(range(len(ids)))
        for c in p["channels"]:
            assert {"id", "description", "gain", "mixing_coefficient", "body_part_mask", "bands"} <= set(c)
            (band,) = c["bands"]
            assert band["band_type"] == "Curve" and band["curve_type"] == "Linear"
            assert band["lower_frequency_limit"] <= band["upper_frequency_limit"]
            for eff in band["effects"]:
                assert eff["effect_type"] == "Basis" and eff["position"] % 100 == 0
                rel = [k["relative_position"] for k in eff["keyframes"]]
                assert rel[0] == 0 and rel == sorted(rel) and all(r % 100 == 0 for r in rel)
                assert all(0.0 <= k["amplitude_modulation"] <= 1.0 for k in eff["keyframes"])
    assert [c["description"].split(":")[0] for c in vib["channels"]] == list(ACTUATOR_IDS)
    assert [c["body_part_mask"] for c in vib["channels"]] == [ACTUATOR_MASK[a] for a in ACTUATOR_IDS]
    assert temp["channels"][0]["body_part_mask"] == TEMPERATURE_MASK
    assert {c["body_part_mask"] for c in wind["channels"]} == {WIND_MASK}
    assert wind["channels"][FAN_COLS + 3]["description"] == "fan r1 c3"


def test_every_track_decodes_back_to_its_ticks():
    tl = _timeline()
    doc = _export(tl)
    ts = doc["timescale"]
    vib, temp, wind = doc["perceptions"]
    for i, channel in enumerate(vib["channels"]):
        np.testing.assert_allclose(decode_channel(channel, tl.n_ticks, ts), tl.vibration[:, i], atol=1e-4)
    lo, hi = tl.temp_range
    assert f"{lo:g}..{hi:g}" in temp["description"]
    decoded_t = lo + (hi - lo) * decode_channel(temp["channels"][0], tl.n_ticks, ts)
    np.testing.assert_allclose(decoded_t, tl.temperature_c, atol=1e-4)
    fans = np.stack([decode_channel(c, tl.n_ticks, ts) for c in wind["channels"]], axis=1)
    np.testing.assert_allclose(fans.reshape(-1, FAN_ROWS, FAN_COLS), tl.fans, atol=1e-4)


def test_keyframes_only_where_the_slope_changes():
    doc = _export(_timeline())
    vib, _, wind = doc["perceptions"]
    (a1,) = vib["channels"][0]["bands"][0]["effects"]
    assert a1["position"] == 19_900  # opens with a zero keyframe one tick before the stretch
    assert [(k["relative_position"], k["amplitude_modulation"]) for k in a1["keyframes"]] == [
        (0, 0), (100, 0.5), (60_000, 0.5), (60_100, 0)]
    assert vib["channels"][6]["bands"][0]["effects"] == []  # silent A7
    (a9_last,) = vib["channels"][8]["bands"][0]["effects"][-1:]
    end = a9_last["position"] + a9_last["keyframes"][-1]["relative_position"]
    assert end == 1500 * 100 and a9_last["keyframes"][-1]["amplitude_modulation"] == 0.8  # held to the end
    active = [c for c in wind["channels"] if c["bands"][0]["effects"]]
    assert [c["description"] for c in active] == ["fan r2 c5", "fan r8 c16"]
    total = sum(len(e["keyframes"]) for c in wind["channels"] for e in c["bands"][0]["effects"])
    assert total == 8


def test_constant_two_hour_channel_costs_a_handful_of_keyframes():
    tl = Timeline.empty(72_000)
    tl.vibration[:, 4] = 0.4
    tl.temperature_c[:] = 36.5
    doc = _export(tl)
    vib, temp, wind = doc["perceptions"]
    assert sum(len(e["keyframes"]) for e in vib["channels"][4]["bands"][0]["effects"]) == 2
    assert len(temp["channels"][0]["bands"][0]["effects"][0]["keyframes"]) == 2
    assert all(c["bands"][0]["effects"] == [] for c in wind["channels"])


@settings(max_examples=200, deadline=None)
@given(st.lists(st.integers(-50_000, 50_000), min_size=1, max_size=80))
def test_breakpoints_reproduce_every_sample_by_linear_interpolation(values):
    q = np.array(values, dtype=np.int64)
    idx = breakpoints(q)
    assert idx[0] == 0 and idx[-1] == q.shape[0] - 1
    np.testing.assert_array_equal(np.interp(np.arange(q.shape[0]), idx, q[idx]), q)


@settings(max_examples=25, deadline=None)
@given(st.integers(1, 120), st.integers(0, 2**31 - 1))
def test_random_short_timelines_decode_exactly(n, seed):
    tl = synthetic_timeline(n, seed=seed)
    doc = _export(tl)
    vib = doc["perceptions"][0]
    for i, channel in enumerate(vib["channels"]):
        np.testing.assert_allclose(decode_channel(channel, n, 1000), tl.vibration[:, i], atol=1e-4)
