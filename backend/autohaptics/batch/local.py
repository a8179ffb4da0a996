"""A batch's films on local worker processes (:class:`~autohaptics.runner.WorkerPool`)."""

from __future__ import annotations

from concurrent.futures import FIRST_COMPLETED, Future, wait
from concurrent.futures.process import BrokenProcessPool
from typing import Any

from autohaptics.batch.work import Film, Run, process_film
from autohaptics.runner import WorkerPool

MAX_CRASHES = 2  # a film analysed in this many dying worker processes is reported as failed


def run_local(run: Run, params: Any, preset: str, jobs: int, style: Any = None) -> None:
    """Films on ``jobs`` worker processes; a pool whose worker died is replaced and the films it
    was running go again, except one that was being analysed in ``MAX_CRASHES`` dying workers."""
    pool = WorkerPool(min(jobs, len(run.films))).start()
    cancel = pool.cancel_event()
    try:
        todo = list(run.films)
        while todo:
            todo = _round(run, todo, params, preset, pool, cancel, style)
    except BaseException:  # Ctrl+C: running films stop at their next cancel check
        cancel.set()
        raise
    finally:
        pool.shutdown()


def _round(run: Run, todo: list[Film], params: Any, preset: str, pool: WorkerPool, cancel,
           style: Any = None) -> list[Film]:
    """Submit ``todo``; return the films to submit again after a worker died (the pool replaced).

    A film that had started in a worker when the pool broke is charged with the crash; the others
    were waiting and go again uncharged."""
    futures: dict[Future, Film] = {}
    for film in todo:
        fut = pool.submit(_film, film.index, str(film.source), params, preset, film.skip_sha, pool.events, cancel,
                          style)
        futures[fut] = film
    started: set[int] = set()
    again: list[Film] = []
    pending = set(futures)
    while pending:
        done, pending = wait(pending, timeout=0.2, return_when=FIRST_COMPLETED)
        started |= _drain(pool, run)
        for fut in sorted(done, key=lambda f: futures[f].index):
            film = futures[fut]
            exc = fut.exception()
            if isinstance(exc, BrokenProcessPool):
                film.fraction = 0.0
                if film.index in started:
                    film.crashes += 1
                if film.crashes >= MAX_CRASHES:
                    run.finish(film, error=f"the worker process died while analysing it ({film.crashes} times)")
                else:
                    again.append(film)
            elif exc is not None:
                run.finish(film, error=exc)
            else:
                run.finish(film, outcome=fut.result())
    if again:
        pool.replace()
    return again


def _film(index: int, source: str, params: Any, preset: str, skip_sha: str | None, events, cancel,
          style: Any = None) -> dict:
    """:func:`process_film` with its queue and cancel event (pool tasks take positional arguments)."""
    return process_film(index, source, params, preset, skip_sha, events=events, cancel=cancel, style=style)


def _drain(pool: WorkerPool, run: Run) -> set[int]:
    """Apply every waiting worker message; return the films that reported a start."""
    started: set[int] = set()
    for msg in pool.drain():
        if msg[1] == "start":
            started.add(msg[0])
        run.on_message(msg)
    return started
