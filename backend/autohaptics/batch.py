"""Many films in one run: :func:`run_batch` writes ``OUT_DIR/<name>.timeline.json`` per film.

- Inputs are files, folders (their media files, not recursive) or glob patterns (``**`` recurses);
  :func:`collect_inputs` expands them, sorted and without duplicates.
- Each film runs :func:`autohaptics.pipeline.generate` in a worker: a local process pool of
  ``jobs`` processes (spawn context), or one task per film on an existing Dask distributed
  cluster (``scheduler="tcp://HOST:PORT"``; its workers must see the input files at the same
  paths). The worker returns the timeline and this process writes it, so both paths give the
  same files.
- A film is skipped when its timeline exists and was made from the same source (SHA-256) with
  the same resolved parameters and preset. ``OUT_DIR/batch-manifest.json`` records, per output
  name, the source path, its SHA-256 and the parameters' digest; without an entry the existing
  timeline's ``source.sha256`` and ``generator`` are read instead.
- Output names are the file stem; a stem already taken (another film of the run, or one the
  manifest records for a file that still exists) gets ``-<8 hex of the source path's SHA-1>``.
  A film keeps the name the manifest gave it in earlier runs.
- A failing film does not stop the others: every failure is in the :class:`BatchReport` with a
  one-line reason. A worker process that dies is replaced; a film that was being analysed in two
  dying workers is reported as failed.
- One overall progress callback ``progress(stage, fraction)``: films weighted by file size.
"""

from __future__ import annotations

import glob
import hashlib
import json
import multiprocessing
import os
import queue as queue_mod
import signal
import time
import uuid
from concurrent.futures import FIRST_COMPLETED, Future, ProcessPoolExecutor, wait
from concurrent.futures.process import BrokenProcessPool
from multiprocessing.managers import SyncManager
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Iterable

from autohaptics.errors import AutohapticsError, ParameterError
from autohaptics.progress import ProgressFn, null_progress
from autohaptics.workers import start_worker

MANIFEST_NAME = "batch-manifest.json"
MANIFEST_FORMAT = "autohaptics.batch-manifest"
OUTPUT_SUFFIX = ".timeline.json"
MEDIA_SUFFIXES = frozenset({
    ".mp4", ".m4v", ".mov", ".mkv", ".webm", ".avi", ".mpg", ".mpeg", ".ts", ".m2ts", ".mts", ".wmv",
    ".flv", ".ogv", ".3gp", ".wav", ".flac", ".mp3", ".m4a", ".aac", ".ogg", ".oga", ".opus",
})
_MAX_CRASHES = 2  # a film analysed in this many dying worker processes is reported as failed
_PROGRESS_STEP = 0.01  # workers report at most every 1 % of a film (or on a stage change)
_GLOB_CHARS = frozenset("*?[")


@dataclass
class FilmResult:
    """What happened to one film.

    status : "done" (timeline written), "skipped" (an up-to-date timeline was there) or "failed".
    reason : one line, for a failed film.
    seconds : wall time of the film's generation (done films only).
    """

    source: Path
    output: Path
    status: str
    reason: str | None = None
    seconds: float | None = None


@dataclass
class BatchReport:
    """The outcome of :func:`run_batch`, one :class:`FilmResult` per input film (input order)."""

    out_dir: Path
    results: list[FilmResult] = field(default_factory=list)

    def _with(self, status: str) -> list[FilmResult]:
        return [r for r in self.results if r.status == status]

    @property
    def done(self) -> list[FilmResult]:
        return self._with("done")

    @property
    def skipped(self) -> list[FilmResult]:
        return self._with("skipped")

    @property
    def failed(self) -> list[FilmResult]:
        return self._with("failed")

    @property
    def exit_status(self) -> int:
        """0 when every film has an up-to-date timeline, 1 when some failed."""
        return 1 if self.failed else 0

    def summary(self) -> str:
        return (f"{len(self.results)} film(s): {len(self.done)} done, {len(self.skipped)} skipped "
                f"(up to date), {len(self.failed)} failed; timelines in {self.out_dir}")


# ------------------------------------------------------------------- inputs
def collect_inputs(specs: Iterable[str | os.PathLike]) -> list[Path]:
    """Expand files, folders (their files with a media suffix) and glob patterns into film paths.

    Sorted by path, duplicates (same resolved file) removed. Raises ParameterError naming an input
    that does not exist or a pattern that matches nothing, and when no film is found at all.
    """
    specs = list(specs)
    found: dict[Path, Path] = {}
    for spec in specs:
        text = os.fspath(spec)
        p = Path(text).expanduser()
        if p.is_dir():
            files = [c for c in p.iterdir() if c.is_file() and c.suffix.lower() in MEDIA_SUFFIXES]
        elif p.is_file():
            files = [p]
        elif _GLOB_CHARS & set(text):
            files = [Path(m) for m in glob.glob(os.path.expanduser(text), recursive=True) if Path(m).is_file()]
            if not files:
                raise ParameterError(f"{text}: the pattern matches no file")
        else:
            raise ParameterError(f"{text}: no such file or folder")
        for f in files:
            found.setdefault(f.resolve(), f.absolute())
    if not found:
        raise ParameterError("no media files found in " + ", ".join(os.fspath(s) for s in specs))
    return sorted(found.values())


def output_names(sources: list[Path], manifest: dict[str, dict]) -> dict[Path, str]:
    """Output name (without ``.timeline.json``) per source: the name the manifest gave that source
    earlier, else its stem, else the stem with 8 hex digits of the path's SHA-1 when the stem is taken.

    Names are compared case-insensitively, so outputs never collide on a case-insensitive disk.
    """
    names: dict[Path, str] = {}
    taken: set[str] = set()
    by_source = {str(e.get("source")): name for name, e in manifest.items()}
    for src in sources:
        name = by_source.get(str(src))
        if name is not None and name.casefold() not in taken:
            names[src] = name
            taken.add(name.casefold())
    wanted = {str(s) for s in sources}
    for name, entry in manifest.items():  # films of earlier runs that still exist keep their names
        other = str(entry.get("source"))
        if other not in wanted and Path(other).exists():
            taken.add(name.casefold())
    for src in sources:
        if src in names:
            continue
        name = _safe_stem(src)
        if name.casefold() in taken:
            tag = hashlib.sha1(str(src).encode()).hexdigest()[:8]
            name, k = f"{name}-{tag}", 2
            while name.casefold() in taken:
                name, k = f"{_safe_stem(src)}-{tag}-{k}", k + 1
        names[src] = name
        taken.add(name.casefold())
    return names


def _safe_stem(src: Path) -> str:
    stem = src.stem.strip() or "film"
    return stem if not stem.startswith(".") else "_" + stem[1:]


# ----------------------------------------------------------------- manifest
def params_digest(params: Any, preset: str) -> str:
    """SHA-256 of the resolved parameters and the preset name (what makes a timeline up to date)."""
    from autohaptics.records import params_to_dict

    doc = {"params": params_to_dict(params), "preset": preset}
    return hashlib.sha256(json.dumps(doc, sort_keys=True).encode()).hexdigest()


def load_manifest(out_dir: Path) -> dict[str, dict]:
    """The manifest's films ({output name: entry}); empty when absent or unreadable (the existing
    timelines are then read instead)."""
    try:
        doc = json.loads((out_dir / MANIFEST_NAME).read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return {}
    films = doc.get("films") if isinstance(doc, dict) and doc.get("format") == MANIFEST_FORMAT else None
    return {k: v for k, v in films.items() if isinstance(v, dict)} if isinstance(films, dict) else {}


def save_manifest(out_dir: Path, films: dict[str, dict]) -> None:
    """Write the manifest atomically (a temporary file renamed into place)."""
    path = out_dir / MANIFEST_NAME
    tmp = path.with_name(path.name + ".part")
    doc = {"format": MANIFEST_FORMAT, "version": 1, "films": dict(sorted(films.items()))}
    tmp.write_text(json.dumps(doc, indent=1) + "\n", encoding="utf-8")
    os.replace(tmp, path)


def _recorded_sha(output: Path, entry: dict | None, source: Path, digest: str, params: Any,
                  preset: str) -> str | None:
    """The source SHA-256 an existing, parameter-matching timeline was made from (None: redo)."""
    if not output.is_file():
        return None
    if entry is not None:
        if entry.get("source") == str(source) and entry.get("params_digest") == digest:
            return entry.get("sha256")
        return None
    return _timeline_sha(output, params, preset)


def _timeline_sha(output: Path, params: Any, preset: str) -> str | None:
    """``source.sha256`` of a timeline file whose ``generator`` matches ``params`` and ``preset``."""
    from autohaptics.records import params_to_dict

    try:
        with open(output, encoding="utf-8") as fh:
            doc = json.load(fh)
        gen, src = doc["generator"], doc["source"]
        stored = gen["params"]
    except (OSError, ValueError, KeyError, TypeError):
        return None
    if gen.get("preset") != preset or not isinstance(stored, dict):
        return None
    if any(stored.get(k) != v for k, v in params_to_dict(params).items()):
        return None
    sha = src.get("sha256") if isinstance(src, dict) else None
    return sha if isinstance(sha, str) else None


# -------------------------------------------------------------- worker side
_events = None  # multiprocessing queue of (index, kind, stage, fraction), set in local workers
_cancel = None  # multiprocessing Event, set in local workers


def _init_local_worker(events, cancel, parent_pid: int) -> None:
    """Pool initializer: keep the queue and the cancel event, leave Ctrl+C to the parent (which
    cancels through the event), exit when the parent is gone."""
    global _events, _cancel
    _events, _cancel = events, cancel
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    start_worker(parent_pid)


class _Reporter:
    """Throttled progress of one film from inside a worker: to the local queue, or as a Dask event."""

    def __init__(self, index: int, topic: str | None):
        self.index, self.topic = index, topic
        self.stage, self.fraction = None, -1.0
        self.worker = None
        if topic is not None:
            from distributed import get_worker

            self.worker = get_worker()

    def send(self, kind: str, stage: str = "", fraction: float = 0.0) -> None:
        msg = (self.index, kind, stage, fraction)
        try:
            if self.worker is not None:
                self.worker.log_event(self.topic, msg)
            elif _events is not None:
                _events.put(msg)
        except Exception:  # the parent is going away: progress no longer matters
            pass

    def __call__(self, stage: str, fraction: float) -> None:
        fraction = min(1.0, max(0.0, float(fraction)))
        if stage == self.stage and fraction < 1.0 and fraction - self.fraction < _PROGRESS_STEP:
            return
        self.stage, self.fraction = stage, fraction
        self.send("progress", stage, fraction)


def process_film(index: int, source: str, params: Any, preset: str, skip_sha: str | None = None,
                 topic: str | None = None) -> dict:
    """Worker entry point for one film (local pool or Dask task).

    Returns {"status": "skipped", "sha256"} when the file's SHA-256 equals ``skip_sha``, else
    {"status": "done", "timeline", "seconds"}. Raises the pipeline's errors for unusable input.
    """
    from autohaptics.heap import release_between_passes
    from autohaptics.pipeline import file_sha256, generate

    reporter = _Reporter(index, topic)
    reporter.send("start")
    t0 = time.perf_counter()
    if skip_sha is not None:
        try:
            sha = file_sha256(source)
        except OSError as exc:
            raise AutohapticsError(f"{source}: cannot read ({exc.strerror or exc})") from None
        if sha == skip_sha:
            return {"status": "skipped", "sha256": sha}
    tl = generate(source, params, preset=preset, progress=reporter, cancel=_cancel,
                  between_passes=release_between_passes)
    return {"status": "done", "timeline": tl, "seconds": time.perf_counter() - t0}


# -------------------------------------------------------------- parent side
@dataclass
class _Film:
    index: int
    source: Path
    output: Path
    name: str
    weight: float
    skip_sha: str | None
    fraction: float = 0.0
    crashes: int = 0


class _Run:
    """Bookkeeping of one batch: results, manifest, overall progress."""

    def __init__(self, films: list[_Film], out_dir: Path, manifest: dict, digest: str, preset: str,
                 progress: ProgressFn):
        self.films, self.out_dir, self.manifest = films, out_dir, manifest
        self.digest, self.preset, self.progress = digest, preset, progress
        self.results: dict[int, FilmResult] = {}
        self.total = sum(f.weight for f in films) or 1.0

    def report_progress(self) -> None:
        done = len(self.results)
        frac = sum(f.weight * (1.0 if f.index in self.results else f.fraction) for f in self.films) / self.total
        self.progress(f"{done}/{len(self.films)} films", min(1.0, frac))

    def on_message(self, msg: tuple) -> None:
        index, kind, _stage, fraction = msg
        if kind == "progress" and 0 <= index < len(self.films) and index not in self.results:
            self.films[index].fraction = max(self.films[index].fraction, float(fraction))
            self.report_progress()

    def finish(self, film: _Film, outcome: dict | None = None, error: BaseException | str | None = None) -> None:
        if error is None and outcome is not None and outcome["status"] == "done":
            try:
                tl = outcome["timeline"]
                tl.save(film.output)
                self._record(film, tl.source.get("sha256"))
            except (OSError, AutohapticsError) as exc:
                error = exc
            else:
                self.results[film.index] = FilmResult(film.source, film.output, "done",
                                                      seconds=float(outcome.get("seconds", 0.0)))
        elif error is None and outcome is not None:
            entry = self.manifest.get(film.name) or {}
            if (entry.get("source"), entry.get("sha256"), entry.get("params_digest")) != (
                    str(film.source), outcome["sha256"], self.digest):
                try:  # found up to date by reading the timeline: remember it
                    self._record(film, outcome["sha256"])
                except OSError:
                    pass
            self.results[film.index] = FilmResult(film.source, film.output, "skipped")
        if error is not None:
            reason = _reason(error)
            for prefix in (f"{film.source}: ", f"{film.source.name}: "):
                reason = reason[len(prefix):] if reason.startswith(prefix) else reason
            self.results[film.index] = FilmResult(film.source, film.output, "failed", reason=reason)
        self.report_progress()


    def _record(self, film: _Film, sha256: str | None) -> None:
        self.manifest[film.name] = {
            "source": str(film.source), "sha256": sha256, "params_digest": self.digest, "preset": self.preset,
            "finished_at": time.strftime("%Y-%m-%dT%H:%M:%S%z"),
        }
        save_manifest(self.out_dir, self.manifest)


def _reason(error: BaseException | str) -> str:
    """One line saying why a film failed."""
    if isinstance(error, str):
        text = error
    elif isinstance(error, AutohapticsError):
        text = str(error)
    elif isinstance(error, OSError):
        text = f"{error.filename or ''}: {error.strerror or error}".lstrip(": ")
    else:
        text = f"{type(error).__name__}: {error}"
    lines = [ln.strip() for ln in text.splitlines() if ln.strip()]
    return lines[0] if lines else type(error).__name__


def run_batch(inputs: Iterable[str | os.PathLike], out_dir: str | os.PathLike, params: Any = None,
              preset: str | None = None, *, jobs: int = 1, scheduler: str | None = None,
              progress: ProgressFn | None = None) -> BatchReport:
    """Generate a timeline per film of ``inputs`` into ``out_dir`` (created when missing).

    inputs : files, folders and glob patterns (:func:`collect_inputs`).
    params, preset : :class:`~autohaptics.params.GenerateParams` and the preset name they were
        resolved from (:func:`~autohaptics.params.resolve_params`); default: the default preset.
    jobs : local worker processes (>= 1); ignored when ``scheduler`` is given.
    scheduler : address of a Dask distributed scheduler (``tcp://HOST:PORT``): one task per film
        on that cluster instead of local processes.

    Raises ParameterError for usage errors (no films, bad ``jobs``, ``out_dir`` is a file, bad
    scheduler address); film failures are in the report, never raised. Ctrl+C cancels the
    running films (KeyboardInterrupt propagates); films finished so far keep their timelines.
    """
    from autohaptics.params import DEFAULT_PRESET, resolve_params

    preset = preset or DEFAULT_PRESET
    if params is None:
        params, preset = resolve_params(preset)
    if scheduler is None and (not isinstance(jobs, int) or jobs < 1):
        raise ParameterError(f"jobs must be a whole number >= 1, got {jobs!r}")
    if scheduler is not None and not (isinstance(scheduler, str) and "://" in scheduler
                                      and scheduler.split("://", 1)[1]):
        raise ParameterError(f"scheduler must be an address like tcp://HOST:PORT, got {scheduler!r}")
    sources = collect_inputs(inputs)
    out = Path(out_dir)
    if out.exists() and not out.is_dir():
        raise ParameterError(f"{out}: exists and is not a folder")
    try:
        out.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise ParameterError(f"{out}: cannot create the output folder ({exc.strerror or exc})") from None
    manifest = load_manifest(out)
    names = output_names(sources, manifest)
    digest = params_digest(params, preset)
    films = []
    for i, src in enumerate(sources):
        output = out / f"{names[src]}{OUTPUT_SUFFIX}"
        try:
            weight = float(max(src.stat().st_size, 1))
        except OSError:
            weight = 1.0
        films.append(_Film(i, src, output, names[src], weight,
                           _recorded_sha(output, manifest.get(names[src]), src, digest, params, preset)))
    run = _Run(films, out, manifest, digest, preset, progress or null_progress)
    run.report_progress()
    if scheduler is not None:
        _run_dask(run, params, preset, scheduler)
    else:
        _run_local(run, params, preset, jobs)
    return BatchReport(out, [run.results[f.index] for f in films])


def _run_local(run: _Run, params: Any, preset: str, jobs: int) -> None:
    """Films on a pool of ``jobs`` spawned processes; a dead worker's pool is replaced.

    Messages and the cancel flag go through a Manager (a worker killed in the middle of a message
    cannot leave a lock held, as it could with a plain multiprocessing queue)."""
    ctx = multiprocessing.get_context("spawn")
    manager = SyncManager(ctx=ctx)
    manager.start(_ignore_sigint)
    try:
        events, cancel = manager.Queue(), manager.Event()
        todo = list(run.films)
        while todo:
            todo = _local_round(run, todo, params, preset, jobs, ctx, events, cancel)
    finally:
        manager.shutdown()


def _ignore_sigint() -> None:
    """Manager initializer: Ctrl+C is the parent's to handle (it cancels the films, then stops us)."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)


def _local_round(run: _Run, todo: list[_Film], params: Any, preset: str, jobs: int, ctx, events,
                 cancel) -> list[_Film]:
    """Submit ``todo`` to a fresh pool; return the films to submit again after a worker died.

    A film that had started in a worker when the pool broke is charged with the crash; the others
    were waiting and go again uncharged."""
    pool = ProcessPoolExecutor(max_workers=min(jobs, len(todo)), mp_context=ctx,
                               initializer=_init_local_worker, initargs=(events, cancel, os.getpid()))
    futures: dict[Future, _Film] = {}
    started: set[int] = set()
    again: list[_Film] = []
    broken = False
    try:
        for film in todo:
            futures[pool.submit(process_film, film.index, str(film.source), params, preset, film.skip_sha)] = film
        pending = set(futures)
        while pending:
            done, pending = wait(pending, timeout=0.2, return_when=FIRST_COMPLETED)
            started |= _drain(events, run)
            for fut in sorted(done, key=lambda f: futures[f].index):
                film = futures[fut]
                exc = fut.exception()
                if isinstance(exc, BrokenProcessPool):
                    broken = True
                    film.fraction = 0.0
                    if film.index in started:
                        film.crashes += 1
                    if film.crashes >= _MAX_CRASHES:
                        run.finish(film, error="the worker process died while analysing it "
                                               f"({film.crashes} times)")
                    else:
                        again.append(film)
                elif exc is not None:
                    run.finish(film, error=exc)
                else:
                    run.finish(film, outcome=fut.result())
    except BaseException:  # Ctrl+C: running films stop at their next cancel check
        cancel.set()
        pool.shutdown(wait=True, cancel_futures=True)
        raise
    pool.shutdown(wait=not broken, cancel_futures=True)
    return again


def _drain(events, run: _Run) -> set[int]:
    """Apply every queued worker message; return the films that reported a start."""
    started: set[int] = set()
    while True:
        try:
            msg = events.get_nowait()
        except queue_mod.Empty:
            return started
        if msg[1] == "start":
            started.add(msg[0])
        run.on_message(msg)


def _run_dask(run: _Run, params: Any, preset: str, scheduler: str) -> None:
    """One task per film on the Dask cluster at ``scheduler``; progress comes back as worker events.

    A worker that dies is handled by Dask (the task is retried elsewhere, then KilledWorker)."""
    try:
        from distributed import Client
        from distributed import wait as dask_wait
    except ImportError as exc:  # pragma: no cover - dask[distributed] is a dependency
        raise AutohapticsError(f"--scheduler needs dask[distributed]: {exc}") from None
    try:
        client = Client(scheduler, timeout="20s", set_as_default=False)
    except (OSError, TimeoutError, ValueError) as exc:
        raise AutohapticsError(f"cannot connect to the Dask scheduler at {scheduler}: {_reason(exc)}") from None
    topic = f"autohaptics-batch-{uuid.uuid4().hex}"
    messages: "queue_mod.SimpleQueue[Any]" = queue_mod.SimpleQueue()
    futures = {}
    try:
        client.subscribe_topic(topic, lambda event: messages.put(event[1]))
        for film in run.films:
            fut = client.submit(process_film, film.index, str(film.source), params, preset, film.skip_sha, topic,
                                key=f"autohaptics-film-{film.index}-{topic[-12:]}", pure=False)
            futures[fut] = film
        pending = set(futures)
        while pending:
            try:
                with client.as_current():
                    dask_wait(list(pending), timeout=0.5, return_when="FIRST_COMPLETED")
            except TimeoutError:
                pass
            _drain_simple(messages, run)
            for fut in [f for f in pending if f.done()]:
                pending.discard(fut)
                film = futures[fut]
                if fut.status == "error":
                    exc = fut.exception()
                    if type(exc).__name__ == "KilledWorker":
                        exc = "the Dask workers that ran it died (KilledWorker)"
                    run.finish(film, error=exc)
                elif fut.status == "finished":
                    run.finish(film, outcome=fut.result())
                else:
                    run.finish(film, error=f"the task ended as {fut.status} on the cluster")
                fut.release()
    except BaseException:
        client.cancel(list(futures))
        raise
    finally:
        try:
            client.unsubscribe_topic(topic)
        except Exception:
            pass
        client.close()


def _drain_simple(messages: "queue_mod.SimpleQueue[Any]", run: _Run) -> None:
    while True:
        try:
            msg = messages.get_nowait()
        except queue_mod.Empty:
            return
        if isinstance(msg, (tuple, list)) and len(msg) == 4:
            run.on_message(tuple(msg))


__all__ = ["BatchReport", "FilmResult", "MANIFEST_NAME", "MEDIA_SUFFIXES", "collect_inputs", "load_manifest",
           "output_names", "params_digest", "process_film", "run_batch", "save_manifest"]
