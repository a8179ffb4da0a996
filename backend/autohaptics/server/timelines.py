"""A project's timelines: parameters, the generated timeline, re-deriving, composing with edits.

- :func:`resolve` merges requested parameters into a project's stored ones and validates them
  through :func:`pipeline.resolve_params` (ParameterError -> 400).
- :class:`Timelines` loads the generated timeline and the feature cache (kept in memory while
  their files do not change), re-derives from the cache without decoding, and composes
  ``apply_ops(generated, ops[:cursor])`` (kept per revision).

Stored parameters are ``{preset, mode, thresholds, overrides}``: ``thresholds`` are the effective
four values, ``overrides`` the user's dotted overrides.
"""

from __future__ import annotations

import dataclasses
import threading
import time
from collections import OrderedDict
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from autohaptics import pipeline
from autohaptics.importers import parse_timeline
from autohaptics.server import edits as edit_ops
from autohaptics.server.store import Conflict, NotFound, Store, new_id
from autohaptics.server.waveform import cached_peaks
from autohaptics.timeline import Timeline

DEFAULT_PARAMS = {"preset": "balanced", "mode": None, "thresholds": {}, "overrides": {}}


def params_from_doc(doc: dict) -> tuple[pipeline.GenerateParams, str]:
    """(GenerateParams, preset) for stored parameters."""
    overrides = dict(doc.get("overrides") or {})
    if doc.get("mode"):
        overrides["mode"] = doc["mode"]
    return pipeline.resolve_params(doc.get("preset") or "balanced", overrides, doc.get("thresholds") or {})


def resolve(current: dict | None, *, preset: str | None = None, mode: str | None = None,
            thresholds: dict | None = None, overrides: dict | None = None) -> tuple[dict, pipeline.GenerateParams]:
    """New stored parameters: each given field replaces the current one whole, the others stay."""
    cur = {**DEFAULT_PARAMS, **(current or {})}
    doc = {
        "preset": preset if preset is not None else cur["preset"],
        "mode": mode if mode is not None else cur["mode"],
        "thresholds": dict(thresholds) if thresholds is not None else dict(cur["thresholds"]),
        "overrides": dict(overrides) if overrides is not None else dict(cur["overrides"]),
    }
    params, preset_name = params_from_doc(doc)
    doc["preset"] = preset_name
    doc["mode"] = params.mode
    doc["thresholds"] = dict(params.intensity.thresholds)
    return doc, params


def derive_timeline(analysis: pipeline.Analysis, doc: dict, *, name: str) -> Timeline:
    """The generated timeline for stored parameters ``doc`` from a feature cache (no decoding)."""
    params, preset = params_from_doc(doc)
    tl = pipeline.derive(analysis, params, preset=preset)
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


class Timelines:
    """Loads, derives and composes timelines for the routes; caches by file identity and revision."""

    def __init__(self, store: Store, *, cache_size: int = 2):
        self.store = store
        self._lock = threading.Lock()
        self._files: OrderedDict[Path, tuple[tuple, Any]] = OrderedDict()
        self._composed: OrderedDict[str, tuple[tuple, Composed]] = OrderedDict()
        self._json: OrderedDict[str, tuple[Composed, bytes]] = OrderedDict()
        self._waveform_locks: dict[str, threading.Lock] = {}
        self._size = cache_size

    # -------------------------------------------------------------------- loading
    def _cached(self, path: Path, load) -> Any:
        try:
            st = path.stat()
        except FileNotFoundError:
            return None
        key = (st.st_ino, st.st_mtime_ns, st.st_size)
        with self._lock:
            hit = self._files.get(path)
            if hit is not None and hit[0] == key:
                self._files.move_to_end(path)
                return hit[1]
        value = load(path)
        with self._lock:
            self._files[path] = (key, value)
            while len(self._files) > 2 * self._size:
                self._files.popitem(last=False)
        return value

    def generated(self, pid: str) -> Timeline | None:
        """The generated timeline of ``pid``, or None before the first successful job."""
        return self._cached(self.store.generated_path(pid), Timeline.load)

    def analysis(self, pid: str) -> pipeline.Analysis | None:
        return self._cached(self.store.analysis_path(pid), pipeline.Analysis.load)

    def require_generated(self, pid: str) -> Timeline:
        tl = self.generated(pid)
        if tl is None:
            raise NotFound(f"project {pid} has no timeline yet; generate one first")
        return tl

    # -------------------------------------------------------------------- derive
    def rederive(self, pid: str, doc: dict) -> Derived | None:
        """Derive from the cached analysis with parameters ``doc`` and store the result.

        Returns None when there is no cache or ``doc`` changes analysis parameters (a job is
        needed). ``seconds`` covers loading the cache, deriving and writing the timeline.
        """
        t0 = time.perf_counter()
        analysis = self.analysis(pid)
        if analysis is None:
            return None
        params, _ = params_from_doc(doc)
        if not pipeline.analysis_compatible(analysis, params):
            return None
        project = self.store.get_project(pid)
        tl = derive_timeline(analysis, doc, name=project["name"])
        tmp = self.store.work_dir / f"derive-{new_id()}.json"
        try:
            tl.save(tmp)
            revision = self.store.replace_generated(pid, tmp, params=doc)
        finally:
            tmp.unlink(missing_ok=True)
        return Derived(revision=revision, seconds=time.perf_counter() - t0,
                       needs_analysis=bool(tl.stats.get("needs_analysis")))

    # ------------------------------------------------------------------- compose
    def compose(self, pid: str) -> Composed:
        """The composed timeline at the project's current revision."""
        revision, ops, project = self.store.snapshot(pid)
        generated = self.require_generated(pid)
        key = (revision, id(generated), project["name"])
        with self._lock:
            hit = self._composed.get(pid)
            if hit is not None and hit[0] == key:
                return hit[1]
        tl, markers = edit_ops.apply_ops(generated, ops)
        tl.source["name"] = project["name"]
        composed = Composed(revision=revision, timeline=tl, markers=markers, ops=ops)
        with self._lock:
            self._composed[pid] = (key, composed)
            self._composed.move_to_end(pid)
            while len(self._composed) > self._size:
                self._composed.popitem(last=False)
        return composed

    def check_op(self, pid: str, op: Any, *, base_revision: int | None) -> dict:
        """Validate ``op`` against the composition at ``base_revision`` (strict); returns the
        normalised op. ``base_revision`` None checks against the current one.

        Conflict when the project has no timeline yet or the revision moved on; ParameterError
        for an invalid op.
        """
        normalised = edit_ops.validate_op(op)
        if self.generated(pid) is None:
            raise Conflict("the project has no timeline yet; edits need a generated timeline")
        composed = self.compose(pid)
        if base_revision is not None and composed.revision != base_revision:
            raise Conflict(f"the timeline changed meanwhile (revision {composed.revision}, the request was "
                           f"based on {base_revision}); reload and try again")
        edit_ops.apply_ops(composed.timeline, [normalised], strict=True, markers=composed.markers)
        return normalised

    def append(self, pid: str, base_revision: int | None, op: Any) -> dict:
        """Validate ``op`` and append it at the cursor: ``{revision, cursor, op}`` (the op as stored).

        ``base_revision`` None appends on top of the current revision."""
        normalised = self.check_op(pid, op, base_revision=base_revision)
        if base_revision is None:
            base_revision = self.store.get_project(pid)["revision"]
        return {**self.store.append_edit(pid, base_revision, normalised), "op": normalised}

    def import_file(self, pid: str, data: bytes, *, name: str, base_revision: int | None) -> dict:
        """Append an ``import`` op built from an uploaded timeline file (our JSON or CSV).

        The format comes from ``name``'s suffix (.json / .csv), else from the content; the
        document's own ``edits`` / ``markers`` / ``revision`` keys are not imported."""
        suffix = Path(name).suffix.lower()
        fmt = suffix[1:] if suffix in (".json", ".csv") else None
        doc = parse_timeline(data, fmt=fmt, name=name).to_dict()
        for key in ("edits", "markers", "revision"):
            doc.pop(key, None)
        return self.append(pid, base_revision, {"op": "import", "timeline": doc})

    def timeline_json(self, pid: str) -> bytes:
        """The composed timeline document as UTF-8 JSON (TIMELINE.md plus revision/edits/markers)."""
        composed = self.compose(pid)
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

    # ------------------------------------------------------------------ waveform
    def waveform(self, pid: str, points: int) -> dict:
        """Audio peaks of the project's media, computed once per ``points`` and cached on disk."""
        project = self.store.get_project(pid)
        with self._lock:
            lock = self._waveform_locks.setdefault(pid, threading.Lock())
        with lock:
            return cached_peaks(self.store.media_path(project), self.store.waveform_path(pid, points),
                                points=points)
