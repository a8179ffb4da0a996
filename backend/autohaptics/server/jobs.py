"""Generation jobs: one process pool, progress through a Manager queue, cancellation by a Manager Event.

Life of a job:

1. :meth:`JobRunner.submit` records it (``queued``) and creates ``work/<job id>/``; the job waits
   in the runner's own queue until fewer than ``Settings.jobs`` jobs are in the pool, then
   :func:`run_job` is submitted to it (one ``ProcessPoolExecutor`` with that many workers, spawn
   or forkserver context). Waiting here rather than in the pool makes cancelling a queued job
   immediate.
2. In the worker, :func:`run_job` sends ``("started", id, time)`` then ``("progress", id, stage,
   fraction)`` messages on the Manager queue, runs :func:`pipeline.analyse` with the job's Manager
   Event as the cancel token, derives the timeline, and writes ``analysis.npz`` and
   ``generated.npz`` into the work folder (never into the project folder).
3. A reader thread turns queue messages into the job's live state (``running``, progress, stage),
   stores them and forwards them to SSE subscribers.
4. When the future completes, a finisher thread moves the outputs into the project
   (:meth:`Store.finish_job`) and publishes the terminal event: ``done``, ``failed`` (the error's
   message) or ``cancelled`` (the pipeline raised CancelledError, or the job was cancelled while
   queued; a job whose cancel was requested never replaces the timeline).

If the parameters of a project changed while its job ran and they need no other analysis, the
finisher derives the timeline again with the current ones. Deleting a project cancels its job;
the job's outputs are then dropped. On shutdown running jobs are cancelled and recorded as
interrupted by a server restart (as :meth:`Store.recover` does after a crash), so they can be
re-run.
"""

from __future__ import annotations

import asyncio
import logging
import multiprocessing
import os
import queue as queue_mod
import signal
import threading
from collections import deque
from concurrent.futures import Future, ProcessPoolExecutor
from concurrent.futures.process import BrokenProcessPool
from multiprocessing.managers import SyncManager
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from autohaptics.errors import AutohapticsError, CancelledError
from autohaptics.progress import check_cancel
from autohaptics.workers import start_worker
from autohaptics.server.store import GENERATED, INTERRUPTED, Conflict, NotFound, Store, now_iso

log = logging.getLogger("autohaptics.server.jobs")

TERMINAL = ("done", "failed", "cancelled")
_PROGRESS_STEP = 0.01  # the worker reports at most every 1 % (or on a stage change)


# ------------------------------------------------------------------- worker side
class _Reporter:
    """The pipeline's progress callback inside the worker: throttled messages on the Manager queue."""

    def __init__(self, events, job_id: str):
        self.events = events
        self.job_id = job_id
        self.stage = None
        self.fraction = -1.0

    def __call__(self, stage: str, fraction: float) -> None:
        fraction = min(1.0, max(0.0, float(fraction)))
        if stage == self.stage and fraction < 1.0 and fraction - self.fraction < _PROGRESS_STEP:
            return
        self.stage, self.fraction = stage, fraction
        _send(self.events, ("progress", self.job_id, stage, fraction))


def _send(events, message: tuple) -> None:
    try:
        events.put(message)
    except Exception:  # the server is shutting down: progress no longer matters
        pass


def exit_with_parent(parent_pid: int) -> None:
    """Initializer of the pool workers and the Manager: exit once the server process is gone (killed
    hard), instead of lingering as orphans; ignore SIGINT and SIGTERM (Ctrl+C in a terminal and
    process managers signal the whole process group), so the server's own shutdown cancels and
    records the running jobs as interrupted."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    signal.signal(signal.SIGTERM, signal.SIG_IGN)
    start_worker(parent_pid)


def warm_up() -> None:
    """Import the pipeline in a fresh worker, so the first job does not wait for it."""
    import autohaptics.pipeline  # noqa: F401


def run_job(spec: dict, events, cancel) -> dict:
    """Worker entry point: analyse the media, derive the timeline, write both into ``spec["work_dir"]``.

    spec : {job_id, media_path, work_dir, params (stored parameters), name (display name)}.
    Raises CancelledError when ``cancel`` is set, MediaError / ParameterError for unusable input.
    """
    from autohaptics import pipeline
    from autohaptics.heap import release_between_passes
    from autohaptics.server.generated import save_npz
    from autohaptics.server.timelines import derive_timeline, params_from_doc

    started = now_iso()
    _send(events, ("started", spec["job_id"], started))
    params, _ = params_from_doc(spec["params"])
    analysis = pipeline.analyse(spec["media_path"], params, progress=_Reporter(events, spec["job_id"]),
                                cancel=cancel, between_passes=release_between_passes)
    check_cancel(cancel)
    work = Path(spec["work_dir"])
    if not work.is_dir():  # the project was deleted meanwhile
        raise CancelledError("the project was deleted")
    analysis.save(work / "analysis.npz")
    tl = derive_timeline(analysis, spec["params"], name=spec["name"])
    save_npz(tl, work / GENERATED)
    return {"started_at": started, "n_ticks": tl.n_ticks}


# ------------------------------------------------------------------- server side
@dataclass
class _Live:
    job_id: str
    project_id: str
    params: dict
    name: str
    media_path: str
    cancel: Any  # Manager Event proxy
    future: Future | None = None
    status: str = "queued"
    progress: float = 0.0
    stage: str = ""
    started_at: str | None = None
    cancel_requested: bool = False
    subscribers: list = field(default_factory=list)  # [(loop, asyncio.Queue)]


@dataclass
class Subscription:
    """What an SSE stream reads: events so far, then a queue of later ones (None when finished)."""

    initial: list[tuple[str, dict]]
    queue: asyncio.Queue | None
    close: Any


class JobRunner:
    """Owns the process pool, the Manager, and the live state of queued and running jobs."""

    def __init__(self, store: Store, *, workers: int = 1, mp_context: str = "spawn", timelines=None):
        self.store = store
        self.workers = int(workers)
        self.ctx = multiprocessing.get_context(mp_context)
        self.timelines = timelines
        self._lock = threading.RLock()
        self._live: dict[str, _Live] = {}
        self._pending: deque[tuple[_Live, dict]] = deque()  # waiting for a free worker
        self._in_pool = 0  # jobs handed to the pool and not finished
        self._manager = None
        self._events = None
        self._pool: ProcessPoolExecutor | None = None
        self._finished: queue_mod.Queue = queue_mod.Queue()
        self._threads: list[threading.Thread] = []
        self._params_locks: dict[str, threading.Lock] = {}
        self._stopping = False

    # ---------------------------------------------------------------- lifecycle
    def start(self) -> None:
        self._manager = SyncManager(ctx=self.ctx)
        self._manager.start(exit_with_parent, (os.getpid(),))
        self._events = self._manager.Queue()
        self._pool = self._new_pool()
        self._stopping = False
        for target, name in ((self._read_events, "job-events"), (self._finish_loop, "job-finisher")):
            t = threading.Thread(target=target, name=name, daemon=True)
            t.start()
            self._threads.append(t)

    def _new_pool(self) -> ProcessPoolExecutor:
        pool = ProcessPoolExecutor(max_workers=self.workers, mp_context=self.ctx,
                                   initializer=exit_with_parent, initargs=(os.getpid(),))
        pool.submit(warm_up)
        return pool

    def stop(self) -> None:
        """Cancel every job, stop the pool, the threads and the Manager; jobs that did not complete
        are recorded as interrupted by a server restart (re-runnable)."""
        with self._lock:
            self._stopping = True
            live = list(self._live.values())
            self._pending.clear()
        for job in live:
            job.cancel_requested = True
            if job.future is not None:
                job.future.cancel()
            try:
                job.cancel.set()
            except Exception:
                pass
        if self._pool is not None:
            self._pool.shutdown(wait=True, cancel_futures=True)
        self._finished.put(None)
        try:
            self._events.put(None)
        except Exception:
            pass
        for t in self._threads:
            t.join(timeout=60)
        self._threads.clear()
        with self._lock:
            left = list(self._live.values())
            self._live.clear()
        for job in left:
            self._publish_final(job, self.store.finish_job(job.job_id, "failed", error=INTERRUPTED,
                                                           started_at=job.started_at))
        if self._manager is not None:
            self._manager.shutdown()
        self._pool = None

    # ------------------------------------------------------------------ actions
    def submit(self, project: dict, params: dict) -> dict:
        """Queue a generation job for ``project`` with stored parameters ``params``; Conflict when one runs."""
        if self._pool is None or self._stopping:
            raise Conflict("the job runner is not running")
        cancel = self._manager.Event()
        job = self.store.create_job(project["id"], params)
        media_path = str(self.store.media_path(project))
        live = _Live(job_id=job["id"], project_id=project["id"], params=params, name=project["name"],
                     media_path=media_path, cancel=cancel)
        spec = {"job_id": job["id"], "media_path": media_path, "work_dir": str(self.store.job_work_dir(job["id"])),
                "params": params, "name": project["name"]}
        with self._lock:
            self._live[job["id"]] = live
            self._pending.append((live, spec))
            self._dispatch()
        return job

    def _dispatch(self) -> None:
        """Hand waiting jobs to the pool while fewer than ``workers`` are in it (call with the lock held).

        Jobs wait here rather than in the pool's own queue, so a queued job is cancelled at once."""
        while self._pending and self._in_pool < self.workers and not self._stopping:
            live, spec = self._pending.popleft()
            try:
                live.future = self._pool.submit(run_job, spec, self._events, live.cancel)
            except (BrokenProcessPool, RuntimeError):  # a worker died: the pool is unusable, replace it
                self._pool.shutdown(wait=False, cancel_futures=True)
                self._pool = self._new_pool()
                live.future = self._pool.submit(run_job, spec, self._events, live.cancel)
            self._in_pool += 1
            live.future.add_done_callback(lambda f, jid=live.job_id: self._finished.put((jid, f)))

    def cancel(self, job_id: str) -> dict:
        """Ask a job to stop (202); Conflict when it has already finished."""
        with self._lock:
            live = self._live.get(job_id)
        if live is None:
            job = self.store.get_job(job_id)
            raise Conflict(f"job {job_id} has already finished ({job['status']})")
        live.cancel_requested = True
        live.cancel.set()
        with self._lock:
            waiting = [item for item in self._pending if item[0] is live]
            for item in waiting:
                self._pending.remove(item)
        if waiting:
            self._finished.put((job_id, None))  # never reached the pool: ends now
        return self.job(job_id)

    def cancel_project(self, project_id: str) -> None:
        with self._lock:
            ids = [j.job_id for j in self._live.values() if j.project_id == project_id]
        for jid in ids:
            try:
                self.cancel(jid)
            except (Conflict, NotFound):
                pass

    def job(self, job_id: str) -> dict:
        """The job as stored, with the live progress of a running one."""
        with self._lock:
            live = self._live.get(job_id)
            if live is not None:
                return self._live_dict(live)
        return self.store.get_job(job_id)

    def active_job(self, project_id: str) -> dict | None:
        with self._lock:
            for live in self._live.values():
                if live.project_id == project_id:
                    return self._live_dict(live)
        return None

    def _live_dict(self, live: _Live) -> dict:
        try:
            job = self.store.get_job(live.job_id)
        except NotFound:  # the project (and its job rows) was deleted
            job = {"id": live.job_id, "project_id": live.project_id, "params": live.params, "error": None,
                   "created_at": None, "finished_at": None}
        job.update(status=live.status, progress=live.progress, stage=live.stage,
                   started_at=live.started_at or job.get("started_at"))
        return job

    # ---------------------------------------------------------------- streaming
    def subscribe(self, job_id: str) -> Subscription:
        """Register an SSE listener on the running event loop; NotFound for an unknown job."""
        loop = asyncio.get_running_loop()
        with self._lock:
            live = self._live.get(job_id)
            if live is None:
                job = self.store.get_job(job_id)
                events = [("progress", {"progress": job["progress"], "stage": job["stage"]})]
                if job["status"] in TERMINAL:
                    events.append((job["status"], job))
                return Subscription(initial=events, queue=None, close=lambda: None)
            q: asyncio.Queue = asyncio.Queue()
            entry = (loop, q)
            live.subscribers.append(entry)
            initial = [("progress", {"progress": live.progress, "stage": live.stage})]

        def close() -> None:
            with self._lock:
                if entry in live.subscribers:
                    live.subscribers.remove(entry)

        return Subscription(initial=initial, queue=q, close=close)

    def _publish(self, live: _Live, name: str, data: dict) -> None:
        for loop, q in list(live.subscribers):
            try:
                loop.call_soon_threadsafe(q.put_nowait, (name, data))
            except RuntimeError:  # that client's event loop is gone
                live.subscribers.remove((loop, q))

    def _publish_final(self, live: _Live, job: dict | None) -> None:
        if job is None:
            job = {"id": live.job_id, "project_id": live.project_id, "status": "cancelled",
                   "progress": live.progress, "stage": live.stage, "error": None, "params": live.params,
                   "created_at": None, "started_at": live.started_at, "finished_at": now_iso()}
        with self._lock:
            self._publish(live, job["status"], job)
            live.subscribers.clear()

    # ------------------------------------------------------------------ threads
    def _read_events(self) -> None:
        while True:
            try:
                msg = self._events.get()
            except (EOFError, OSError, BrokenPipeError):
                return
            if msg is None:
                return
            try:
                self._on_event(msg)
            except Exception:
                log.exception("job event %r", msg)

    def _on_event(self, msg: tuple) -> None:
        kind, job_id = msg[0], msg[1]
        with self._lock:
            live = self._live.get(job_id)
            if live is None or live.status in TERMINAL:
                return
            if kind == "started":
                live.status, live.started_at = "running", msg[2]
            elif kind == "progress":
                live.stage, live.progress = msg[2], float(msg[3])
        if kind == "started":
            self.store.job_started(job_id, msg[2])
            return
        self.store.job_progress(job_id, live.progress, live.stage)
        with self._lock:
            self._publish(live, "progress", {"progress": live.progress, "stage": live.stage})

    def _finish_loop(self) -> None:
        while True:
            item = self._finished.get()
            if item is None:
                return
            job_id, future = item
            try:
                self._finish(job_id, future)
            except Exception:
                log.exception("finishing job %s", job_id)

    def _finish(self, job_id: str, future: Future | None) -> None:
        with self._lock:
            live = self._live.get(job_id)
            if future is not None:
                self._in_pool -= 1
                self._dispatch()
        if live is None:
            return
        status, error, result = _outcome(future, live)
        if self._stopping and status != "done":
            return  # stop() records it as interrupted
        # Under the project's parameter lock: a parameter change either lands before the current
        # parameters are read here (and is derived with), or after the job is gone.
        with self.params_lock(live.project_id):
            params = live.params
            if status == "done":
                try:
                    params = self._current_params(live)
                except Exception as exc:  # the outputs are unusable: report, keep the previous timeline
                    status, error = "failed", f"{type(exc).__name__}: {exc}"
            if error:
                error = error.replace(live.media_path, live.name)
            try:
                job = self.store.finish_job(job_id, status, error=error, params=params,
                                            started_at=(result or {}).get("started_at") or live.started_at)
            except Exception as exc:
                log.exception("storing the end of job %s", job_id)
                job = self.store.finish_job(job_id, "failed", error=f"{type(exc).__name__}: {exc}")
            with self._lock:
                live.status = job["status"] if job else "cancelled"
                self._live.pop(job_id, None)
        self._publish_final(live, job)

    def params_lock(self, project_id: str) -> threading.Lock:
        """Held while a project's parameters are changed (PUT params) and while its job finishes,
        so a change made during a job is never lost to the job's own parameters."""
        with self._lock:
            return self._params_locks.setdefault(project_id, threading.Lock())

    def _current_params(self, live: _Live) -> dict:
        """Parameters to derive with at the end of a job: the project's current ones when they changed
        meanwhile and need no other analysis (the timeline is derived again), else the job's."""
        try:
            current = self.store.get_project(live.project_id)["params"]
        except NotFound:
            return live.params
        if current == live.params or self.timelines is None:
            return live.params
        from autohaptics import pipeline
        from autohaptics.server.generated import save_npz
        from autohaptics.server.timelines import derive_timeline, params_from_doc

        work = self.store.job_work_dir(live.job_id)
        analysis = pipeline.Analysis.load(work / "analysis.npz")
        p, _ = params_from_doc(current)
        if not pipeline.reusable(analysis, p):
            return live.params
        save_npz(derive_timeline(analysis, current, name=live.name), work / GENERATED)
        return current


def _outcome(future: Future | None, live: _Live) -> tuple[str, str | None, dict | None]:
    """(status, error, result) of a finished future (None: cancelled before it reached the pool)."""
    if future is None or future.cancelled():
        return "cancelled", None, None
    exc = future.exception()
    if exc is None:
        if live.cancel_requested:  # cancelled after the last check: keep the previous timeline
            return "cancelled", None, None
        return "done", None, future.result()
    if isinstance(exc, CancelledError) or live.cancel_requested:
        return "cancelled", None, None
    if isinstance(exc, BrokenProcessPool):
        return "failed", "the job's worker process died unexpectedly", None
    if isinstance(exc, AutohapticsError):
        return "failed", str(exc), None
    return "failed", f"{type(exc).__name__}: {exc}", None
