"""Generation jobs: one process pool, progress through a Manager queue, cancellation by a Manager Event.

Life of a job:

1. :meth:`JobRunner.submit` records it (``queued``) and creates ``work/<job id>/``; it waits in the
   runner's own queue (so cancelling it is immediate) until fewer than ``Settings.jobs`` jobs are
   in the pool, then :func:`run_job` is submitted to it (one ``ProcessPoolExecutor``, spawn or
   forkserver context).
2. In the worker, :func:`run_job` sends ``("started", id, time)`` then ``("progress", id, stage,
   fraction)`` messages, runs :func:`pipeline.analyse` (or :func:`pipeline.refine`) with the job's
   Manager Event as the cancel token, derives, and writes ``analysis.npz`` and ``generated.npz``
   into the work folder (never into the project folder).
3. A reader thread turns queue messages into the job's live state (``running``, progress, stage),
   stores them and forwards them to SSE subscribers.
4. When the future completes, a finisher thread moves the outputs into the project
   (:meth:`Store.finish_job`) and publishes the terminal event: ``done``, ``failed`` (the error's
   message) or ``cancelled`` (the pipeline raised CancelledError, or the job was cancelled while
   queued; a job whose cancel was requested never replaces the timeline).

Parameters changed while a job ran and needing no other analysis are derived with at its end (and
refined again if they lack saliency). Deleting a project cancels its job. On shutdown running jobs
are cancelled and left queued; the next start (as after a crash) re-queues them with their
project's latest parameters (:meth:`Store.recover`) and runs them again (:meth:`JobRunner.resume`:
a refinement where the cache serves those parameters, else a new analysis).
"""

from __future__ import annotations

import logging
import queue as queue_mod
import threading
from collections import deque
from concurrent.futures import Future
from concurrent.futures.process import BrokenProcessPool
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from autohaptics.errors import AutohapticsError, CancelledError
from autohaptics.progress import check_cancel
from autohaptics.runner import Reporter, WorkerPool, queue_sender
from autohaptics.server.sse import Subscribers, Subscription
from autohaptics.server.store import GENERATED, Conflict, NotFound, Store, now_iso

log = logging.getLogger("autohaptics.server.jobs")

TERMINAL = ("done", "failed", "cancelled")


# ------------------------------------------------------------------- worker side
def run_job(spec: dict, events, cancel) -> dict:
    """Worker entry point: analyse the media, derive the timeline, write both into ``spec["work_dir"]``.

    spec : {job_id, media_path, work_dir, params (stored parameters), name (display name), refine
    (optional: refine the project's cache at ``analysis_path`` instead of analysing again)}.
    Raises CancelledError when ``cancel`` is set, MediaError / ParameterError for unusable input.
    """
    from autohaptics import pipeline
    from autohaptics.params import params_from_doc
    from autohaptics.pipeline.handoff import kept_of
    from autohaptics.runner.heap import release_between_passes
    from autohaptics.server.composer import derive_timeline
    from autohaptics.timeline.npz import save_npz

    reporter = Reporter(queue_sender(events), spec["job_id"])
    started = now_iso()
    reporter.event("started", started)
    params, _ = params_from_doc(spec["params"])
    cached = spec.get("refine") and Path(spec["analysis_path"]).is_file()
    if cached:  # the cache serves these parameters: only the saliency the derive lacks is computed
        analysis = pipeline.Analysis.load(spec["analysis_path"])
        estimate = derive_timeline(analysis, spec["params"], name=spec["name"])
        analysis = pipeline.refine(spec["media_path"], analysis, params, estimate.features["intensity"] > 0,
                                   progress=reporter, cancel=cancel)
    else:
        analysis = pipeline.analyse(spec["media_path"], params, progress=reporter, cancel=cancel,
                                    between_passes=release_between_passes)
    check_cancel(cancel)
    work = Path(spec["work_dir"])
    if not work.is_dir():  # the project was deleted meanwhile
        raise CancelledError("the project was deleted")
    analysis.save(work / "analysis.npz")
    tl = derive_timeline(analysis, spec["params"], name=spec["name"])
    save_npz(tl, work / GENERATED)
    return {"started_at": started, "n_ticks": tl.n_ticks, "needs_analysis": bool(tl.stats.get("needs_analysis")),
            "kept": kept_of(analysis, tl)}  # the server's derives from the file need not compute it again


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
    previous: dict | None = None  # the parameters of the timeline the job would replace (None: none yet)
    record: bool = False  # a regeneration: its parameters, when done, are an undoable ``params`` op
    subscribers: Subscribers = field(default_factory=Subscribers)


class JobRunner:
    """Owns the process pool, the Manager, and the live state of queued and running jobs."""

    def __init__(self, store: Store, *, workers: int = 1, mp_context: str = "spawn", composer=None):
        self.store = store
        self.workers = int(workers)
        self.composer = composer
        self.pool = WorkerPool(self.workers, mp_context=mp_context, ignore_term=True)
        self._lock = threading.RLock()
        self._live: dict[str, _Live] = {}
        self._pending: deque[tuple[_Live, dict]] = deque()  # waiting for a free worker
        self._in_pool = 0  # jobs handed to the pool and not finished
        self._started = False
        self._finished: queue_mod.Queue = queue_mod.Queue()
        self._threads: list[threading.Thread] = []
        self._params_locks: dict[str, threading.Lock] = {}
        self._stopping = False

    # ---------------------------------------------------------------- lifecycle
    def start(self) -> None:
        self.pool.start()
        self._started = True
        self._stopping = False
        for target, name in ((self._read_events, "job-events"), (self._finish_loop, "job-finisher")):
            t = threading.Thread(target=target, name=name, daemon=True)
            t.start()
            self._threads.append(t)

    def stop(self) -> None:
        """Cancel every job, stop the pool, the threads and the Manager; jobs that did not complete
        stay queued in the store, and the next start resumes them."""
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
        if self._started:
            self.pool.shutdown_workers()
        self._finished.put(None)
        self.pool.wake()
        for t in self._threads:
            t.join(timeout=60)
        self._threads.clear()
        with self._lock:
            left = list(self._live.values())
            self._live.clear()
        for job in left:  # stays queued in the store: the next start resumes it (Store.recover)
            job.subscribers.close_all()
        if self._started:
            self.pool.shutdown()
            self._started = False

    # ------------------------------------------------------------------ actions
    def submit(self, project: dict, params: dict, *, refine: bool = False, record: bool = False) -> dict:
        """Queue a generation job for ``project`` with stored parameters ``params``; Conflict when one runs.

        refine : the project's feature cache serves ``params``: compute only the saliency a derive
        lacks (:func:`pipeline.refine`), not the whole analysis.
        record : when done, the change from the timeline's parameters to the job's enters the edit
        history as a ``params`` op (a regeneration; a parameter change records its own)."""
        if not self._started or self._stopping:
            raise Conflict("the job runner is not running")
        job = self.store.create_job(project["id"], params)
        self._queue(project, job, refine=refine, record=record)
        return job

    def resume(self, jobs: list[dict]) -> None:
        """Queue again the jobs a restart interrupted (:meth:`Store.recover`), each with its project's
        current parameters: a refinement where the feature cache serves them, else a new analysis."""
        from autohaptics import pipeline
        from autohaptics.params import params_from_doc

        for job in jobs:
            try:
                project = self.store.get_project(job["project_id"])
                cache = self.store.analysis_path(project["id"])
                refine = cache.is_file() and pipeline.reusable(pipeline.Analysis.load(cache),
                                                               params_from_doc(job["params"])[0])
                self._queue(project, job, refine=refine)
            except Exception as exc:  # that one project's files are unusable: say so, resume the others
                log.exception("resuming job %s", job["id"])
                self.store.finish_job(job["id"], "failed", error=f"could not be resumed: {exc}")

    def _queue(self, project: dict, job: dict, *, refine: bool, record: bool = False) -> None:
        cancel = self.pool.cancel_event()
        params = job["params"]
        media_path = str(self.store.media_path(project))
        live = _Live(job_id=job["id"], project_id=project["id"], params=params, name=project["name"],
                     media_path=media_path, cancel=cancel, record=record,
                     previous=project["params"] if project.get("has_timeline") else None)
        spec = {"job_id": job["id"], "media_path": media_path, "work_dir": str(self.store.job_work_dir(job["id"])),
                "params": params, "name": project["name"], "refine": refine,
                "analysis_path": str(self.store.analysis_path(project["id"]))}
        with self._lock:
            self._live[job["id"]] = live
            self._pending.append((live, spec))
            self._dispatch()

    def _dispatch(self) -> None:
        """Hand waiting jobs to the pool while fewer than ``workers`` are in it (call with the lock held).

        Jobs wait here rather than in the pool's own queue, so a queued job is cancelled at once."""
        while self._pending and self._in_pool < self.workers and not self._stopping:
            live, spec = self._pending.popleft()
            live.future = self.pool.submit(run_job, spec, self.pool.events, live.cancel)
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
        """A progress stream on the running event loop; NotFound for an unknown job."""
        with self._lock:
            live = self._live.get(job_id)
            if live is not None:
                return live.subscribers.subscribe([("progress", {"progress": live.progress, "stage": live.stage})])
        job = self.store.get_job(job_id)
        events = [("progress", {"progress": job["progress"], "stage": job["stage"]})]
        if job["status"] in TERMINAL:
            events.append((job["status"], job))
        return Subscription(initial=events, queue=None, close=lambda: None)

    def _publish_final(self, live: _Live, job: dict | None) -> None:
        if job is None:
            job = {"id": live.job_id, "project_id": live.project_id, "status": "cancelled",
                   "progress": live.progress, "stage": live.stage, "error": None, "params": live.params,
                   "created_at": None, "started_at": live.started_at, "finished_at": now_iso()}
        live.subscribers.publish((job["status"], job))
        live.subscribers.close_all()

    # ------------------------------------------------------------------ threads
    def _read_events(self) -> None:
        while True:
            msg = self.pool.get()
            if msg is None:  # woken by stop(), or the Manager is gone
                return
            try:
                self._on_event(msg)
            except Exception:
                log.exception("job event %r", msg)

    def _on_event(self, msg: tuple) -> None:
        job_id, kind = msg[0], msg[1]
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
        live.subscribers.publish(("progress", {"progress": live.progress, "stage": live.stage}))

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
        more = False
        with self.params_lock(live.project_id):
            params = live.params if status == "done" else live.previous  # a stopped job: back to the timeline's
            if status == "done":
                try:
                    params, more = self._current_params(live, result)
                except Exception as exc:  # the outputs are unusable: report, keep the previous timeline
                    status, error = "failed", f"{type(exc).__name__}: {exc}"
            if error:
                error = error.replace(live.media_path, live.name)
            if self.composer is not None:  # a re-derived layer still being written goes first
                self.composer.flush(live.project_id)
            try:
                job = self.store.finish_job(job_id, status, error=error, params=params,
                                            started_at=(result or {}).get("started_at") or live.started_at,
                                            **_replaced(live, params))
            except Exception as exc:
                log.exception("storing the end of job %s", job_id)
                job = self.store.finish_job(job_id, "failed", error=f"{type(exc).__name__}: {exc}")
            with self._lock:
                live.status = job["status"] if job else "cancelled"
                self._live.pop(job_id, None)
        if job is not None and job["status"] == "done" and self.composer is not None:  # before done is told
            self.composer.warm(live.project_id, kept=result.get("kept") if params == live.params else None)
        self._publish_final(live, job)
        if more and job is not None and job["status"] == "done" and not self._stopping:
            self._refine_again(live.project_id, params)

    def _refine_again(self, project_id: str, params: dict) -> None:
        """A refinement for parameters whose derive still lacks saliency (they changed during the job)."""
        from autohaptics import pipeline
        from autohaptics.params import params_from_doc

        try:
            self.submit(self.store.get_project(project_id), params,
                        refine=pipeline.refinable(params_from_doc(params)[0]))
        except (Conflict, NotFound):  # a job of the project started meanwhile, or it was deleted
            pass

    def params_lock(self, project_id: str) -> threading.Lock:
        """Held while a project's parameters are changed (PUT params) and while its job finishes,
        so a change made during a job is never lost to the job's own parameters."""
        with self._lock:
            return self._params_locks.setdefault(project_id, threading.Lock())

    def _current_params(self, live: _Live, result: dict | None) -> tuple[dict, bool]:
        """Parameters to derive with at the end of a job: the project's current ones when they changed
        meanwhile and need no other analysis (the timeline is derived again), else the job's; and
        whether the timeline derived with them still lacks saliency (a refinement should follow)."""
        more = bool((result or {}).get("needs_analysis"))
        try:
            current = self.store.get_project(live.project_id)["params"]
        except NotFound:
            return live.params, False
        if current == live.params or self.composer is None:
            return live.params, more
        from autohaptics import pipeline
        from autohaptics.params import params_from_doc
        from autohaptics.server.composer import derive_timeline
        from autohaptics.timeline.npz import save_npz

        work = self.store.job_work_dir(live.job_id)
        analysis = pipeline.Analysis.load(work / "analysis.npz")
        p, _ = params_from_doc(current)
        if not pipeline.reusable(analysis, p):
            return live.params, more
        tl = derive_timeline(analysis, current, name=live.name)
        save_npz(tl, work / GENERATED)
        return current, bool(tl.stats.get("needs_analysis"))


def _replaced(live: _Live, params: dict) -> dict:
    """What a done job keeps of the timeline it replaces: the feature cache, when the job analysed
    with other analysis parameters (undoing the change re-derives from it), and the change as a
    ``params`` op when the job is a regeneration that changed the parameters."""
    from autohaptics.params import same_analysis

    if live.previous is None:
        return {}
    keep = not same_analysis(live.previous, live.params)
    op = {"op": "params", "from": live.previous, "to": params} if live.record and params != live.previous else None
    return {"keep_analysis": keep, "op": op}


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
