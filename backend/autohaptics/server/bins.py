"""The served binary timelines (``timeline.bin``) of the composer: blocks quantised and laid out
once per revision, a block whose values did not change reused (its bytes and its DEFLATE
segment), and the answer kept per (project, revision, layer, blocks, gzip, since).

``since`` (a revision the client holds): the answer leaves out every block whose bytes are the
same as that revision's and names them in the header's ``unchanged`` (with ``since``), so a
threshold commit sends the vibration and the curves, not the fans (docs/API.md "Binary timeline").
A revision no longer kept here is answered whole, without ``since``.
"""

from __future__ import annotations

import dataclasses
import hashlib
import os
import threading
from collections import OrderedDict
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from autohaptics.timeline import Timeline
from autohaptics.timeline import wire as binary

GZIP_LEVEL = 1  # the fans block is mostly zeros: level 1 already shrinks it ~10x, at ~100 MB/s
REVISIONS_KEPT = 4  # per project and layer: the revisions a ``since`` can name


@dataclass
class Encoded:
    """One block of a served binary timeline: quantised, its bytes, its DEFLATE segment (lazily)."""

    block: binary.Block
    source: Any  # the array it was quantised from (compared with the next revision's)
    plain: bytes
    deflated: bytes | None = None


class BinaryCache:
    """Encodes composed (or generated) timelines into their binary form for the composer."""

    def __init__(self, size: int):
        self._lock = threading.Lock()
        self._size = size
        # per (project, layer): {revision: {block name: Encoded}}, oldest first
        self._encoded: OrderedDict[tuple[str, str], OrderedDict[int, dict[str, Encoded]]] = OrderedDict()
        self._bins: OrderedDict[tuple, bytes] = OrderedDict()

    def get(self, pid: str, layer: str, revision: int, tl: Timeline, *, header: dict, names: tuple | None,
            gzipped: bool, since: int | None) -> bytes:
        """The binary timeline of ``tl`` at ``revision`` (``names``: the blocks to send, None: all;
        ``header``: extra header keys; ``since``: module docstring)."""
        key = (pid, revision, id(tl), layer, names, gzipped, since)
        with self._lock:
            hit = self._bins.get(key)
            if hit is not None:
                self._bins.move_to_end(key)
                return hit
        wanted = binary.wanted_names([name for name, _, _ in binary.block_sources(tl)], names)
        encoded, before = self._encoded_blocks(pid, layer, revision, tl, since, wanted)
        chosen = [e for e in encoded if e.block.name in wanted]
        header = dict(header)
        if before is not None:
            unchanged = [e.block.name for e in chosen if (old := before.get(e.block.name)) is not None
                         and old.plain is e.plain]
            chosen = [e for e in chosen if e.block.name not in unchanged]
            header.update(since=since, unchanged=unchanged)
        head = binary.head_bytes(tl.n_ticks, tl.tick_s, revision, [e.block for e in chosen], header)
        if gzipped:
            for e in chosen:
                if e.deflated is None:
                    e.deflated = binary.deflate_segment(e.plain, GZIP_LEVEL)
            data = binary.gzip_join([head, *(e.plain for e in chosen)],
                                    [binary.deflate_segment(head, GZIP_LEVEL), *(e.deflated for e in chosen)])
        else:
            data = b"".join([head, *(e.plain for e in chosen)])
        with self._lock:
            self._bins[key] = data
            self._bins.move_to_end(key)
            while len(self._bins) > 4 * self._size:
                self._bins.popitem(last=False)
        return data

    def prepare(self, pid: str, layer: str, revision: int, tl: Timeline) -> None:
        """Quantise every block of ``tl`` ahead of the requests (a project being warmed)."""
        self._encoded_blocks(pid, layer, revision, tl, None, None)

    def _encoded_blocks(self, pid: str, layer: str, revision: int, tl: Timeline, since: int | None,
                        wanted: set[str] | None) -> tuple[list[Encoded], dict[str, Encoded] | None]:
        """The blocks of ``tl`` named in ``wanted`` (None: all) quantised and laid out, with those
        of the revision already done, reusing the latest kept revision's blocks whose source values
        are the same (an edit of one lane leaves the fans' 11 MB as they were), and the blocks of
        revision ``since`` (None when not kept or not asked for)."""
        with self._lock:
            history = self._encoded.get((pid, layer), OrderedDict())
            current = history.get(revision) or {}
            latest = next((v for r, v in reversed(history.items()) if r != revision), {})
            previous = {**latest, **current}
            before = history.get(since) if since is not None else None
        same: dict[tuple[int, int], bool] = {}
        out: dict[str, Encoded] = {}
        for name, dtype, src in binary.block_sources(tl):
            if wanted is not None and name not in wanted:
                if name in current:
                    out[name] = current[name]
                continue
            e = previous.get(name)
            if e is not None:
                pair = (id(e.source), id(src))
                if pair not in same:
                    same[pair] = same_values(e.source, src)
                if same[pair]:
                    out[name] = e if e.source is src else dataclasses.replace(e, source=src)
                    continue
            block = binary.quantise(name, dtype, src)
            out[name] = Encoded(block=block, source=src, plain=binary.block_bytes(block))
        with self._lock:
            history = self._encoded.setdefault((pid, layer), OrderedDict())
            # merged: a request for some blocks that ends after the warm's prepare of the same
            # revision keeps the others (a later ``since`` of it would send them all again)
            history[revision] = {**history.get(revision, {}), **out}
            history.move_to_end(revision)
            while len(history) > REVISIONS_KEPT:
                history.popitem(last=False)
            self._encoded.move_to_end((pid, layer))
            while len(self._encoded) > 2 * self._size:
                self._encoded.popitem(last=False)
        return list(out.values()), before


class BinFiles:
    """Whole answers (no ``since``) of the revision on show, kept on disk in ``<project>/bins/``: a
    server that has not loaded the project yet (just started, or a job just ended) answers the
    editor's first requests from the file, without loading the generated layer. An answer is the
    same for as long as the revision is (every change bumps it); the files of older revisions are
    removed when a newer one is written, and the folder goes with the project."""

    def __init__(self, folder_of):
        self._folder_of = folder_of  # project id -> its folder

    def _path(self, pid: str, revision: int, layer: str, names: tuple | None, gzipped: bool) -> Path:
        what = hashlib.sha1(repr((layer, names, gzipped)).encode()).hexdigest()[:16]  # no request text in a path
        return self._folder_of(pid) / "bins" / f"{int(revision)}-{what}.bin"

    def read(self, pid: str, revision: int, layer: str, names: tuple | None, gzipped: bool) -> bytes | None:
        try:
            return self._path(pid, revision, layer, names, gzipped).read_bytes()
        except OSError:
            return None

    def write(self, pid: str, revision: int, layer: str, names: tuple | None, gzipped: bool, data: bytes) -> None:
        """Keep ``data`` as the answer at ``revision`` (written whole, then renamed into place)."""
        path = self._path(pid, revision, layer, names, gzipped)
        try:
            path.parent.mkdir(exist_ok=True)
            for old in path.parent.iterdir():
                if not old.name.startswith(f"{int(revision)}-"):
                    old.unlink(missing_ok=True)
            part = path.with_name(f"{path.name}.{threading.get_ident()}.part")
            part.write_bytes(data)
            os.replace(part, path)
        except OSError:  # the project folder went away meanwhile, or the disk is full: answered anyway
            pass


def same_values(a, b) -> bool:
    """The same array, or the same shape, dtype and values."""
    return a is b or (a.shape == b.shape and a.dtype == b.dtype and bool(np.array_equal(a, b)))


def picture_box(tl: Timeline) -> dict | None:
    """Where the fan grid lies in the film's frame: the rectangle the analysis read (the active picture
    inside black bars, a 3D film's first view; ``stats.video.active_area``) as fractions of the frame
    as shown, {x, y, w, h} in 0..1; None when the timeline does not say (no picture analysed)."""
    try:
        area = tl.stats["video"]["active_area"]
        (x, y, w, h), (fw, fh) = [float(v) for v in area["rect"]], [float(v) for v in area["frame"]]
    except (KeyError, TypeError, ValueError):
        return None
    if not (fw > 0 and fh > 0 and w > 0 and h > 0):
        return None
    return {"x": round(x / fw, 6), "y": round(y / fh, 6), "w": round(w / fw, 6), "h": round(h / fh, 6)}
