"""The data folder's database: its schema, ids, the errors a store raises and a file's identity. Ids are 32 lower-case
hex digits chosen here; no client-supplied string ever becomes a path."""

from __future__ import annotations

import re
import uuid
from datetime import datetime, timezone
from pathlib import Path

from autohaptics.errors import AutohapticsError

DB_NAME = "autohaptics.sqlite3"
GENERATED = "generated.npz"
ACTIVE_JOB_STATES = ("queued", "running")
ID_PATTERN = re.compile(r"^[0-9a-f]{32}$")

SCHEMA = """
CREATE TABLE IF NOT EXISTS projects (
    id TEXT PRIMARY KEY,
    name TEXT NOT NULL,
    created_at TEXT NOT NULL,
    updated_at TEXT NOT NULL,
    status TEXT NOT NULL,
    media_file TEXT NOT NULL,
    media_type TEXT NOT NULL,
    source TEXT NOT NULL,
    params TEXT NOT NULL,
    view TEXT NOT NULL DEFAULT '{}',
    revision INTEGER NOT NULL DEFAULT 0,
    cursor INTEGER NOT NULL DEFAULT 0,
    n_ticks INTEGER NOT NULL,
    duration_s REAL NOT NULL,
    has_timeline INTEGER NOT NULL DEFAULT 0,
    job_id TEXT
);
CREATE TABLE IF NOT EXISTS jobs (
    id TEXT PRIMARY KEY,
    project_id TEXT NOT NULL,
    status TEXT NOT NULL,
    progress REAL NOT NULL DEFAULT 0,
    stage TEXT NOT NULL DEFAULT '',
    error TEXT,
    params TEXT NOT NULL,
    created_at TEXT NOT NULL,
    started_at TEXT,
    finished_at TEXT
);
CREATE INDEX IF NOT EXISTS jobs_project ON jobs (project_id);
CREATE TABLE IF NOT EXISTS edits (
    project_id TEXT NOT NULL,
    seq INTEGER NOT NULL,
    op TEXT NOT NULL,
    created_at TEXT NOT NULL,
    PRIMARY KEY (project_id, seq)
);
CREATE TABLE IF NOT EXISTS settings (
    key TEXT PRIMARY KEY,
    value TEXT NOT NULL,
    updated_at TEXT NOT NULL
);
CREATE TABLE IF NOT EXISTS styles (
    id TEXT PRIMARY KEY,
    name TEXT NOT NULL,
    created_at TEXT NOT NULL,
    films TEXT NOT NULL,
    report TEXT NOT NULL
);
"""


class NotFound(AutohapticsError):
    """No project or job with that id."""


class Conflict(AutohapticsError):
    """The request conflicts with the current state (stale revision, a job already running)."""


def now_iso() -> str:
    """The current UTC time, ISO 8601 with milliseconds and a Z."""
    return datetime.now(timezone.utc).isoformat(timespec="milliseconds").replace("+00:00", "Z")


def new_id() -> str:
    """A fresh random id."""
    return uuid.uuid4().hex


def check_id(value: str, what: str = "project") -> str:
    """``value`` when it is a well-formed id, else NotFound (ids never reach the file system unchecked)."""
    if not isinstance(value, str) or not ID_PATTERN.match(value):
        raise NotFound(f"no {what} with id {value!r}")
    return value


def file_key(path: Path) -> tuple | None:
    """A file's identity (inode, mtime in ns, size), what the caches of its contents are keyed by;
    None when it does not exist."""
    try:
        st = path.stat()
    except FileNotFoundError:
        return None
    return (st.st_ino, st.st_mtime_ns, st.st_size)
