"""The chair wire protocol in Python: the shared byte vectors (also checked by the C tests),
round trips and parser robustness as properties (hypothesis)."""

from __future__ import annotations

import binascii
from pathlib import Path

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from autohaptics.chair import protocol as P
from autohaptics.chair.messages import STATUS_U32
from autohaptics.chair.protocol import (
    MAX_ENCODED,
    ChairStatus,
    Frame,
    Hello,
    HelloRequest,
    Parser,
    ProtocolError,
    Status,
    StatusRequest,
    Stop,
    cobs_decode,
    cobs_encode,
    crc16,
    decode,
    encode,
)
from autohaptics.errors import ParameterError
from shared_data import REPO

VECTORS = REPO / "firmware" / "test" / "vectors.txt"


def _load_vectors():
    crcs, cobs, vectors = [], [], []
    current = None
    for raw in VECTORS.read_text().splitlines():
        line = raw.strip()
        if not line or line.startswith("#"):
            continue
        key, _, rest = line.partition(" ")
        if current is None:
            if key == "crc":
                data, value = rest.split()
                crcs.append((bytes.fromhex(data), int(value, 16)))
            elif key == "cobs":
                dec, enc = rest.split()
                cobs.append((b"" if dec == "-" else bytes.fromhex(dec), bytes.fromhex(enc)))
            elif key == "vector":
                current = {"name": rest, "fields": {}, "canonical": False, "type": None}
            else:
                raise AssertionError(f"unrecognised line in {VECTORS}: {line[:60]}")
        elif key == "end":
            vectors.append(current)
            current = None
        elif key == "wire":
            current["wire"] = bytes.fromhex(rest)
        elif key == "results":
            current["results"] = rest.split()
        elif key == "canonical":
            current["canonical"] = True
        elif key == "type":
            current["type"] = int(rest, 16)
        else:
            current["fields"][key] = rest
    assert current is None, "unterminated vector"
    return crcs, cobs, vectors


CRCS, COBS, VECTOR_LIST = _load_vectors()


def _field_value(msg, key):
    if key == "firmware_version":
        return " ".join(str(v) for v in msg.firmware_version)
    value = getattr(msg, key)
    if isinstance(value, bytes):
        return " ".join(str(b) for b in value)
    return str(value)


def test_vectors_file_covers_every_message_and_error():
    kinds = {v["type"] for v in VECTOR_LIST if v["type"] is not None}
    assert kinds == {P.MSG_HELLO_REQ, P.MSG_HELLO, P.MSG_STATUS_REQ, P.MSG_STATUS, P.MSG_FRAME, P.MSG_STOP}
    results = {r for v in VECTOR_LIST for r in v["results"]}
    assert results == {"ok", "crc_error", "length_error", "overflow", "version_error", "type_error"}
    assert len(CRCS) >= 2 and len(COBS) >= 8


@pytest.mark.parametrize("data,value", CRCS, ids=[d.hex()[:16] for d, _ in CRCS])
def test_crc_vectors(data, value):
    assert crc16(data) == value
    assert binascii.crc_hqx(data, 0xFFFF) == value  # an independent CRC-16/CCITT-FALSE


@pytest.mark.parametrize("decoded,encoded", COBS, ids=[f"cobs{i}" for i in range(len(COBS))])
def test_cobs_vectors(decoded, encoded):
    assert cobs_encode(decoded) == encoded
    assert cobs_decode(encoded) == decoded


@pytest.mark.parametrize("vec", VECTOR_LIST, ids=[v["name"] for v in VECTOR_LIST])
def test_protocol_vector(vec):
    parsed = Parser().feed(vec["wire"])
    assert [p.status.label for p in parsed] == vec["results"]
    oks = [p.message for p in parsed if p.status == Status.OK]
    if vec["type"] is None:
        assert oks == []
        return
    assert len(oks) == 1
    msg = oks[0]
    assert msg.type == vec["type"]
    for key, expected in vec["fields"].items():
        assert _field_value(msg, key) == expected, f"{vec['name']}: field {key}"
    if vec["canonical"]:
        assert encode(msg) == vec["wire"]
        assert decode(vec["wire"]) == msg


def test_decode_names_the_reason():
    frame = Frame(tick=1, motors=bytes(range(9)))
    wire = bytearray(encode(frame))
    wire[10] ^= 0x01
    with pytest.raises(ProtocolError) as err:
        decode(bytes(wire))
    assert err.value.status in (Status.CRC_ERROR, Status.LENGTH_ERROR)
    with pytest.raises(ProtocolError) as err:
        decode(b"\x42" * (MAX_ENCODED + 1))
    assert err.value.status == Status.OVERFLOW
    with pytest.raises(ProtocolError, match="more than one frame"):
        decode(encode(Stop()) + encode(Stop()))


def test_messages_validate_their_fields():
    with pytest.raises(ParameterError, match="9 motor values"):
        Frame(tick=0, motors=bytes(8))
    with pytest.raises(ParameterError, match="153 fan values"):
        Frame(tick=0, fans=bytes(152))
    with pytest.raises(ParameterError, match="tick"):
        Frame(tick=-1)
    with pytest.raises(ParameterError, match="temp_cc"):
        Frame(tick=0, temp_cc=40000)
    with pytest.raises(ParameterError, match="name"):
        Hello(name="x" * 17)
    with pytest.raises(ParameterError, match="frames_ok"):
        ChairStatus(frames_ok=2**32)


# --------------------------------------------------------------------------- properties
u8s = lambda n: st.binary(min_size=n, max_size=n)  # noqa: E731
frames = st.builds(Frame, tick=st.integers(0, 2**32 - 1), seq=st.integers(0, 0xFFFF), motors=u8s(9),
                   temp_cc=st.integers(-0x8000, 0x7FFF), fans=u8s(153))
hellos = st.builds(Hello, protocol_version=st.integers(0, 255),
                   firmware_version=st.tuples(*[st.integers(0, 255)] * 3),
                   n_actuators=st.integers(0, 255), fan_rows=st.integers(0, 255), fan_cols=st.integers(0, 255),
                   temp_min_cc=st.integers(-0x8000, 0x7FFF), temp_max_cc=st.integers(-0x8000, 0x7FFF),
                   temp_neutral_cc=st.integers(-0x8000, 0x7FFF), temp_rate_cc_per_s=st.integers(0, 0xFFFF),
                   watchdog_ms=st.integers(0, 0xFFFF), tick_ms=st.integers(0, 0xFFFF),
                   max_packet=st.integers(0, 0xFFFF),
                   name=st.text(st.characters(min_codepoint=1, max_codepoint=127), max_size=16))
statuses = st.builds(ChairStatus, **{k: st.integers(0, 2**32 - 1) for k in STATUS_U32},
                     last_seq=st.integers(0, 0xFFFF), flags=st.integers(0, 255), safe_reason=st.integers(0, 255),
                     temp_target_cc=st.integers(-0x8000, 0x7FFF), temp_setpoint_cc=st.integers(-0x8000, 0x7FFF))
messages = st.one_of(frames, hellos, statuses, st.just(HelloRequest()), st.just(StatusRequest()), st.just(Stop()))


@settings(max_examples=300, deadline=None)
@given(frames)
def test_frame_roundtrip(frame):
    wire = encode(frame)
    assert wire.endswith(b"\x00") and b"\x00" not in wire[:-1]
    assert len(wire) <= MAX_ENCODED + 1
    assert decode(wire) == frame


@settings(max_examples=200, deadline=None)
@given(messages)
def test_any_message_roundtrip(msg):
    assert decode(encode(msg)) == msg
    assert [p.message for p in Parser().feed(encode(msg))] == [msg]


@settings(max_examples=300, deadline=None)
@given(st.binary(max_size=1200))
def test_cobs_roundtrip_and_crc_agree_with_reference(data):
    enc = cobs_encode(data)
    assert b"\x00" not in enc
    assert cobs_decode(enc) == data
    assert crc16(data) == binascii.crc_hqx(data, 0xFFFF)


@settings(max_examples=300, deadline=None)
@given(st.binary(max_size=3000), st.lists(st.integers(1, 400), max_size=30))
def test_parser_survives_arbitrary_bytes_in_any_chunking(data, cuts):
    whole = Parser()
    expected = [(p.status, p.message) for p in whole.feed(data)]
    chunked = Parser()
    got = []
    pos = 0
    for size in cuts + [len(data)]:
        got += [(p.status, p.message) for p in chunked.feed(data[pos:pos + size])]
        assert chunked.pending <= MAX_ENCODED  # memory stays bounded
        pos += size
    assert got == expected
    assert chunked.counters == whole.counters
    for status, msg in got:
        assert isinstance(status, Status) and status != Status.STALE
        assert (msg is not None) == (status == Status.OK)


@settings(max_examples=150, deadline=None)
@given(st.lists(frames, min_size=1, max_size=8), st.data())
def test_corrupted_stream_yields_only_whole_original_frames(originals, data):
    stream = bytearray()
    for frame in originals:
        wire = bytearray(encode(frame))
        mode = data.draw(st.sampled_from(["intact", "flip", "truncate", "garbage"]))
        if mode == "flip":
            i = data.draw(st.integers(0, len(wire) - 2))
            wire[i] ^= 1 << data.draw(st.integers(0, 7))
        elif mode == "truncate":
            cut = data.draw(st.integers(1, len(wire) - 2))
            wire = wire[:cut] + b"\x00"
        elif mode == "garbage":
            wire = bytearray(data.draw(st.binary(min_size=1, max_size=40))) + wire
        stream += wire
    parsed = Parser().feed(bytes(stream))
    for p in parsed:
        # garbage of at most 40 bytes cannot hold a whole FRAME (178 bytes), so every decoded
        # FRAME must be one of the originals, intact
        if p.status == Status.OK and isinstance(p.message, Frame):
            assert p.message in originals
