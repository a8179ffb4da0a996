"""The compact binary timeline the editor loads (docs/API.md, "Binary timeline").

Layout::

    offset 0   4 bytes  magic "AHTL"
           4   u32 LE   format version (1)
           8   u32 LE   header length H (bytes)
          12   H bytes  UTF-8 JSON header {n_ticks, tick_s, revision, blocks: [{name, dtype, shape, offset, scale}],
                        markers (composed layer only)}
      12 + H   blocks, each starting at a multiple of 4 bytes, little-endian, at the header's offsets

A ``u8`` block stores ``floor(value / scale + 0.5)`` (:func:`~autohaptics.timeline.quantise.to_u8`) with ``scale = 1/255`` (value = byte * scale); an
``f32`` block stores the value itself (scale 1). Blocks: ``vibration`` u8 (n, 9),
``temperature_c`` f32 (n,), ``fans`` u8 (n, 9, 17), ``fan_activity`` u8 (n,) = fraction of the
153 fans that are on, one block per feature: ``features.NAME`` u8 for the normalised features
(0..1), f32 for any other curve.
"""

from __future__ import annotations

import json
import struct
import zlib
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from autohaptics.errors import ParameterError
from autohaptics.timeline.model import NORMALISED_FEATURES, Timeline
from autohaptics.timeline.quantise import U8_SCALE, to_u8

MAGIC = b"AHTL"
VERSION = 1
_PREFIX = struct.Struct("<4sII")
_DTYPES = {"u8": np.dtype("<u1"), "f32": np.dtype("<f4")}


@dataclass(frozen=True)
class Block:
    name: str
    dtype: str  # "u8" | "f32"
    data: np.ndarray  # already quantised to the block's dtype


def block_sources(tl: Timeline) -> list[tuple[str, str, np.ndarray]]:
    """(name, dtype, source array) of every block of ``tl`` in file order; :func:`quantise` turns one
    into its Block. ``fan_activity`` is computed from the fans."""
    out = [("vibration", "u8", tl.vibration), ("temperature_c", "f32", tl.temperature_c), ("fans", "u8", tl.fans),
           ("fan_activity", "u8", tl.fans)]
    for name, values in tl.features.items():
        out.append((f"features.{name}", "u8" if name in NORMALISED_FEATURES else "f32", values))
    return out


def quantise(name: str, dtype: str, source: np.ndarray) -> Block:
    if name == "fan_activity":
        fans = np.asarray(source)
        cols = int(np.prod(fans.shape[1:]))  # the share of fans on: count / cols is their mean, bit for bit
        return Block(name, "u8", to_u8(np.count_nonzero(fans.reshape(-1, cols) > 0, axis=1) / cols))
    if dtype == "u8":
        return Block(name, "u8", to_u8(source))
    return Block(name, "f32", np.asarray(source, dtype="<f4"))


def timeline_blocks(tl: Timeline) -> list[Block]:
    """The blocks of ``tl`` in file order, quantised."""
    return [quantise(name, dtype, src) for name, dtype, src in block_sources(tl)]


def select_blocks(blocks: list[Block], names: list[str] | None) -> list[Block]:
    """The blocks named in ``names`` (None: all), in file order (:func:`wanted_names`)."""
    wanted = wanted_names([b.name for b in blocks], names)
    return [b for b in blocks if b.name in wanted]


def wanted_names(known: Sequence[str], names: Sequence[str] | None) -> set[str]:
    """The block names of ``known`` that ``names`` asks for (None: all). A name is a block name
    (``vibration``, ``temperature_c``, ``fans``, ``fan_activity``, ``features.loudness``) or
    ``features`` for every feature block; ParameterError for an unknown one."""
    if names is None:
        return set(known)
    wanted = set()
    for name in names:
        if name == "features":
            wanted.update(n for n in known if n.startswith("features."))
        elif name in known:
            wanted.add(name)
        else:
            raise ParameterError(f"unknown block {name!r}; blocks are {', '.join(sorted({*known, 'features'}))}")
    return wanted


def block_bytes(block: Block) -> bytes:
    """A block's bytes in the file, padded to a multiple of 4."""
    raw = np.ascontiguousarray(block.data, dtype=_DTYPES[block.dtype]).tobytes()
    return raw + bytes(_align(len(raw)) - len(raw))


def head_bytes(n_ticks: int, tick_s: float, revision: int, blocks: list[Block], header: dict | None = None) -> bytes:
    """Magic, version, header length and the JSON header (padded to a multiple of 4) for ``blocks``,
    which follow it in order, each padded to a multiple of 4."""
    extra = dict(header or {})
    # The header length changes the offsets and the offsets change the header: iterate until stable.
    header_len = 0
    head = b""
    for _ in range(8):
        offset = _align(_PREFIX.size + header_len)
        entries = []
        for b in blocks:
            entries.append({"name": b.name, "dtype": b.dtype, "shape": list(b.data.shape), "offset": offset,
                            "scale": U8_SCALE if b.dtype == "u8" else 1.0})
            offset = _align(offset + b.data.nbytes)
        head = json.dumps({"n_ticks": int(n_ticks), "tick_s": tick_s, "revision": int(revision),
                           "blocks": entries, **extra}, separators=(",", ":")).encode("utf-8")
        if len(head) == header_len:
            break
        header_len = len(head)
    out = _PREFIX.pack(MAGIC, VERSION, header_len) + head
    return out + bytes(_align(len(out)) - len(out))


def encode(tl: Timeline, *, revision: int, blocks: list[Block] | None = None, header: dict | None = None) -> bytes:
    """The binary form of ``tl`` (see the module docstring): ``blocks`` (default: every block of
    ``tl``, see :func:`timeline_blocks`), ``header`` extra keys for the JSON header."""
    blocks = timeline_blocks(tl) if blocks is None else blocks
    return b"".join([head_bytes(tl.n_ticks, tl.tick_s, revision, blocks, header), *map(block_bytes, blocks)])


def deflate_segment(data: bytes, level: int = 1) -> bytes:
    """Raw DEFLATE of one segment, ended by a full flush (byte-aligned, no history), so segments
    compressed apart can be joined into one stream by :func:`gzip_join`."""
    c = zlib.compressobj(level, zlib.DEFLATED, -15)
    return c.compress(data) + c.flush(zlib.Z_FULL_FLUSH)


def gzip_join(plain: Sequence[bytes], deflated: Sequence[bytes]) -> bytes:
    """One gzip member (RFC 1952) whose content is ``b"".join(plain)``, from each segment's
    :func:`deflate_segment`: an unchanged block is compressed once, not with every revision."""
    crc, size = 0, 0
    for seg in plain:
        crc = zlib.crc32(seg, crc)
        size += len(seg)
    last = zlib.compressobj(1, zlib.DEFLATED, -15).flush(zlib.Z_FINISH)  # an empty final block
    head = b"\x1f\x8b\x08\x00\x00\x00\x00\x00\x00\xff"  # deflate, no flags, mtime 0, unknown OS
    return b"".join([head, *deflated, last, struct.pack("<II", crc, size & 0xFFFFFFFF)])


def decode(data: bytes) -> tuple[dict, dict[str, np.ndarray]]:
    """Read a binary timeline: (header, {block name: float64 values, de-quantised}).

    Raises ParameterError for a wrong magic, version, header or a block outside the data.
    """
    if len(data) < _PREFIX.size:
        raise ParameterError(f"binary timeline is {len(data)} bytes, shorter than its {_PREFIX.size}-byte prefix")
    magic, version, header_len = _PREFIX.unpack_from(data, 0)
    if magic != MAGIC:
        raise ParameterError(f"not a binary timeline: magic {magic!r}, expected {MAGIC!r}")
    if version != VERSION:
        raise ParameterError(f"binary timeline version {version}; this build reads version {VERSION}")
    end = _PREFIX.size + header_len
    if end > len(data):
        raise ParameterError(f"binary timeline header ({header_len} bytes) runs past the data ({len(data)} bytes)")
    try:
        header = json.loads(bytes(data[_PREFIX.size:end]).decode("utf-8"))
    except (UnicodeDecodeError, json.JSONDecodeError) as exc:
        raise ParameterError(f"binary timeline header is not UTF-8 JSON ({exc})") from None
    arrays: dict[str, np.ndarray] = {}
    for e in header.get("blocks", []):
        dtype = _DTYPES.get(e.get("dtype"))
        if dtype is None:
            raise ParameterError(f"block {e.get('name')!r} has unknown dtype {e.get('dtype')!r}")
        shape = tuple(int(s) for s in e["shape"])
        count = int(np.prod(shape)) if shape else 1
        start = int(e["offset"])
        stop = start + count * dtype.itemsize
        if start % 4 or stop > len(data):
            raise ParameterError(f"block {e['name']!r} at offset {start} ({stop - start} bytes) is misaligned "
                                 f"or runs past the data ({len(data)} bytes)")
        raw = np.frombuffer(data, dtype=dtype, count=count, offset=start).reshape(shape)
        arrays[e["name"]] = raw.astype(np.float64) * float(e["scale"])
    return header, arrays


def _align(n: int) -> int:
    return (n + 3) & ~3
