"""Reading a JSON document whose big numeric arrays (a timeline's tracks and features) come back as
float64 numpy arrays instead of nested lists: the same numbers ``np.asarray(json.loads(...),
np.float64)`` gives, several times faster and without a Python object per number (a 2-hour film's
fan track is 11 million numbers). Anything the fast path is not sure of (a ragged or mixed array,
a number JSON does not allow, an exponent-heavy file) is left to the standard parser.
"""

from __future__ import annotations

import json
import re
from collections.abc import Callable
from typing import Any

import numpy as np

MIN_BYTES = 4096  # an array shorter than this is left to the standard parser
_CHUNK = 1 << 16  # bytes of numbers parsed per step (bounds the temporaries; most of a fan track's are all 0)
_MAX_SLOW = 100_000  # numbers per array parsed one by one (exponents, > 15 digits) before giving up
_NUMBER_CHARS = b"0123456789.eE+-"
_CANDIDATE = re.compile(rb"\[[0-9\[\],.eE+\- \t\r\n]{%d,}" % MIN_BYTES)  # to its last "]": linear
_JSON_NUMBER = re.compile(rb"-?(?:0|[1-9][0-9]*)(?:\.[0-9]+)?(?:[eE][+-]?[0-9]+)?")
_SPLIT_NUMBER = re.compile(rb"[0-9.eE+\-][ \t\r\n]+[0-9.eE+\-]")
_MARK = "@autohaptics-numeric-array-"
_AS_NW = bytes.maketrans(_NUMBER_CHARS + b"\t\r\n", b"n" * len(_NUMBER_CHARS) + b"   ")
_P10 = 10 ** np.arange(16, dtype=np.int64)
_ZEROS = b"0," * (_CHUNK + 64)
_ZERO_INDEX = np.zeros(1, np.int64)


def loads(raw: bytes, places: Callable[[tuple], bool] = lambda path: True) -> Any:
    """The JSON document in ``raw`` (UTF-8) with every rectangular all-number array of at least
    :data:`MIN_BYTES` bytes at a path (tuple of keys and indices) that ``places`` accepts as a
    float64 array of its shape. Errors as ``json.loads(raw.decode())``."""
    fast = _with_arrays(raw, places)
    return fast if fast is not None else json.loads(raw.decode("utf-8"))


def _with_arrays(raw: bytes, places: Callable[[tuple], bool]) -> Any:
    """The document with its big arrays parsed by :func:`numeric_array`; None when it has none, the
    rest does not parse (the standard parser then says why) or one lies where ``places`` refuses."""
    if _MARK.encode() in raw:
        return None
    pieces, arrays, last = [], [], 0
    for m in _CANDIDATE.finditer(raw):
        end = raw.rfind(b"]", m.start(), m.end()) + 1
        arr = numeric_array(raw, m.start(), end) if end - m.start() > MIN_BYTES else None
        if arr is None:
            continue
        pieces += [raw[last:m.start()], f'"{_MARK}{len(arrays)}"'.encode()]
        arrays.append(arr)
        last = end
    if not arrays:
        return None
    try:
        doc = json.loads(b"".join(pieces + [raw[last:]]).decode("utf-8"))
    except (json.JSONDecodeError, UnicodeDecodeError):
        return None  # a candidate inside a string leaves two strings side by side: not JSON
    used: list[int] = []
    try:
        doc = _put_back(doc, arrays, used, places, ())
    except RecursionError:  # nested about as deep as the standard parser allows: leave it to that one
        return None
    return doc if sorted(used) == list(range(len(arrays))) else None


def _put_back(value: Any, arrays: list, used: list, places: Callable[[tuple], bool], path: tuple) -> Any:
    if isinstance(value, str) and value.startswith(_MARK):
        k = value[len(_MARK):]
        if k.isdigit() and int(k) < len(arrays) and places(path):
            used.append(int(k))
            return arrays[int(k)]
    if isinstance(value, dict):
        return {key: _put_back(v, arrays, used, places, (*path, key)) for key, v in value.items()}
    if isinstance(value, list):
        return [_put_back(v, arrays, used, places, (*path, i)) for i, v in enumerate(value)]
    return value


def numeric_array(raw: bytes, start: int = 0, end: int | None = None) -> np.ndarray | None:
    """A JSON array of arrays ... of numbers (``raw[start:end]``, nothing around it) as a float64
    array of its shape, or None when it is not one (ragged, empty, not only numbers, a number JSON
    does not allow). Each copy of the text is let go as soon as it has served."""
    text = raw[start:end]
    marked = text.translate(_AS_NW)
    if b"n " in marked and _SPLIT_NUMBER.search(text):
        return None  # white space inside a number
    marked = marked.translate(None, b" ")
    if b"]n" in marked or b"n[" in marked:  # a number outside the innermost lists (empty slots: _chunk)
        return None
    shape = _shape(marked.translate(None, b"n"))
    del marked
    if shape is None:
        return None
    flat = text.translate(None, b" \t\r\n[]")
    del text
    values = _numbers(flat, int(np.prod(shape)))
    return None if values is None else values.reshape(shape)


def _shape(skeleton: bytes) -> tuple[int, ...] | None:
    """The shape whose nested lists have exactly this skeleton (brackets and commas), or None."""
    depth = len(skeleton) - len(skeleton.lstrip(b"["))
    if depth == 0 or b"]" not in skeleton:
        return None
    sizes = [skeleton.index(b"]") - depth + 1]
    unit = b"[" + b"," * (sizes[0] - 1) + b"]"
    for level in range(depth - 2, 0, -1):  # the first list at each level below the outermost
        pos, m = level + 1, 0
        while skeleton.startswith(unit, pos):
            m, pos = m + 1, pos + len(unit)
            if skeleton[pos:pos + 1] != b",":
                break
            pos += 1
        sizes.insert(0, m)
        unit = b"[" + b",".join([unit] * m) + b"]"
    if depth > 1:
        sizes.insert(0, (len(skeleton) - 1) // (len(unit) + 1))
        unit = b"[" + b",".join([unit] * sizes[0]) + b"]"
    return tuple(sizes) if unit == skeleton else None


def _numbers(flat: bytes, count: int) -> np.ndarray | None:
    """``count`` comma-separated JSON numbers as float64 (what ``float(json.loads(token))`` gives), or None."""
    out = np.empty(count, np.float64)
    done, start = 0, 0
    slow = [0]
    while start < len(flat):
        end = flat.find(b",", min(start + _CHUNK, len(flat)))
        end = len(flat) if end < 0 else end
        part = _chunk(flat[start:end], slow)
        if part is None or done + part.size > count:
            return None
        out[done:done + part.size] = part
        done, start = done + part.size, end + 1
    return out if done == count else None


def _chunk(text: bytes, slow: list) -> np.ndarray | None:
    """The numbers of one chunk: "0" at once, the others by :func:`_decimals`."""
    if len(text) % 2 and text == _ZEROS[:len(text)]:
        return np.zeros((len(text) + 1) // 2)
    b = np.frombuffer(text, np.uint8)
    commas = np.flatnonzero(b == ord(","))
    starts = np.concatenate([_ZERO_INDEX, commas + 1])
    ends = np.concatenate([commas, [b.size]])
    lengths = ends - starts
    if lengths.min() < 1:
        return None
    out = np.zeros(starts.size)
    zero = (lengths == 1) & (b[starts] == ord("0"))
    if zero.all():
        return out
    keep = np.ones(b.size, bool)
    keep[commas], keep[starts[zero]] = False, False
    other = np.flatnonzero(~zero)
    values = _decimals(b[keep], lengths[other], slow)
    if values is None:
        return None
    out[other] = values
    return out


def _decimals(b: np.ndarray, lengths: np.ndarray, slow: list) -> np.ndarray | None:
    """Numbers written back to back (``b`` bytes, ``lengths`` per number): ``-?(0|[1-9]d*)(.d+)?``
    of at most 15 digits exactly (the integer of its digits over a power of ten, both exact: one
    correctly rounded division), any other JSON number by ``float``; None where one is not JSON."""
    starts = np.concatenate([_ZERO_INDEX, np.cumsum(lengths)[:-1]])
    ends = starts + lengths
    digit = (b >= ord("0")) & (b <= ord("9"))
    dot, minus = b == ord("."), b == ord("-")
    cum = [np.concatenate([_ZERO_INDEX, np.cumsum(x, dtype=np.int64)]) for x in (digit, dot, minus)]
    digits, dots, minuses = (c[ends] - c[starts] for c in cum)
    neg = b[starts] == ord("-")
    first = starts + neg
    lead = b[np.minimum(first, b.size - 1)]
    after_lead = b[np.minimum(first + 1, b.size - 1)]
    simple = ((digits + dots + minuses == lengths) & (dots <= 1) & (minuses == neg) & (first < ends)
              & (lead >= ord("0")) & (lead <= ord("9")) & ((lead != ord("0")) | (first + 1 == ends) | (after_lead == ord(".")))
              & digit[ends - 1] & (digits <= 15))
    owner_end = np.repeat(ends, lengths)
    after = cum[0][owner_end] - cum[0][np.arange(b.size) + 1]  # digits after each byte in its number
    weight = np.where(digit, (b.astype(np.int64) - ord("0")) * _P10[np.minimum(after, 15)], 0)
    mantissa = np.add.reduceat(weight, starts) if b.size else np.zeros(0, np.int64)
    frac = np.add.reduceat(np.where(dot, after, 0), starts) if b.size else np.zeros(0, np.int64)
    values = mantissa.astype(np.float64) / _P10[np.minimum(frac, 15)].astype(np.float64)
    values = np.where(neg & ((dots > 0) | (mantissa != 0)), -values, values)
    rest = np.flatnonzero(~simple)
    slow[0] += rest.size
    if slow[0] > _MAX_SLOW:
        return None
    raw = b.tobytes() if rest.size else b""
    for i in rest:
        token = raw[starts[i]:ends[i]]
        if not _JSON_NUMBER.fullmatch(token):
            return None
        try:
            values[i] = float(int(token)) if token.strip(b"-").isdigit() else float(token)
        except (OverflowError, ValueError):  # too big for a float, or for int(): the standard parser says
            return None
    return values
