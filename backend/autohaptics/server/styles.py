"""Learned styles on the server (docs/STYLE_FORMAT.md, docs/API.md "Styles").

- :class:`Styles` keeps them: the checked document in ``<data>/styles/<id>.json`` (server-chosen
  id, never a client's name), its name, the projects it was learned from and the report of how
  much of each film's edits it explains in the ``styles`` table of the data folder's database.
- :func:`learn_from_projects` learns one from projects (each one's cached analysis and composed
  timeline) with :func:`autohaptics.style.learn` and reports with :func:`autohaptics.style.explain`.
- A project's stored parameters name the style they derive in as ``style: {id, name, document}``
  (:func:`style_ref`): the document travels with the parameters, so Regenerate, a threshold change,
  undo and a job in another process derive in the same style, also after the style is deleted.
"""

from __future__ import annotations

import dataclasses
import json
import os
import sqlite3
import threading
from pathlib import Path

from autohaptics.errors import ParameterError
from autohaptics.params import params_from_doc
from autohaptics.server.db import DB_NAME, Conflict, NotFound, check_id, new_id, now_iso
from autohaptics.server.uploads import display_name
from autohaptics.style import Style, from_dict, to_dict

MAX_STYLE_BYTES = 1024 * 1024  # a style file (12 knots: about 2 kB)
MAX_PROJECTS = 20  # projects one style is learned from


def style_of(doc: dict) -> Style | None:
    """The style a stored parameter document derives in, or None."""
    ref = doc.get("style")
    return None if not ref else from_dict(ref["document"])


def style_ref(style: dict) -> dict:
    """What a project's parameter document holds of a stored style (``Styles.get``'s answer)."""
    return {"id": style["id"], "name": style["name"], "document": style["document"]}


def parse_style_file(data: bytes, *, fallback_name: str) -> Style:
    """A style from an imported file's bytes; ParameterError with one sentence naming the field. Its
    name is made a display name (no control characters, at most 200), else ``fallback_name``."""
    if len(data) > MAX_STYLE_BYTES:
        raise ParameterError(f"a style file holds at most {MAX_STYLE_BYTES} bytes, got {len(data)}")
    try:
        doc = json.loads(data.decode("utf-8"))
    except (UnicodeDecodeError, json.JSONDecodeError) as exc:
        raise ParameterError(f"not a style file (not JSON: {exc})") from None
    style = from_dict(doc)
    name = display_name(style.name, basename=False, fallback="") or fallback_name
    return style if name == style.name else dataclasses.replace(style, name=name)


def learn_from_projects(store, composer, project_ids: list[str], *, name: str) -> tuple[Style, list[dict]]:
    """(the style learned from ``project_ids``' edits, a report per project: ``{project_id, name,
    plain, styled, explained}``, :func:`autohaptics.style.explain`). The projects must start from
    the same parameters (a style is relative to them) and have a timeline (Conflict otherwise)."""
    from autohaptics.style import explain, learn  # the pipeline loads on first use

    if len(set(project_ids)) != len(project_ids):
        raise ParameterError("field 'project_ids' names a project twice")
    projects = [store.get_project(pid) for pid in project_ids]
    first = projects[0]
    for project in projects[1:]:
        if _plain(project["params"]) != _plain(first["params"]):
            raise ParameterError(f"projects {first['name']!r} and {project['name']!r} start from different "
                                 "parameters (preset, mode, thresholds); learn a style from one of them")
    pairs = []
    for project in projects:
        analysis = composer.analysis(project["id"])
        if analysis is None or not project["has_timeline"]:
            raise Conflict(f"project {project['name']!r} has no timeline yet; generate one first")
        pairs.append((analysis, composer.compose(project["id"]).timeline))
    params, _ = params_from_doc(first["params"])
    style = learn(pairs, params, name=name)
    report = [{"project_id": p["id"], "name": p["name"], **r}
              for p, r in zip(projects, explain(pairs, params, style))]
    return style, report


class Styles:
    """The stored styles of a data folder (its own connection to the folder's database, whose
    ``styles`` table the :class:`~autohaptics.server.store.Store` creates)."""

    def __init__(self, data_dir: str | os.PathLike):
        self.dir = Path(data_dir).resolve() / "styles"
        self.dir.mkdir(parents=True, exist_ok=True)
        self._lock = threading.Lock()
        self._db = sqlite3.connect(Path(data_dir) / DB_NAME, check_same_thread=False, isolation_level=None)
        self._db.row_factory = sqlite3.Row

    def close(self) -> None:
        with self._lock:
            self._db.close()

    def path(self, sid: str) -> Path:
        return self.dir / f"{check_id(sid, 'style')}.json"

    def add(self, style: Style, *, films: list[dict], report: list[dict]) -> dict:
        """Store ``style`` (file first, then its row: a crash leaves at most an unlisted file)."""
        sid = new_id()
        part = self.dir / f"{sid}.part"
        part.write_text(json.dumps(to_dict(style), indent=1) + "\n", encoding="utf-8")
        os.replace(part, self.path(sid))
        with self._lock:
            self._db.execute("INSERT INTO styles (id, name, created_at, films, report) VALUES (?, ?, ?, ?, ?)",
                             (sid, style.name, now_iso(), json.dumps(films), json.dumps(report)))
        return self.get(sid)

    def list(self) -> list[dict]:
        with self._lock:
            rows = self._db.execute("SELECT * FROM styles ORDER BY created_at DESC, id").fetchall()
        return [_summary(row) for row in rows]

    def get(self, sid: str) -> dict:
        """The stored style with its document; NotFound for an unknown id."""
        path = self.path(sid)
        with self._lock:
            row = self._db.execute("SELECT * FROM styles WHERE id=?", (sid,)).fetchone()
        if row is None:
            raise NotFound(f"no style with id {sid!r}")
        try:
            document = json.loads(path.read_text(encoding="utf-8"))
        except (OSError, ValueError):
            raise NotFound(f"the file of style {sid!r} is missing or damaged in the data folder") from None
        return {**_summary(row), "document": document}

    def delete(self, sid: str) -> None:
        path = self.path(sid)
        with self._lock:
            gone = self._db.execute("DELETE FROM styles WHERE id=?", (sid,)).rowcount
        if not gone:
            raise NotFound(f"no style with id {sid!r}")
        path.unlink(missing_ok=True)


def _summary(row: sqlite3.Row) -> dict:
    return {"id": row["id"], "name": row["name"], "created_at": row["created_at"],
            "films": json.loads(row["films"]), "report": json.loads(row["report"])}


def _plain(doc: dict) -> dict:
    """A parameter document without its style (what a style is learned relative to)."""
    return {k: v for k, v in doc.items() if k != "style"}
