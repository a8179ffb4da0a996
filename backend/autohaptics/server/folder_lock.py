"""One server per data folder: an exclusive ``flock`` on ``<data>/server.lock``, taken before the
start-up recovery touches anything. The lock is re-entrant within a process (the CLI takes it
before binding, the application's lifespan again) and the OS drops it when the process dies,
so a ``kill -9`` leaves no stale lock."""

from __future__ import annotations

import fcntl
import os
import threading
from pathlib import Path

from autohaptics.errors import ParameterError
from autohaptics.outputs import prepare_folder

LOCK_FILE = "server.lock"

_held: dict[Path, list] = {}  # resolved folder -> [fd, count]
_guard = threading.Lock()


class FolderBusy(ParameterError):
    """Another process holds the data folder."""


def acquire(data_dir: Path) -> Path:
    """Hold the folder's lock (once more, when this process holds it already).

    Raises FolderBusy naming the folder and the PID that holds it."""
    folder = prepare_folder(data_dir, label="data folder").resolve()
    with _guard:
        if folder in _held:
            _held[folder][1] += 1
            return folder
        fd = os.open(folder / LOCK_FILE, os.O_RDWR | os.O_CREAT, 0o644)
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            holder = os.pread(fd, 32, 0).decode(errors="replace").strip() or "unknown"
            os.close(fd)
            raise FolderBusy(f"data folder {data_dir} is in use by another autohaptics server (PID {holder})") \
                from None
        os.ftruncate(fd, 0)
        os.pwrite(fd, f"{os.getpid()}\n".encode(), 0)
        _held[folder] = [fd, 1]
        return folder


def release(folder: Path) -> None:
    """Give back one hold of :func:`acquire`; the last one unlocks."""
    with _guard:
        entry = _held.get(folder)
        if entry is None:
            return
        entry[1] -= 1
        if entry[1] == 0:
            del _held[folder]
            os.close(entry[0])  # closing the descriptor drops the flock
