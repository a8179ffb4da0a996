"""One film of a batch: the worker's entry point (a local worker process or a Dask task) and the
parent's bookkeeping of results, manifest and overall progress."""

from __future__ import annotations

import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from autohaptics.batch.films import FilmResult, save_manifest
from autohaptics.errors import AutohapticsError
from autohaptics.progress import ProgressFn
from autohaptics.runner import Reporter, queue_sender


def process_film(index: int, source: str, params: Any, preset: str, skip_sha: str | None = None, *,
                 events=None, cancel=None, topic: str | None = None, style: Any = None) -> dict:
    """Worker entry point for one film (local pool or Dask task).

    Messages ``(index, "start")`` and ``(index, "progress", stage, fraction)`` go to ``events`` (a
    local worker's queue) or, on a Dask worker, to the event ``topic``. ``cancel`` stops the film.
    ``style`` (an :class:`autohaptics.style.Style`) shapes its timeline.
    Returns {"status": "skipped", "sha256"} when the file's SHA-256 equals ``skip_sha``, else
    {"status": "done", "timeline", "seconds"}. Raises the pipeline's errors for unusable input.
    """
    from autohaptics.pipeline import file_sha256, generate
    from autohaptics.runner.heap import release_between_passes

    if topic is not None:
        send = _dask_sender(topic)
    else:
        send = queue_sender(events) if events is not None else (lambda message: None)
    reporter = Reporter(send, index)
    reporter.event("start")
    t0 = time.perf_counter()
    if skip_sha is not None:
        try:
            sha = file_sha256(source)
        except OSError as exc:
            raise AutohapticsError(f"{source}: cannot read ({exc.strerror or exc})") from None
        if sha == skip_sha:
            return {"status": "skipped", "sha256": sha}
    tl = generate(source, params, preset=preset, progress=reporter, cancel=cancel,
                  between_passes=release_between_passes, style=style)
    return {"status": "done", "timeline": tl, "seconds": time.perf_counter() - t0}


def _dask_sender(topic: str):
    """``send(message)`` as an event of ``topic`` on the Dask worker running this task."""
    from distributed import get_worker

    worker = get_worker()

    def send(message: tuple) -> None:
        try:
            worker.log_event(topic, message)
        except Exception:  # the client is going away: progress no longer matters
            pass

    return send


@dataclass
class Film:
    index: int
    source: Path
    output: Path
    name: str
    weight: float
    skip_sha: str | None
    fraction: float = 0.0
    crashes: int = 0


class Run:
    """Bookkeeping of one batch: results, manifest, overall progress."""

    def __init__(self, films: list[Film], out_dir: Path, manifest: dict, digest: str, preset: str,
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
        """A worker's ``(index, kind, *payload)``; progress moves the film's fraction."""
        index, kind = msg[0], msg[1]
        if kind == "progress" and 0 <= index < len(self.films) and index not in self.results:
            self.films[index].fraction = max(self.films[index].fraction, float(msg[3]))
            self.report_progress()

    def finish(self, film: Film, outcome: dict | None = None, error: BaseException | str | None = None) -> None:
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
            reason = failure_reason(error)
            for prefix in (f"{film.source}: ", f"{film.source.name}: "):
                reason = reason[len(prefix):] if reason.startswith(prefix) else reason
            self.results[film.index] = FilmResult(film.source, film.output, "failed", reason=reason)
        self.report_progress()


    def _record(self, film: Film, sha256: str | None) -> None:
        self.manifest[film.name] = {
            "source": str(film.source), "sha256": sha256, "params_digest": self.digest, "preset": self.preset,
            "finished_at": time.strftime("%Y-%m-%dT%H:%M:%S%z"),
        }
        save_manifest(self.out_dir, self.manifest)


def failure_reason(error: BaseException | str) -> str:
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
