"""The timeline file's big arrays read straight into numpy (timeline.numeric_json) give exactly what
the standard parser and ``np.asarray`` give, for any JSON numbers and layout, and anything that is
not a rectangular array of JSON numbers is left to the standard parser (the same error, the same
lists)."""

from __future__ import annotations

import json

import numpy as np
import pytest
from hypothesis import given, settings, strategies as st

from autohaptics.timeline import Timeline, numeric_json
from autohaptics.timeline.numeric_json import MIN_BYTES

_number = st.one_of(
    st.just("0"), st.just("-0"), st.just("-0.0"), st.integers(-10**6, 10**6).map(str),
    st.integers(-10**25, 10**25).map(str),  # beyond 15 digits: float(int) like the standard path
    st.floats(-1e6, 1e6, allow_nan=False).map(lambda v: f"{v:.4f}".rstrip("0").rstrip(".") or "0"),
    st.floats(allow_nan=False, allow_infinity=False).map(repr).filter(lambda s: "e" in s or "." in s),
    st.decimals(-1000, 1000, places=17, allow_nan=False).map(lambda d: format(d, "f")).filter(
        lambda s: not s.lstrip("-").startswith("0") or s.lstrip("-").startswith("0.") or s.lstrip("-") == "0"),
    st.sampled_from(["1e5", "1E+05", "-2.5e-3", "123456789012345", "1234567890123456", "0.000001", "1e400"]))
_space = st.sampled_from(["", "", "", " ", "\n", "\t", "\r\n "])


def _text(data, shape) -> str:
    """A JSON array of ``shape`` with numbers drawn from :data:`_number` and white space between tokens."""
    if len(shape) == 1:
        items = [data.draw(_number) for _ in range(shape[0])]
    else:
        items = [_text(data, shape[1:]) for _ in range(shape[0])]
    sp = data.draw(_space)
    return "[" + sp + ("," + data.draw(_space)).join(items) + data.draw(_space) + "]"


def _expected(text: str):
    return np.asarray(json.loads(text), np.float64)


@settings(max_examples=150, deadline=None)
@given(st.data(), st.lists(st.integers(1, 7), min_size=1, max_size=3))
def test_arrays_are_the_numbers_the_standard_parser_gives(data, shape):
    text = _text(data, tuple(shape))
    got = numeric_json.numeric_array(text.encode())
    want = _expected(text)
    assert got is not None and got.dtype == np.float64 and got.shape == want.shape
    assert got.tobytes() == want.tobytes()  # bit for bit: -0.0, rounding of long decimals


@pytest.mark.parametrize("text", [
    "[[1,2],[3]]", "[[1,2],3]", "[1,[2,3]]", "[[1,2]5,[3,4]]", "[[1,2],[3,4]6]", "[]", "[[]]", "[1,,2]", "[1,2,]",
    "[,1]", "[01,2]", "[1.,2]", "[.5,2]", "[+1,2]", "[1e,2]", "[1 2,3]", "[1\n2,3]", "[--1,2]", "[1-2,3]", "[1.2.3,4]",
    "[0x1,2]", "[1e5e5,2]", "[[1,2]][[3,4]]", "[1,2]]", "[[1,2]", "[-,1]", "[1e1.5,2]"])
def test_what_is_not_a_rectangular_array_of_json_numbers_is_refused(text):
    assert numeric_json.numeric_array(text.encode()) is None


def _document(body: str) -> bytes:
    return ('{"format": "x", "note": "a [1,2] in a string", "tracks": {"a": ' + body + ', "b": [1, 2]}}').encode()


def test_documents_match_the_standard_parser_and_fall_back_when_unsure():
    big = "[" + ",\n".join("[0,0,0.25,-1,1e-3,0]" for _ in range(MIN_BYTES // 10)) + "]"
    doc = numeric_json.loads(_document(big))
    assert isinstance(doc["tracks"]["a"], np.ndarray) and doc["tracks"]["b"] == [1, 2]
    assert doc["tracks"]["a"].tobytes() == _expected(big).tobytes() and doc["note"] == "a [1,2] in a string"
    only_tracks = numeric_json.loads(_document(big), lambda path: path == ("tracks", "b"))
    assert only_tracks == json.loads(_document(big))  # an array elsewhere than asked: the standard parse
    ragged = big[:-1] + ",[1]]"
    assert numeric_json.loads(_document(ragged)) == json.loads(_document(ragged))
    in_string = ('{"note": "' + big.replace("\n", "") + '", "n": 1}').encode()
    assert numeric_json.loads(in_string) == json.loads(in_string)
    broken = _document(big)[:-1]
    with pytest.raises(json.JSONDecodeError):
        numeric_json.loads(broken)
    with pytest.raises(json.JSONDecodeError):
        numeric_json.loads(_document(big.replace("0.25", "01", 1)))


def test_a_long_timeline_file_loads_the_same_as_through_lists(tmp_path):
    """A 2,000-tick timeline (fans mostly off, some on) read through numpy and through the standard
    parser's lists: the same tracks and features, bit for bit, and the same metadata."""
    rng = np.random.default_rng(3)
    tl = Timeline.empty(2000)
    tl.vibration[:] = np.round(rng.random((2000, 9)) * (rng.random((2000, 1)) > 0.6), 3)
    tl.fans[500:520] = rng.random((20, 9, 17)).astype(np.float32)
    tl.temperature_c[:] = 30 + 25 * rng.random(2000)
    tl.features["loudness"] = rng.random(2000)
    path = tl.save(tmp_path / "long.json")
    fast = Timeline.load(path)
    slow = Timeline.from_dict(json.loads(path.read_text()))
    for name in ("vibration", "temperature_c", "fans"):
        assert getattr(fast, name).dtype == getattr(slow, name).dtype
        assert getattr(fast, name).tobytes() == getattr(slow, name).tobytes()
    assert fast.features["loudness"].tobytes() == np.asarray(slow.features["loudness"]).tobytes()
    assert (fast.source, fast.generator, fast.stats) == (slow.source, slow.generator, slow.stats)


@pytest.mark.parametrize("raw", [
    b'{"a": ' + b"[" * 50_000 + b'"}', b'{"a": "' + b"[1," * 20_000 + b'"}', b'{"a": [' + b"1" * 20_000 + b"]}",
    b'{"a": [' + b"0," * 5_000 + b"1" * 5_000 + b"]}", b'{"a": [' + b"0," * 5_000 + b"1e999]}"])
def test_odd_documents_give_what_the_standard_parser_gives(raw):
    """Runs of brackets without an end, numbers too long for int() or a float: the same result or
    the same error as the standard parser (the big-array reader steps aside)."""
    try:
        want = json.loads(raw.decode())
    except (ValueError, RecursionError) as exc:
        with pytest.raises(type(exc)):
            numeric_json.loads(raw)
    else:
        got = numeric_json.loads(raw)["a"]
        assert got == want["a"] if isinstance(want["a"], str) else np.array_equal(got, np.asarray(want["a"], float))
