"""Persistence: projects, jobs and edit history in SQLite, project files in the data folder.

Layout of ``data_dir``::

    autohaptics.sqlite3          projects, jobs, edits, settings (service-wide, e.g. the chair's)
    projects/<id>/<uuid>.<ext>   the uploaded media (server-chosen name)
    projects/<id>/analysis.npz   the feature cache (pipeline.Analysis)
    projects/<id>/analysis-previous.npz  the cache it replaced when a job analysed with other
                                 analysis parameters (undoing that change re-derives from it)
    projects/<id>/generated.npz  the generated timeline (never edited; edits live in the database)
    projects/<id>/imports/<ref>.json  the document of each ``import`` edit (the op keeps ``ref``)
    projects/<id>/waveform-<N>.json  cached audio peaks
    uploads/<uuid>.part          uploads in flight (removed on failure and on start)
    work/<job id>/               a running job's outputs (moved into the project when it succeeds)

Ids are 32 lower-case hex digits chosen here; no client-supplied string ever becomes a path.
One connection guarded by a lock serves every thread; writes run in ``BEGIN IMMEDIATE``
transactions, so the revision check of an edit and its insertion are atomic.

``revision`` counts changes of a project's composed timeline (edit, undo, redo, a re-derive, a
finished job); an edit must name the revision it was based on, or it is refused (Conflict).
"""

from __future__ import annotations

import contextlib
import json
import os
import shutil
import sqlite3
import threading
from collections.abc import Iterator
from pathlib import Path

from autohaptics.server.db import (  # noqa: F401  the store's own errors and ids, where callers expect them
    ACTIVE_JOB_STATES,
    DB_NAME,
    GENERATED,
    SCHEMA,
    Conflict,
    NotFound,
    check_id,
    file_key,
    new_id,
    now_iso,
)

class Store:
    """SQLite database plus the project folders under ``data_dir``."""

    def __init__(self, data_dir: str | os.PathLike):
        self.data_dir = Path(data_dir).resolve()
        self.projects_dir = self.data_dir / "projects"
        self.uploads_dir = self.data_dir / "uploads"
        self.work_dir = self.data_dir / "work"
        for d in (self.data_dir, self.projects_dir, self.uploads_dir, self.work_dir):
            d.mkdir(parents=True, exist_ok=True)
        self._lock = threading.RLock()
        self._db = sqlite3.connect(self.data_dir / DB_NAME, check_same_thread=False, isolation_level=None)
        self._db.row_factory = sqlite3.Row
        self._db.execute("PRAGMA journal_mode=WAL")
        self._db.execute("PRAGMA synchronous=NORMAL")
        self._db.executescript(SCHEMA)

    def close(self) -> None:
        with self._lock:
            self._db.close()

    # ------------------------------------------------------------------ plumbing
    @contextlib.contextmanager
    def _tx(self) -> Iterator[sqlite3.Connection]:
        with self._lock:
            self._db.execute("BEGIN IMMEDIATE")
            try:
                yield self._db
            except BaseException:
                self._db.execute("ROLLBACK")
                raise
            self._db.execute("COMMIT")

    def _one(self, sql: str, args: tuple = ()) -> sqlite3.Row | None:
        with self._lock:
            return self._db.execute(sql, args).fetchone()

    def _all(self, sql: str, args: tuple = ()) -> list[sqlite3.Row]:
        with self._lock:
            return self._db.execute(sql, args).fetchall()

    # --------------------------------------------------------------------- paths
    def project_dir(self, pid: str) -> Path:
        return self.projects_dir / check_id(pid)

    def media_path(self, project: dict) -> Path:
        return self.project_dir(project["id"]) / project["media_file"]

    def analysis_path(self, pid: str) -> Path:
        return self.project_dir(pid) / "analysis.npz"

    def previous_analysis_path(self, pid: str) -> Path:
        return self.project_dir(pid) / "analysis-previous.npz"

    def swap_analyses(self, pid: str) -> None:
        """The previous feature cache becomes the current one and the current one the previous
        (parameters that need the previous analysis are in force again)."""
        current, previous = self.analysis_path(pid), self.previous_analysis_path(pid)
        held = current.with_name("analysis-swap.npz")
        os.replace(current, held)
        os.replace(previous, current)
        os.replace(held, previous)

    def generated_path(self, pid: str) -> Path:
        return self.project_dir(pid) / GENERATED

    def import_path(self, pid: str, ref: str) -> Path:
        return self.project_dir(pid) / "imports" / f"{check_id(ref, 'import')}.json"

    def waveform_path(self, pid: str, points: int) -> Path:
        return self.project_dir(pid) / f"waveform-{int(points)}.json"

    def new_upload_path(self) -> Path:
        return self.uploads_dir / f"{new_id()}.part"

    def job_work_dir(self, job_id: str) -> Path:
        return self.work_dir / check_id(job_id, "job")

    # ------------------------------------------------------------------ recovery
    def recover(self) -> list[dict]:
        """After a (re)start: stray uploads and work folders removed; jobs left queued or running
        queued again from the start (progress 0) with their project's current parameters (the
        designer's latest), their projects shown as running, never as failed. Returns those jobs,
        oldest first, for :meth:`JobRunner.resume`."""
        for d in (self.uploads_dir, self.work_dir):
            for p in d.iterdir():
                if p.is_dir():
                    shutil.rmtree(p, ignore_errors=True)
                else:
                    p.unlink(missing_ok=True)
        with self._tx() as db:
            rows = db.execute(f"SELECT j.id, j.project_id, p.params FROM jobs j JOIN projects p ON"
                              f" p.id = j.project_id WHERE j.status IN {ACTIVE_JOB_STATES}"
                              f" ORDER BY j.created_at").fetchall()
            stamp = now_iso()
            for r in rows:
                db.execute("UPDATE jobs SET status='queued', progress=0, stage='', started_at=NULL, params=?"
                           " WHERE id=?", (r["params"], r["id"]))
                db.execute("UPDATE projects SET status='running', job_id=?, updated_at=? WHERE id=?",
                           (r["id"], stamp, r["project_id"]))
        for r in rows:
            self.job_work_dir(r["id"]).mkdir(exist_ok=True)
        return [self.get_job(r["id"]) for r in rows]

    # ------------------------------------------------------------------ projects
    def create_project(self, upload: Path, *, media_file: str, media_type: str, name: str, source: dict,
                       params: dict, n_ticks: int, duration_s: float) -> dict:
        """Move an accepted upload into a new project folder and record the project."""
        pid = new_id()
        pdir = self.projects_dir / pid
        pdir.mkdir()
        try:
            os.replace(upload, pdir / media_file)
            stamp = now_iso()
            with self._tx() as db:
                db.execute(
                    "INSERT INTO projects (id, name, created_at, updated_at, status, media_file, media_type, source,"
                    " params, n_ticks, duration_s) VALUES (?, ?, ?, ?, 'new', ?, ?, ?, ?, ?, ?)",
                    (pid, name, stamp, stamp, media_file, media_type, json.dumps(source), json.dumps(params),
                     int(n_ticks), float(duration_s)))
        except BaseException:
            shutil.rmtree(pdir, ignore_errors=True)
            raise
        return self.get_project(pid)

    def get_project(self, pid: str) -> dict:
        row = self._one("SELECT * FROM projects WHERE id=?", (check_id(pid),))
        if row is None:
            raise NotFound(f"no project with id {pid!r}")
        return self._project_dict(row)

    def list_projects(self) -> list[dict]:
        return [self._project_dict(r) for r in self._all("SELECT * FROM projects ORDER BY created_at DESC, id")]

    def last_worked_on(self) -> str | None:
        """The project with a timeline changed or viewed last (its view is saved as it is worked on)."""
        rows = self._all("SELECT id FROM projects WHERE has_timeline ORDER BY updated_at DESC LIMIT 1")
        return rows[0]["id"] if rows else None

    def _project_dict(self, row: sqlite3.Row) -> dict:
        d = dict(row)
        for key in ("source", "params", "view"):
            d[key] = json.loads(d[key])
        d["has_timeline"] = bool(d["has_timeline"])
        d["job"] = self.get_job(d["job_id"]) if d["job_id"] else None
        return d

    def update_project(self, pid: str, *, name: str | None = None, view: dict | None = None) -> dict:
        with self._tx() as db:
            self._require(db, pid)
            if name is not None:
                db.execute("UPDATE projects SET name=? WHERE id=?", (name, pid))
            if view is not None:
                db.execute("UPDATE projects SET view=? WHERE id=?", (json.dumps(view), pid))
            db.execute("UPDATE projects SET updated_at=? WHERE id=?", (now_iso(), pid))
        return self.get_project(pid)

    def set_params(self, pid: str, params: dict) -> None:
        with self._tx() as db:
            self._require(db, pid)
            db.execute("UPDATE projects SET params=?, updated_at=? WHERE id=?", (json.dumps(params), now_iso(), pid))

    def delete_project(self, pid: str) -> None:
        """Remove the project's rows and folder (its job must have been cancelled by the caller)."""
        with self._tx() as db:
            self._require(db, pid)
            db.execute("DELETE FROM edits WHERE project_id=?", (pid,))
            db.execute("DELETE FROM jobs WHERE project_id=?", (pid,))
            db.execute("DELETE FROM projects WHERE id=?", (pid,))
        shutil.rmtree(self.project_dir(pid), ignore_errors=True)

    def duplicate_project(self, pid: str, *, name: str) -> dict:
        """A new project with the same media (hard link when possible), caches, params, edits, view."""
        self.get_project(pid)
        new = new_id()
        sdir, ndir = self.project_dir(pid), self.projects_dir / new
        ndir.mkdir()
        try:
            for p in sdir.iterdir():
                if p.is_dir() and p.name == "imports":
                    shutil.copytree(p, ndir / p.name, copy_function=_link_or_copy)
                elif p.is_file() and not p.name.endswith(".part"):
                    _link_or_copy(p, ndir / p.name)
            stamp = now_iso()
            with self._tx() as db:
                row = self._require(db, pid)
                has_tl = (ndir / GENERATED).is_file()
                status = row["status"] if row["status"] != "running" else ("ready" if has_tl else "new")
                db.execute(
                    "INSERT INTO projects (id, name, created_at, updated_at, status, media_file, media_type, source,"
                    " params, view, revision, cursor, n_ticks, duration_s, has_timeline)"
                    " VALUES (?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?)",
                    (new, name, stamp, stamp, status, row["media_file"], row["media_type"], row["source"],
                     row["params"], row["view"], row["revision"], row["cursor"], row["n_ticks"], row["duration_s"],
                     int(has_tl)))
                db.execute("INSERT INTO edits (project_id, seq, op, created_at) "
                           "SELECT ?, seq, op, created_at FROM edits WHERE project_id=?", (new, pid))
        except BaseException:
            shutil.rmtree(ndir, ignore_errors=True)
            raise
        return self.get_project(new)

    @staticmethod
    def _require(db: sqlite3.Connection, pid: str) -> sqlite3.Row:
        row = db.execute("SELECT * FROM projects WHERE id=?", (check_id(pid),)).fetchone()
        if row is None:
            raise NotFound(f"no project with id {pid!r}")
        return row

    # ---------------------------------------------------------------------- jobs
    def create_job(self, pid: str, params: dict) -> dict:
        """A queued job for ``pid``; Conflict when one of its jobs is still queued or running."""
        jid = new_id()
        with self._tx() as db:
            self._require(db, pid)
            busy = db.execute(f"SELECT id FROM jobs WHERE project_id=? AND status IN {ACTIVE_JOB_STATES}",
                              (pid,)).fetchone()
            if busy is not None:
                raise Conflict(f"a generation job ({busy['id']}) of this project is already running")
            stamp = now_iso()
            db.execute("INSERT INTO jobs (id, project_id, status, params, created_at) VALUES (?, ?, 'queued', ?, ?)",
                       (jid, pid, json.dumps(params), stamp))
            db.execute("UPDATE projects SET status='running', job_id=?, updated_at=? WHERE id=?", (jid, stamp, pid))
        self.job_work_dir(jid).mkdir()
        return self.get_job(jid)

    def get_job(self, job_id: str) -> dict:
        row = self._one("SELECT * FROM jobs WHERE id=?", (check_id(job_id, "job"),))
        if row is None:
            raise NotFound(f"no job with id {job_id!r}")
        d = dict(row)
        d["params"] = json.loads(d["params"])
        return d

    def job_started(self, job_id: str, started_at: str) -> None:
        with self._tx() as db:
            db.execute("UPDATE jobs SET status='running', started_at=? WHERE id=? AND status='queued'",
                       (started_at, job_id))

    def job_progress(self, job_id: str, progress: float, stage: str) -> None:
        with self._tx() as db:
            db.execute("UPDATE jobs SET progress=?, stage=? WHERE id=? AND status IN ('queued', 'running')",
                       (float(progress), stage, job_id))

    def finish_job(self, job_id: str, status: str, *, error: str | None = None, started_at: str | None = None,
                   params: dict | None = None, keep_analysis: bool = False, op: dict | None = None) -> dict | None:
        """Record a job's end. ``done``: its work folder's analysis.npz and generated.npz replace the
        project's (``keep_analysis``: the replaced analysis is kept as the previous one), ``op`` (a
        regeneration's ``params`` op) is appended at the cursor, and the revision increases.
        ``params`` (what the timeline on show was derived with) are stored. A project whose job did
        not finish but that has a timeline stays ``ready`` (its ``job`` says what happened).
        Returns the job, or None when its project was deleted meanwhile. The work folder is
        removed in every case."""
        work = self.job_work_dir(job_id)
        try:
            with self._tx() as db:
                row = db.execute("SELECT project_id FROM jobs WHERE id=?", (job_id,)).fetchone()
                if row is None:
                    return None
                pid = row["project_id"]
                stamp = now_iso()
                progress_sql = ", progress=1" if status == "done" else ""
                db.execute(f"UPDATE jobs SET status=?, error=?, finished_at=?, started_at=COALESCE(started_at, ?)"
                           f"{progress_sql} WHERE id=?", (status, error, stamp, started_at, job_id))
                project_status = {"done": "ready", "failed": "failed", "cancelled": "cancelled"}[status]
                if status == "done":
                    pdir = self.project_dir(pid)
                    if keep_analysis and self.analysis_path(pid).is_file():
                        os.replace(self.analysis_path(pid), self.previous_analysis_path(pid))
                    for name in ("analysis.npz", GENERATED):
                        os.replace(work / name, pdir / name)
                    db.execute("UPDATE projects SET revision=revision+1, has_timeline=1 WHERE id=?", (pid,))
                    if op is not None:
                        self._insert_op(db, pid, db.execute("SELECT cursor FROM projects WHERE id=?",
                                                            (pid,)).fetchone()[0], op)
                elif db.execute("SELECT has_timeline FROM projects WHERE id=?", (pid,)).fetchone()[0]:
                    project_status = "ready"  # the previous timeline stays; the job keeps its own status
                if params is not None:
                    db.execute("UPDATE projects SET params=? WHERE id=? AND job_id=?", (json.dumps(params), pid, job_id))
                db.execute("UPDATE projects SET status=?, updated_at=? WHERE id=? AND job_id=?",
                           (project_status, stamp, pid, job_id))
        finally:
            shutil.rmtree(work, ignore_errors=True)
        return self.get_job(job_id)

    def active_jobs(self) -> list[dict]:
        return [self.get_job(r["id"]) for r in
                self._all(f"SELECT id FROM jobs WHERE status IN {ACTIVE_JOB_STATES} ORDER BY created_at")]

    # ------------------------------------------------------------ generated data
    def rederived(self, pid: str, *, params: dict) -> int:
        """Record a re-derive of ``pid``'s generated layer with ``params`` (its file is written after,
        :meth:`place_generated`): store the parameters and bump the revision; returns the new one."""
        with self._tx() as db:
            self._require(db, pid)
            db.execute("UPDATE projects SET revision=revision+1, has_timeline=1, params=?, updated_at=?,"
                       " status=CASE WHEN status='running' THEN status ELSE 'ready' END WHERE id=?",
                       (json.dumps(params), now_iso(), pid))
            return int(db.execute("SELECT revision FROM projects WHERE id=?", (pid,)).fetchone()[0])

    def place_generated(self, pid: str, write_to: Path) -> tuple:
        """Move a freshly written ``generated.npz`` (``write_to``, on the data folder's file system) into
        place; returns the new file's identity (inode, mtime, size), for caches keyed by it.
        NotFound when the project is gone."""
        with self._tx() as db:
            self._require(db, pid)
            path = self.generated_path(pid)
            os.replace(write_to, path)
            return file_key(path)

    def edits(self, pid: str) -> dict:
        """``{revision, cursor, ops}``: ops[:cursor] are applied, ops[cursor:] can be redone."""
        with self._lock:
            row = self._require(self._db, pid)
            ops = [json.loads(r["op"]) for r in self._db.execute(
                "SELECT op FROM edits WHERE project_id=? ORDER BY seq", (pid,))]
        return {"revision": row["revision"], "cursor": row["cursor"], "ops": ops}

    def append_edit(self, pid: str, base_revision: int | None, op: dict) -> dict:
        """Append ``op`` at the cursor (dropping the redo tail); Conflict when ``base_revision`` is stale
        (None: on top of the current revision)."""
        with self._tx() as db:
            row = self._require(db, pid) if base_revision is None else self._check_revision(db, pid, base_revision)
            return self._insert_op(db, pid, row["cursor"], op)

    def _insert_op(self, db: sqlite3.Connection, pid: str, cursor: int, op: dict) -> dict:
        db.execute("DELETE FROM edits WHERE project_id=? AND seq>=?", (pid, cursor))
        db.execute("INSERT INTO edits (project_id, seq, op, created_at) VALUES (?, ?, ?, ?)",
                   (pid, cursor, json.dumps(op), now_iso()))
        return self._move_cursor(db, pid, cursor + 1)

    def undo(self, pid: str, base_revision: int) -> dict:
        with self._tx() as db:
            row = self._check_revision(db, pid, base_revision)
            if row["cursor"] == 0:
                raise Conflict("nothing to undo")
            return self._move_cursor(db, pid, row["cursor"] - 1)

    def redo(self, pid: str, base_revision: int) -> dict:
        with self._tx() as db:
            row = self._check_revision(db, pid, base_revision)
            count = db.execute("SELECT COUNT(*) FROM edits WHERE project_id=?", (pid,)).fetchone()[0]
            if row["cursor"] >= count:
                raise Conflict("nothing to redo")
            return self._move_cursor(db, pid, row["cursor"] + 1)

    def _check_revision(self, db: sqlite3.Connection, pid: str, base_revision: int) -> sqlite3.Row:
        row = self._require(db, pid)
        if int(base_revision) != row["revision"]:
            raise Conflict(f"the timeline changed meanwhile (revision {row['revision']}, the request was based "
                           f"on {base_revision}); reload and try again")
        return row

    @staticmethod
    def _move_cursor(db: sqlite3.Connection, pid: str, cursor: int) -> dict:
        db.execute("UPDATE projects SET cursor=?, revision=revision+1, updated_at=? WHERE id=?",
                   (cursor, now_iso(), pid))
        row = db.execute("SELECT revision, cursor FROM projects WHERE id=?", (pid,)).fetchone()
        return {"revision": row["revision"], "cursor": row["cursor"]}

    def get_setting(self, key: str) -> dict | None:
        """A service-wide settings document (JSON object), or None when never stored."""
        row = self._one("SELECT value FROM settings WHERE key=?", (key,))
        return json.loads(row["value"]) if row is not None else None

    def put_setting(self, key: str, value: dict) -> None:
        with self._tx() as db:
            db.execute("INSERT INTO settings (key, value, updated_at) VALUES (?, ?, ?) ON CONFLICT(key) DO UPDATE"
                       " SET value=excluded.value, updated_at=excluded.updated_at", (key, json.dumps(value), now_iso()))

    def revision(self, pid: str) -> int:
        """The project's current revision (NotFound when it does not exist)."""
        row = self._one("SELECT revision FROM projects WHERE id=?", (check_id(pid),))
        if row is None:
            raise NotFound(f"no project with id {pid!r}")
        return int(row["revision"])

    # ------------------------------------------------------------------ snapshot
    def snapshot(self, pid: str) -> tuple[int, list[dict], dict]:
        """(revision, applied ops, project) read together, for composing the timeline."""
        with self._lock:
            project = self.get_project(pid)
            ops = [json.loads(r["op"]) for r in self._db.execute(
                "SELECT op FROM edits WHERE project_id=? AND seq<? ORDER BY seq", (pid, project["cursor"]))]
        return project["revision"], ops, project


def _link_or_copy(src, dst) -> None:
    """Hard link (files here are only ever replaced, never rewritten in place), else copy."""
    try:
        os.link(src, dst)
    except OSError:
        shutil.copy2(src, dst)
