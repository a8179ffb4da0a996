"""The compact binary timeline (autohaptics.timeline.wire): layout, alignment, round trip."""

from __future__ import annotations

import json
import struct

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays

from autohaptics.errors import ParameterError
from autohaptics.layout import FAN_COLS, FAN_ROWS
from autohaptics.timeline.wire import MAGIC, U8_SCALE, decode, encode
from autohaptics.timeline import Timeline


def sample(n: int = 7) -> Timeline:
    rng = np.random.default_rng(3)
    tl = Timeline.empty(n)
    tl.vibration[:] = rng.random((n, 9))
    tl.temperature_c[:] = rng.uniform(30, 55, n)
    tl.fans[:] = np.where(rng.random((n, FAN_ROWS, FAN_COLS)) > 0.7, rng.random((n, FAN_ROWS, FAN_COLS)), 0)
    tl.features["loudness"] = rng.random(n)
    tl.features["flow_px"] = rng.uniform(-5, 50, n)  # not a normalised feature: float32
    return tl.validate()


def test_layout_prefix_header_and_aligned_blocks():
    tl = sample()
    data = encode(tl, revision=12)
    magic, version, hlen = struct.unpack_from("<4sII", data, 0)
    assert (magic, version) == (MAGIC, 1)
    header = json.loads(data[12:12 + hlen].decode("utf-8"))
    assert header["n_ticks"] == 7 and header["tick_s"] == 0.1 and header["revision"] == 12
    blocks = {b["name"]: b for b in header["blocks"]}
    assert list(blocks) == ["vibration", "temperature_c", "fans", "fan_activity", "features.loudness",
                            "features.flow_px"]
    assert blocks["vibration"] == {"name": "vibration", "dtype": "u8", "shape": [7, 9],
                                   "offset": blocks["vibration"]["offset"], "scale": U8_SCALE}
    assert blocks["temperature_c"]["dtype"] == "f32" and blocks["temperature_c"]["scale"] == 1.0
    assert blocks["fans"]["shape"] == [7, FAN_ROWS, FAN_COLS]
    assert blocks["features.flow_px"]["dtype"] == "f32"
    ends = []
    for b in header["blocks"]:
        assert b["offset"] % 4 == 0 and b["offset"] >= 12 + hlen
        size = int(np.prod(b["shape"])) * (1 if b["dtype"] == "u8" else 4)
        ends.append((b["offset"], b["offset"] + size))
    for (_, end), (start, _) in zip(ends, ends[1:]):
        assert end <= start  # no overlap
    assert len(data) >= ends[-1][1]
    # A reader can take the u8 vibration block straight from the bytes.
    raw = np.frombuffer(data, np.uint8, 7 * 9, blocks["vibration"]["offset"]).reshape(7, 9)
    np.testing.assert_array_equal(raw, np.rint(tl.vibration.astype(np.float64) * 255).astype(np.uint8))


def test_decode_gives_the_values_within_quantisation():
    tl = sample()
    header, arrays_ = decode(encode(tl, revision=0))
    np.testing.assert_allclose(arrays_["vibration"], tl.vibration, atol=0.5 / 255 + 1e-7)
    np.testing.assert_allclose(arrays_["fans"], tl.fans, atol=0.5 / 255 + 1e-7)
    np.testing.assert_array_equal(arrays_["temperature_c"], tl.temperature_c)
    np.testing.assert_allclose(arrays_["features.loudness"], tl.features["loudness"], atol=0.5 / 255 + 1e-7)
    np.testing.assert_array_equal(arrays_["features.flow_px"], tl.features["flow_px"].astype(np.float32))
    expected_activity = (tl.fans > 0).reshape(7, -1).mean(axis=1)
    np.testing.assert_allclose(arrays_["fan_activity"], expected_activity, atol=0.5 / 255 + 1e-7)


@settings(max_examples=60, deadline=None)
@given(n=st.integers(1, 40), data=st.data())
def test_round_trip_property(n, data):
    unit = st.floats(0, 1, width=32)
    tl = Timeline.empty(n)
    tl.vibration[:] = data.draw(arrays(np.float32, (n, 9), elements=unit))
    tl.temperature_c[:] = data.draw(arrays(np.float32, (n,), elements=st.floats(30, 55, width=32)))
    tl.fans[:] = data.draw(arrays(np.float32, (n, FAN_ROWS, FAN_COLS), elements=unit))
    tl.validate()
    header, out = decode(encode(tl, revision=n))
    assert header["revision"] == n
    assert np.abs(out["vibration"] - tl.vibration).max() <= 0.5 / 255 + 1e-6
    assert np.abs(out["fans"] - tl.fans).max() <= 0.5 / 255 + 1e-6
    np.testing.assert_array_equal(out["temperature_c"], tl.temperature_c)


@pytest.mark.parametrize("mangle, message", [
    (lambda d: b"XXXX" + d[4:], "magic"),
    (lambda d: d[:4] + struct.pack("<I", 9) + d[8:], "version 9"),
    (lambda d: d[:8] + struct.pack("<I", 10**6) + d[12:], "runs past the data"),
    (lambda d: d[:6], "shorter than"),
    (lambda d: d[:40], "runs past the data|not UTF-8 JSON"),
])
def test_decode_refuses_broken_data(mangle, message):
    with pytest.raises(ParameterError, match=message):
        decode(mangle(encode(sample(), revision=1)))
