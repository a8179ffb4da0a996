"""One pool of worker processes for the pipeline's heavy work, used by the server's jobs and by
``autohaptics batch``.

Workers are spawned (no inherited threads or locks), warmed once (the pipeline imported), exit
with their parent, and leave Ctrl+C to it. Their messages and the cancel events go through a
Manager: a worker killed in the middle of a message cannot leave a lock held, as it could with a
plain multiprocessing queue. A pool whose worker died is replaced (:meth:`WorkerPool.replace`); the
caller decides what to do with the work that was in it.
"""

from __future__ import annotations

import multiprocessing
import os
import queue
from concurrent.futures import Future, ProcessPoolExecutor
from concurrent.futures.process import BrokenProcessPool
from multiprocessing.managers import SyncManager
from typing import Any

from autohaptics.runner.worker import init_worker, warm_up


class WorkerPool:
    """``workers`` processes (``mp_context``: "spawn" or "forkserver") plus a Manager for ``events``
    (the workers' messages) and cancel events. ``ignore_term``: workers ignore SIGTERM too (the
    server stops them itself and records their work as interrupted)."""

    def __init__(self, workers: int, *, mp_context: str = "spawn", ignore_term: bool = False):
        self.workers = int(workers)
        self.ctx = multiprocessing.get_context(mp_context)
        self.ignore_term = ignore_term
        self.events = None
        self._manager: SyncManager | None = None
        self._pool: ProcessPoolExecutor | None = None

    def start(self) -> "WorkerPool":
        self._manager = SyncManager(ctx=self.ctx)
        self._manager.start(init_worker, (os.getpid(), self.ignore_term))
        self.events = self._manager.Queue()
        self._pool = self._new_pool()
        return self

    def _new_pool(self) -> ProcessPoolExecutor:
        pool = ProcessPoolExecutor(max_workers=self.workers, mp_context=self.ctx, initializer=init_worker,
                                   initargs=(os.getpid(), self.ignore_term))
        pool.submit(warm_up)
        return pool

    def cancel_event(self):
        """A new cancel event the workers can read (``is_set()``) and the parent can set."""
        return self._manager.Event()

    def submit(self, fn, *args: Any) -> Future:
        """``fn(*args)`` in a worker; a pool broken by a dead worker is replaced first."""
        try:
            return self._pool.submit(fn, *args)
        except (BrokenProcessPool, RuntimeError):
            self.replace()
            return self._pool.submit(fn, *args)

    def replace(self) -> None:
        """Drop the pool (a worker died: it is unusable) for a fresh one; its futures fail."""
        self._pool.shutdown(wait=False, cancel_futures=True)
        self._pool = self._new_pool()

    def get(self, timeout: float | None = None):
        """The next worker message; None after ``timeout`` s, or once the Manager is gone."""
        try:
            return self.events.get(timeout=timeout)
        except queue.Empty:
            return None
        except (EOFError, OSError, BrokenPipeError):
            return None

    def drain(self) -> list:
        """Every message waiting now."""
        out = []
        while True:
            try:
                out.append(self.events.get_nowait())
            except queue.Empty:
                return out

    def wake(self) -> None:
        """Unblock a reader waiting in :meth:`get` (it receives None)."""
        try:
            self.events.put(None)
        except Exception:
            pass

    def shutdown_workers(self, *, wait: bool = True) -> None:
        """Stop the workers (pending work is cancelled); messages can still be read."""
        if self._pool is not None:
            self._pool.shutdown(wait=wait, cancel_futures=True)
            self._pool = None

    def shutdown(self, *, wait: bool = True) -> None:
        """Stop the workers and the Manager."""
        self.shutdown_workers(wait=wait)
        if self._manager is not None:
            self._manager.shutdown()
            self._manager = None
