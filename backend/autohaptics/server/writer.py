"""Writing re-derived generated layers after the answer: a threshold commit on a feature film derives
in milliseconds, but its ``generated.npz`` takes far longer to write, so the composer keeps the new
layer in memory and this writer stores it in the background (the latest one per project wins),
``settle_s`` after the commit: the editor's request for the new timeline, right after it, does not
share the CPU with the write, and a quick run of commits is written once.

Anything that reads or replaces a project's files directly (a finishing job, a duplicate) first
calls :meth:`LayerWriter.flush`; the server's shutdown calls :meth:`LayerWriter.close`.
"""

from __future__ import annotations

import logging
import threading
import time
from collections.abc import Callable

from autohaptics.server.store import NotFound, Store, new_id
from autohaptics.timeline import Timeline
from autohaptics.timeline.npz import save_npz

log = logging.getLogger("autohaptics.server.writer")


class LayerWriter:
    """One daemon thread writing the pending generated layers, one project at a time.

    ``written(pid, revision, key, timeline)`` is called after each write with the file's identity
    (inode, mtime, size), so caches keyed by it can keep the timeline they already hold."""

    def __init__(self, store: Store, written: Callable[[str, int, tuple, Timeline], None], *, settle_s: float = 1.0):
        self.store = store
        self._written = written
        self.settle_s = float(settle_s)
        self._cond = threading.Condition()
        self._pending: dict[str, tuple[int, Timeline, float]] = {}  # revision, layer, when due (monotonic)
        self._urgent = 0  # flushes waiting: what is pending is due now
        self._busy: str | None = None
        self._closed = False
        self._thread = threading.Thread(target=self._loop, name="layer-writer", daemon=True)
        self._thread.start()

    def put(self, pid: str, revision: int, tl: Timeline) -> None:
        """Write ``tl`` as ``pid``'s generated layer soon (replacing a pending older one)."""
        with self._cond:
            self._pending[pid] = (revision, tl, time.monotonic() + self.settle_s)
            self._cond.notify_all()

    def pending(self, pid: str) -> Timeline | None:
        """The layer waiting to be written for ``pid``, or None."""
        with self._cond:
            hit = self._pending.get(pid)
            return None if hit is None else hit[1]

    def flush(self, pid: str | None = None, *, timeout: float = 120.0) -> None:
        """Wait until ``pid``'s (or every project's) pending layer is on disk."""
        with self._cond:
            self._urgent += 1
            self._cond.notify_all()
            try:
                if pid is None:
                    self._cond.wait_for(lambda: not self._pending and self._busy is None, timeout=timeout)
                else:
                    self._cond.wait_for(lambda: pid not in self._pending and self._busy != pid, timeout=timeout)
            finally:
                self._urgent -= 1

    def close(self) -> None:
        """Write what is pending, then stop the thread."""
        self.flush()
        with self._cond:
            self._closed = True
            self._cond.notify_all()
        self._thread.join(timeout=10)

    def _loop(self) -> None:
        while True:
            with self._cond:
                while True:
                    if not self._pending:
                        if self._closed:
                            return
                        self._cond.wait()
                        continue
                    pid = min(self._pending, key=lambda p: self._pending[p][2])
                    wait = self._pending[pid][2] - time.monotonic()
                    if wait <= 0 or self._urgent or self._closed:
                        break
                    self._cond.wait(wait)
                revision, tl, _ = self._pending[pid]
                self._busy = pid
            try:
                self._write(pid, revision, tl)
            except Exception:
                log.exception("writing the generated layer of project %s", pid)
            finally:
                with self._cond:
                    if self._pending.get(pid, (None, None, None))[1] is tl:
                        del self._pending[pid]
                    self._busy = None
                    self._cond.notify_all()

    def _write(self, pid: str, revision: int, tl: Timeline) -> None:
        tmp = self.store.work_dir / f"derive-{new_id()}.npz"
        try:
            save_npz(tl, tmp)
            key = self.store.place_generated(pid, tmp)
        except NotFound:  # the project was deleted meanwhile
            return
        finally:
            tmp.unlink(missing_ok=True)
        self._written(pid, revision, key, tl)
