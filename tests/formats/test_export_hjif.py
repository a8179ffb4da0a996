"""MPEG-I haptics (.hjif) export: documented keys, perceptions/channels, sparse keyframes, decode."""

from __future__ import annotations

import io
import json
import re
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from autohaptics.bench.export import synthetic_timeline
from autohaptics.formats import export_timeline
from autohaptics.formats.common import breakpoints
from autohaptics.errors import ParameterError
from autohaptics.formats.hjif import (
    ACTUATOR_MASK,
    BODY_PART_BITS,
    MAX_EFFECT_KEYFRAMES,
    MAX_EFFECT_MS,
    TEMPERATURE_MASK,
    WIND_MASK,
    level_for,
)
from autohaptics.layout import ACTUATOR_IDS, FAN_COLS, FAN_ROWS
from autohaptics.timeline import Timeline
from shared_data import REPO


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
    assert doc["version"] == "2023" and doc["profile"] == "Main"
    assert doc["level"] == 2  # 153 wind channels: more than level 1's 127
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
        assert p["unit_exponent"] == -3 and p["perception_unit_exponent"] == 0
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
    # channel ids are unique across the whole file: 0..8 vibration, 9 temperature, 10.. fans
    ids = [c["id"] for p in doc["perceptions"] for c in p["channels"]]
    assert ids == list(range(9 + 1 + FAN_ROWS * FAN_COLS))
    assert "degrees Celsius" in temp["description"]
    assert [c["description"].split(":")[0] for c in vib["channels"]] == list(ACTUATOR_IDS)
    assert [c["body_part_mask"] for c in vib["channels"]] == [ACTUATOR_MASK[a] for a in ACTUATOR_IDS]
    assert temp["channels"][0]["body_part_mask"] == TEMPERATURE_MASK
    assert {c["body_part_mask"] for c in wind["channels"]} == {WIND_MASK}
    assert wind["channels"][FAN_COLS + 3]["description"] == "fan r1 c3"
    assert wind["channels"][FAN_COLS + 3]["id"] == 10 + FAN_COLS + 3


def test_body_part_bits_are_the_reference_table():
    # known answers from the MPEG reference software's body table (OHMData.h), as issue 19 quotes them
    assert BODY_PART_BITS["UPPER_BACK"] == 0x100 and BODY_PART_BITS["LOWER_BACK"] == 0x200
    assert BODY_PART_BITS["RIGHT_UPPERARM"] | BODY_PART_BITS["RIGHT_FOREARM"] == 0x400 | 0x1000
    assert BODY_PART_BITS["RIGHT_THIGH"] | BODY_PART_BITS["LEFT_THIGH"] == 0x400000 | 0x800000
    hand = ("LEFT_HAND_PALM", "LEFT_HAND_DORSUM", "LEFT_HAND_FINGERS")
    assert sum(BODY_PART_BITS[p] for p in hand) == 2752512
    assert BODY_PART_BITS["HEAD_FRONT"] == 1 and BODY_PART_BITS["LEFT_FOOT_FINGERS"] == 0x80000000
    assert sorted(BODY_PART_BITS.values()) == [1 << i for i in range(32)]
    for name, bit in BODY_PART_BITS.items():  # every left part is the bit after its right twin
        if name.startswith("RIGHT_"):
            assert BODY_PART_BITS["LEFT_" + name[6:]] == bit << 1


def _documented_masks() -> dict[str, int]:
    """``body_part_mask`` per channel as docs/EXPORT.md's hjif table states it (hex and decimal agree)."""
    doc = (REPO / "docs" / "EXPORT.md").read_text(encoding="utf-8")
    rows = re.findall(r"^\| (A\d|temperature|fans) \(ids? [^)]*\) \|.*\| (0x[0-9A-F]{8}) \| (\d+) \|$",
                      doc, flags=re.M)
    out = {}
    for name, hexa, dec in rows:
        assert int(hexa, 16) == int(dec), name
        out[name] = int(dec)
    return out


def _documented_bits() -> dict[str, int]:
    doc = (REPO / "docs" / "EXPORT.md").read_text(encoding="utf-8")
    rows = re.findall(r"^\| (\d+) \| (0x[0-9A-F]{8}) \| ([A-Z_]+) \|", doc, flags=re.M)
    for bit, hexa, _ in rows:
        assert int(hexa, 16) == 1 << int(bit)
    return {name: int(hexa, 16) for _, hexa, name in rows}


def test_every_channel_mask_is_the_documented_body_table_bits():
    assert _documented_bits() == BODY_PART_BITS
    documented = _documented_masks()
    assert set(documented) == {*ACTUATOR_IDS, "temperature", "fans"}
    doc = _export(_timeline())
    vib, temp, wind = doc["perceptions"]
    for aid, channel in zip(ACTUATOR_IDS, vib["channels"]):
        assert channel["body_part_mask"] == documented[aid], aid
    assert temp["channels"][0]["body_part_mask"] == documented["temperature"]
    assert {c["body_part_mask"] for c in wind["channels"]} == {documented["fans"]}


def test_level_is_the_lowest_that_holds_the_largest_perception():
    assert level_for((9, 1, 127)) == 1
    assert level_for((128,)) == 2
    assert level_for((9, 1, FAN_ROWS * FAN_COLS)) == 2
    assert level_for((65_535,)) == 2
    with pytest.raises(ParameterError, match="65535"):
        level_for((65_536,))


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


def _effect_spans(doc: dict):
    for p in doc["perceptions"]:
        for c in p["channels"]:
            for e in c["bands"][0]["effects"]:
                yield e["keyframes"][-1]["relative_position"], len(e["keyframes"])


def test_two_hour_effects_fit_the_binary_form_and_still_decode_exactly():
    n = 72_000
    tl = Timeline.empty(n)  # built in memory: 2 hours without the pipeline
    tl.vibration[:, 4] = 0.4  # constant for the whole film
    tl.vibration[1000:2500, 0] = np.round(np.random.default_rng(3).uniform(0.05, 1.0, 1500), 4)  # 150 s busy
    tl.vibration[5000:70_000, 8] = np.round(np.linspace(0.1, 0.9, 65_000), 4)  # a 108-minute ramp
    tl.temperature_c[:] = np.round(36.5 - 3.5 * np.cos(np.arange(n) / 9000.0), 4)  # drifts all film, 33..40 C
    tl.fans[:, 4, 8] = 0.7  # one fan on for the whole film
    doc = _export(tl)
    spans = list(_effect_spans(doc))
    assert max(ms for ms, _ in spans) <= MAX_EFFECT_MS
    assert max(k for _, k in spans) <= MAX_EFFECT_KEYFRAMES
    vib, temp, wind = doc["perceptions"]
    a5 = vib["channels"][4]["bands"][0]["effects"]
    assert len(a5) == -(-n // 655) and all(len(e["keyframes"]) == 2 for e in a5)  # 2 per 65.5 s piece
    for prev, nxt in zip(a5, a5[1:]):  # pieces share their joint: same time, same value
        assert prev["position"] + prev["keyframes"][-1]["relative_position"] == nxt["position"]
        assert prev["keyframes"][-1]["amplitude_modulation"] == nxt["keyframes"][0]["amplitude_modulation"]
    for i in (0, 4, 8):
        np.testing.assert_allclose(decode_channel(vib["channels"][i], n, 1000), tl.vibration[:, i], atol=1e-4)
    lo, hi = tl.temp_range
    decoded_t = lo + (hi - lo) * decode_channel(temp["channels"][0], n, 1000)
    np.testing.assert_allclose(decoded_t, tl.temperature_c, atol=1e-4)
    on = 4 * FAN_COLS + 8
    np.testing.assert_allclose(decode_channel(wind["channels"][on], n, 1000), tl.fans[:, 4, 8], atol=1e-4)
    assert all(c["bands"][0]["effects"] == [] for j, c in enumerate(wind["channels"]) if j != on)


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
