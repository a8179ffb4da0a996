"""A project's timelines on the server: the generated layer, re-deriving it, composing it with the edits.

- :class:`Composer` loads the generated timeline (``generated.npz``) and the feature cache (kept
  in memory while their files do not change), re-derives from the cache without decoding (the
  derived timeline stays in memory), composes ``apply_ops(generated, ops[:cursor])`` (kept per
  revision), and serves the binary form (:mod:`.bins`: unchanged blocks encoded once, and left
  out for a client that holds them).
- ``import`` edits: the document goes to ``projects/<id>/imports/<ref>.json``; the op stored in
  the edit list is ``{"op": "import", "ref", "name", "n_ticks"}``.

Stored parameters are ``{preset, mode, thresholds, overrides}``: ``thresholds`` are the effective
four values, ``overrides`` the user's dotted overrides.
"""

from __future__ import annotations

import dataclasses
import logging
import threading
import time
from collections import OrderedDict
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from autohaptics import pipeline
from autohaptics.pipeline import handoff
from autohaptics.params import params_from_doc
from autohaptics.errors import ParameterError
from autohaptics.formats.importing import parse_timeline
from autohaptics.timeline import edits as edit_ops
from autohaptics.timeline.npz import load_npz
from autohaptics.server import shots
from autohaptics.server.bins import BinaryCache, BinFiles, picture_box, same_values
from autohaptics.server.store import Conflict, NotFound, Store, file_key, new_id
from autohaptics.server.styles import style_of
from autohaptics.server.waveform import cached_peaks
from autohaptics.server.writer import LayerWriter
from autohaptics.timebase import TICK_S
from autohaptics.timeline import Timeline

log = logging.getLogger("autohaptics.server.composer")

def derive_timeline(analysis: pipeline.Analysis, doc: dict, *, name: str) -> Timeline:
    """The generated timeline for stored parameters ``doc`` from a feature cache (no decoding), in
    the style they name (``doc["style"]``, :mod:`.styles`)."""
    params, preset = params_from_doc(doc)
    tl = pipeline.derive(analysis, params, preset=preset, style=style_of(doc))
    tl.source["name"] = name
    return tl


@dataclass(frozen=True)
class Composed:
    revision: int
    timeline: Timeline  # generated + applied edits (shared: never modify it)
    markers: list[dict]
    ops: list[dict]  # the applied operations

    def document(self) -> Timeline:
        """The timeline to send or export: extra keys ``revision``, ``edits``, ``markers`` (arrays shared)."""
        extra = {**self.timeline.extra, "revision": self.revision, "edits": self.ops, "markers": self.markers}
        return dataclasses.replace(self.timeline, extra=extra)


@dataclass(frozen=True)
class Derived:
    revision: int
    seconds: float
    needs_analysis: bool


class Composer:
    """Loads, derives and composes timelines for the routes; caches by file identity and revision."""

    def __init__(self, store: Store, *, cache_size: int = 2):
        self.store = store
        self._lock = threading.Lock()
        self._files: OrderedDict[Path, tuple[tuple, Any]] = OrderedDict()
        self._loading: dict[Path, threading.Lock] = {}
        self._warming: set[Path] = set()
        self._handed: OrderedDict[str, tuple] = OrderedDict()  # per project: a job's (analysis key, layer key, kept)
        self._seeded: set[Path] = set()  # feature caches loaded with a job's complete hand-off
        self._composed: OrderedDict[str, tuple[tuple, Composed]] = OrderedDict()
        self._json: OrderedDict[str, tuple[Composed, bytes]] = OrderedDict()
        self._tracks: OrderedDict[str, dict[str, tuple]] = OrderedDict()  # per project: (generated, keys, composed)
        self.bins = BinaryCache(cache_size)
        self.bin_files = BinFiles(store.project_dir)
        self._waveform_locks: dict[str, threading.Lock] = {}
        self._size = cache_size
        self.writer = LayerWriter(store, self._written)
        self.on_warm: Callable[[str], None] | None = None  # also told of every warm (the pictures made ahead)

    # -------------------------------------------------------------------- loading
    def _cached(self, path: Path, load) -> Any:
        """``load(path)``, kept while the file is the same (inode, mtime, size); one load at a time
        per file, so concurrent requests of a long film's timeline wait for one read."""
        with self._lock:
            gate = self._loading.setdefault(path, threading.Lock())
        with gate:
            key = file_key(path)
            if key is None:
                return None
            with self._lock:
                hit = self._files.get(path)
                if hit is not None and hit[0] == key:
                    self._files.move_to_end(path)
                    return hit[1]
            value = load(path)
            self._remember(path, key, value)
            return value

    def _remember(self, path: Path, key: tuple, value: Any) -> None:
        with self._lock:
            self._files[path] = (key, value)
            self._files.move_to_end(path)
            while len(self._files) > 3 * self._size:
                self._files.popitem(last=False)

    def generated(self, pid: str) -> Timeline | None:
        """The generated timeline of ``pid`` (the latest re-derive, even before its file is written),
        or None before the first successful job."""
        pending = self.writer.pending(pid)
        return pending if pending is not None else self._cached(self.store.generated_path(pid), load_npz)

    def flush(self, pid: str | None = None) -> None:
        """Wait until ``pid``'s (None: every project's) re-derived layer is written (before a job's
        outputs replace it, a duplicate copies it, or the server stops)."""
        self.writer.flush(pid)

    def _written(self, pid: str, revision: int, key: tuple, tl: Timeline) -> None:
        """The writer stored ``tl``: the file's new identity keeps it in memory (unless a newer
        re-derive waits to be written)."""
        if self.writer.pending(pid) is tl:
            self._remember(self.store.generated_path(pid), key, tl)

    def analysis(self, pid: str) -> pipeline.Analysis | None:
        return self._cached(self.store.analysis_path(pid), lambda path: self._load_analysis(pid, path))

    def _load_analysis(self, pid: str, path: Path) -> pipeline.Analysis:
        """Load the feature cache; when it is the file a job just wrote, keep what the job's derive
        kept (:mod:`autohaptics.pipeline.handoff`), its picture tracks from the job's layer if loaded."""
        analysis = pipeline.Analysis.load(path)
        with self._lock:
            handed = self._handed.pop(pid, None)
        layer_path = self.store.generated_path(pid)
        if complete := handed is not None and handed[0] == file_key(path):
            layer = self._cached(layer_path, load_npz) if file_key(layer_path) == handed[1] else None
            complete = handoff.seed(analysis, handed[2], layer)
        with self._lock:  # a complete hand-off leaves the warm-up nothing to derive
            (self._seeded.add if complete else self._seeded.discard)(path)
        return analysis

    def _warm_analysis(self, pid: str) -> None:
        """Load the feature cache in the background when it is not in memory yet, and derive once
        from it (the derive keeps what no threshold changes): a project whose timeline is being
        looked at is about to be re-derived (a threshold drag)."""
        path = self.store.analysis_path(pid)
        key = file_key(path)
        with self._lock:
            hit = self._files.get(path)
            if key is None or (hit is not None and hit[0] == key) or path in self._warming:
                return
            self._warming.add(path)

        def load() -> None:
            try:
                analysis = self.analysis(pid)
                if analysis is not None and path not in self._seeded:  # the derive's kept curves and picture tracks
                    project = self.store.get_project(pid)
                    derive_timeline(analysis, project["params"], name=project["name"])
            except Exception as exc:  # the re-derive will report it
                log.info("project %s: feature cache not loaded ahead (%s)", pid, exc)
            finally:
                with self._lock:
                    self._warming.discard(path)

        threading.Thread(target=load, name=f"warm-analysis {pid}", daemon=True).start()

    def warm(self, pid: str, kept: dict | None = None) -> None:
        """Load ``pid``'s generated layer, its composition (its blocks quantised) and its feature
        cache in the background: at start-up, the project worked on last opens without waiting for
        a long film's files, and after a job, the first commit finds them loaded.

        kept : after a job, what its derive kept (:func:`handoff.kept_of`), for its files as they are now."""
        if kept is not None:
            with self._lock:
                self._handed[pid] = (file_key(self.store.analysis_path(pid)),
                                     file_key(self.store.generated_path(pid)), kept)
                while len(self._handed) > self._size:
                    self._handed.popitem(last=False)
        def load() -> None:
            self._warm_analysis(pid)  # beside the layer's load
            try:
                composed = self.compose(pid)
                self.bins.prepare(pid, "composed", composed.revision, composed.timeline)
            except Exception as exc:  # the editor's own requests will report it
                log.info("project %s: not loaded ahead (%s)", pid, exc)

        threading.Thread(target=load, name=f"warm {pid}", daemon=True).start()
        if self.on_warm is not None:
            self.on_warm(pid)

    def held(self, pid: str) -> bool:
        """Whether ``pid`` is warm: its composition at the current revision and its feature cache
        (derived from once) are in memory, so a threshold commit loads nothing."""
        path = self.store.analysis_path(pid)
        with self._lock:
            hit, composed = self._files.get(path), self._composed.get(pid)
            loaded = hit is not None and hit[0] == file_key(path) and path not in self._warming
        return loaded and composed is not None and composed[1].revision == self.store.revision(pid)

    def require_generated(self, pid: str) -> Timeline:
        tl = self.generated(pid)
        if tl is None:
            raise NotFound(f"project {pid} has no timeline yet; generate one first")
        return tl

    def _import(self, pid: str, ref: str) -> Timeline:
        tl = self._cached(self.store.import_path(pid, ref), Timeline.load)
        if tl is None:
            raise ParameterError(f"the imported timeline {ref} of project {pid} is missing")
        return tl

    # -------------------------------------------------------------------- derive
    def rederive(self, pid: str, doc: dict, *, previous: bool = False) -> Derived | None:
        """Derive from the cached analysis with parameters ``doc``; the derived timeline is the
        project's generated layer at once (in memory) and its .npz is written in the background.

        previous : when the cache does not serve ``doc`` but the previous one does (``doc`` is the
        parameters a regeneration replaced), that one becomes the current cache. Only while no
        job of the project runs (a job reads the cache).

        Returns None when no cache serves ``doc`` (a job is needed). ``seconds`` covers loading
        the cache and deriving.
        """
        t0 = time.perf_counter()
        params, _ = params_from_doc(doc)
        analysis = self._serving(pid, params, previous=previous)
        if analysis is None:
            return None
        project = self.store.get_project(pid)
        tl = derive_timeline(analysis, doc, name=project["name"])
        revision = self.store.rederived(pid, params=doc)
        self.writer.put(pid, revision, tl)  # answered now, written after (.writer)
        return Derived(revision=revision, seconds=time.perf_counter() - t0,
                       needs_analysis=bool(tl.stats.get("needs_analysis")))

    def _serving(self, pid: str, params, *, previous: bool) -> pipeline.Analysis | None:
        """The feature cache that serves ``params``: the current one, else (``previous``) the
        previous one, swapped in; None when neither does."""
        analysis = self.analysis(pid)
        if analysis is None:
            return None
        if pipeline.reusable(analysis, params):
            return analysis
        if not previous:
            return None
        before = self._cached(self.store.previous_analysis_path(pid), pipeline.Analysis.load)
        if before is None or not pipeline.reusable(before, params):
            return None
        self.store.swap_analyses(pid)
        for path, value in ((self.store.analysis_path(pid), before), (self.store.previous_analysis_path(pid), analysis)):
            self._remember(path, file_key(path), value)
        return before

    # ------------------------------------------------------------------- compose
    def compose(self, pid: str) -> Composed:
        """The composed timeline at the project's current revision (and the project's feature
        cache starts loading in the background, for the re-derive that is likely to follow)."""
        revision, ops, project = self.store.snapshot(pid)
        generated = self.require_generated(pid)
        self._warm_analysis(pid)
        key = (revision, id(generated), project["name"])
        with self._lock:
            hit = self._composed.get(pid)
            if hit is not None and hit[0] == key:
                return hit[1]
        keys = edit_ops.track_keys(ops)
        with self._lock:
            previous = self._tracks.get(pid, {})
        reuse = {}
        for track in edit_ops.TRACKS:  # a track whose generated values and edits are unchanged is kept
            hit = previous.get(track)
            if hit is not None and hit[1] == keys[track] and same_values(hit[0], getattr(generated, track)):
                reuse[track] = hit[2]
        tl, markers = edit_ops.apply_ops(generated, ops, imports=lambda ref: self._import(pid, ref), reuse=reuse)
        tl.source["name"] = project["name"]
        composed = Composed(revision=revision, timeline=tl, markers=markers, ops=ops)
        with self._lock:
            self._tracks[pid] = {t: (getattr(generated, t), keys[t], getattr(tl, t)) for t in edit_ops.TRACKS}
            self._tracks.move_to_end(pid)
            while len(self._tracks) > self._size:
                self._tracks.popitem(last=False)
            self._composed[pid] = (key, composed)
            self._composed.move_to_end(pid)
            while len(self._composed) > self._size:
                self._composed.popitem(last=False)
        return composed

    # --------------------------------------------------------------------- edits
    def markers(self, pid: str, ops: list[dict]) -> list[dict]:
        """The markers after ``ops`` (the applied ones), as the composition has them."""
        generated = self.generated(pid)
        n = generated.n_ticks if generated is not None else self.store.get_project(pid)["n_ticks"]
        return edit_ops.fold_markers(ops, n * TICK_S)

    def edits(self, pid: str) -> dict:
        """``{revision, cursor, ops, markers}``; stored imports appear as their reference."""
        e = self.store.edits(pid)
        return {**e, "markers": self.markers(pid, e["ops"][:e["cursor"]])}

    def check_op(self, pid: str, op: Any, *, base_revision: int | None) -> dict:
        """Validate ``op`` against the composition at ``base_revision`` (strict); returns the
        normalised op. ``base_revision`` None checks against the current one.

        Conflict when the project has no timeline yet or the revision moved on; ParameterError
        for an invalid op (a stored import must name one of this project's imports).
        """
        normalised = edit_ops.validate_op(op)
        if normalised["op"] == "params":
            raise ParameterError("op 'params' is recorded by PUT /api/projects/{id}/params; change the parameters there")
        if self.generated(pid) is None:
            raise Conflict("the project has no timeline yet; edits need a generated timeline")
        current = self.store.revision(pid)
        if base_revision is not None and current != base_revision:
            raise Conflict(f"the timeline changed meanwhile (revision {current}, the request was "
                           f"based on {base_revision}); reload and try again")
        if normalised["op"] == "import":  # nothing in an import depends on the composition
            if edit_ops.is_stored_import(normalised):
                self._import(pid, normalised["ref"])
            return normalised
        composed = self.compose(pid)
        edit_ops.apply_ops(composed.timeline, [normalised], strict=True, markers=composed.markers)
        shots.check_op(self.analysis(pid), composed.ops, normalised, composed.timeline.n_ticks)
        return normalised

    def append(self, pid: str, base_revision: int | None, op: Any) -> dict:
        """Validate ``op`` and append it at the cursor: ``{revision, cursor, op, markers}`` (the op as
        stored). An ``import`` with its document is stored as a reference to a file.

        ``base_revision`` None appends on top of the current revision."""
        normalised = self.check_op(pid, op, base_revision=base_revision)
        if normalised["op"] == "import" and not edit_ops.is_stored_import(normalised):
            return self._append_import(pid, base_revision, Timeline.from_dict(normalised["timeline"]),
                                       name="timeline")
        return self._append(pid, base_revision, normalised)

    def _append(self, pid: str, base_revision: int | None, op: dict) -> dict:
        if base_revision is None:
            base_revision = self.store.revision(pid)
        res = self.store.append_edit(pid, base_revision, op)
        return {**res, "op": op, "markers": self._markers_at(pid, res["cursor"])}

    def _append_import(self, pid: str, base_revision: int | None, tl: Timeline, *, name: str) -> dict:
        if self.generated(pid) is None:
            raise Conflict("the project has no timeline yet; edits need a generated timeline")
        for key in ("edits", "markers", "revision"):
            tl.extra.pop(key, None)
        ref = new_id()
        path = self.store.import_path(pid, ref)
        path.parent.mkdir(exist_ok=True)
        tl.save(path)
        op = {"op": "import", "ref": ref, "name": name, "n_ticks": int(tl.n_ticks)}
        try:
            return self._append(pid, base_revision, op)
        except BaseException:
            path.unlink(missing_ok=True)
            raise

    def undo(self, pid: str, base_revision: int) -> dict:
        res = self.store.undo(pid, base_revision)
        return {**res, "markers": self._markers_at(pid, res["cursor"])}

    def redo(self, pid: str, base_revision: int) -> dict:
        res = self.store.redo(pid, base_revision)
        return {**res, "markers": self._markers_at(pid, res["cursor"])}

    def _markers_at(self, pid: str, cursor: int) -> list[dict]:
        return self.markers(pid, self.store.edits(pid)["ops"][:cursor])

    def import_file(self, pid: str, data: bytes, *, name: str, base_revision: int | None) -> dict:
        """Append an ``import`` op built from an uploaded timeline file (our JSON or CSV).

        The format comes from ``name``'s suffix (.json / .csv), else from the content; the
        document's own ``edits`` / ``markers`` / ``revision`` keys are not imported."""
        suffix = Path(name).suffix.lower()
        fmt = suffix[1:] if suffix in (".json", ".csv") else None
        tl = parse_timeline(data, fmt=fmt, name=name)
        current = self.store.revision(pid)
        if base_revision is not None and current != base_revision:
            raise Conflict(f"the timeline changed meanwhile (revision {current}, the request was "
                           f"based on {base_revision}); reload and try again")
        return self._append_import(pid, base_revision, tl, name=name)

    # --------------------------------------------------------------- documents
    def timeline_json(self, pid: str, *, layer: str = "composed") -> bytes:
        """The composed timeline document as UTF-8 JSON (TIMELINE.md plus revision/edits/markers),
        or the generated layer's (``layer="generated"``, plus ``revision``)."""
        composed = self.compose(pid)
        if layer == "generated":
            tl = self.require_generated(pid)
            return dataclasses.replace(tl, extra={**tl.extra, "revision": composed.revision}).to_json().encode()
        with self._lock:
            hit = self._json.get(pid)
            if hit is not None and hit[0] is composed:
                return hit[1]
        data = composed.document().to_json().encode("utf-8")
        with self._lock:
            self._json[pid] = (composed, data)
            while len(self._json) > self._size:
                self._json.popitem(last=False)
        return data

    def timeline_bin(self, pid: str, *, layer: str = "composed", blocks: list[str] | None = None,
                     gzipped: bool = False, since: int | None = None) -> tuple[bytes, str]:
        """The binary timeline and its ETag, kept per (project, revision, layer, blocks, gzip, since).

        ``blocks``: the block names to send (None: all; see :func:`binary.select_blocks`);
        ``since``: a revision the client holds, whose unchanged blocks are left out (:mod:`.bins`).
        The header carries the picture box (:func:`.bins.picture_box`); the composed layer's, the markers."""
        names = None if blocks is None else tuple(sorted(set(blocks)))

        def tag(revision: int) -> str:
            return (f"{pid}-{revision}-{layer}-{','.join(names) if names else 'all'}"
                    f"{'' if since is None else f'-since{since}'}")

        kept = since is None and gzipped  # an editor's first requests: kept on disk (.bins.BinFiles)
        if kept and (data := self.bin_files.read(pid, revision := self.store.revision(pid), layer, names,
                                                 gzipped)) is not None:
            return data, tag(revision)
        composed = self.compose(pid)
        tl = composed.timeline if layer == "composed" else self.require_generated(pid)
        header = {"picture": picture_box(tl), **({"markers": composed.markers} if layer == "composed" else {})}
        data = self.bins.get(pid, layer, composed.revision, tl, header=header, names=names, gzipped=gzipped,
                             since=since)
        if kept and self.writer.pending(pid) is None:  # the generated layer it came from is on disk
            self.bin_files.write(pid, composed.revision, layer, names, gzipped, data)
        return data, tag(composed.revision)

    # ------------------------------------------------------------------ waveform
    def waveform(self, pid: str, points: int) -> dict:
        """Audio peaks of the project's media, computed once per ``points`` and cached on disk."""
        project = self.store.get_project(pid)
        with self._lock:
            lock = self._waveform_locks.setdefault(pid, threading.Lock())
        with lock:
            return cached_peaks(self.store.media_path(project), self.store.waveform_path(pid, points),
                                points=points)
