"""A batch's films on a Dask distributed cluster: one task per film; its workers must see the input
files at the same paths. Progress comes back as worker events on a topic of this run."""

from __future__ import annotations

import queue as queue_mod
import uuid
from typing import Any

from autohaptics.batch.work import Run, failure_reason, process_film
from autohaptics.errors import AutohapticsError


def run_dask(run: Run, params: Any, preset: str, scheduler: str) -> None:
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
        raise AutohapticsError(f"cannot connect to the Dask scheduler at {scheduler}: {failure_reason(exc)}") from None
    topic = f"autohaptics-batch-{uuid.uuid4().hex}"
    messages: "queue_mod.SimpleQueue[Any]" = queue_mod.SimpleQueue()
    futures = {}
    try:
        client.subscribe_topic(topic, lambda event: messages.put(event[1]))
        for film in run.films:
            fut = client.submit(process_film, film.index, str(film.source), params, preset, film.skip_sha, topic=topic,
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


def _drain_simple(messages: "queue_mod.SimpleQueue[Any]", run: Run) -> None:
    while True:
        try:
            msg = messages.get_nowait()
        except queue_mod.Empty:
            return
        if isinstance(msg, (tuple, list)) and len(msg) >= 2:
            run.on_message(tuple(msg))
