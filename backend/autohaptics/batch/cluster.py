"""A batch's films on a Dask distributed cluster: one task per film; its workers must see the input
files at the same paths. Progress comes back as worker events on a topic of this run.

Failure modes end the batch with one line (AutohapticsError, exit 2 from the CLI), never a hang:
an address that does not parse, resolve or accept a connection fails at once; a scheduler lost
for ``LOST_SCHEDULER_S`` or a cluster without workers for ``NO_WORKERS_S`` ends the run (films
finished before keep their timelines), so the batch returns at most ``CLOSE_S`` after that bound.
Dask's own log lines (a cancelled reconnection's traceback, when the scheduler is lost) are kept
off stderr while the run talks to the cluster: the outcome is reported once, by the caller.
"""

from __future__ import annotations

import contextlib
import logging
import queue as queue_mod
import socket
import time
import uuid
from typing import Any

from autohaptics.batch.work import Run, failure_reason, process_film
from autohaptics.errors import AutohapticsError, ParameterError

CONNECT_S = 10.0  # a reachable scheduler answers within this, s
LOST_SCHEDULER_S = 15.0  # the scheduler unreachable this long ends the batch, s
NO_WORKERS_S = 30.0  # the cluster without a worker this long ends the batch, s
CLOSE_S = 5.0  # most time spent closing the client, s
_DASK_LOGGERS = ("distributed", "tornado", "bokeh")  # the loggers Dask's configuration gives a stderr handler


def check_address(scheduler: str) -> None:
    """Refuse at once a ``tcp://HOST:PORT`` whose port is not a number, whose host does not resolve
    or that refuses a connection (ParameterError); other protocols are left to Dask."""
    protocol, _, location = scheduler.partition("://")
    if protocol != "tcp":
        return
    host, sep, port = location.rstrip("/").rpartition(":")
    host = host.strip("[]")
    if not sep or not host or not port.isdigit() or not 0 < int(port) < 65536:
        raise ParameterError(f"--scheduler {scheduler}: expected tcp://HOST:PORT with a port in 1..65535")
    try:
        with socket.create_connection((host, int(port)), timeout=CONNECT_S):
            pass
    except socket.gaierror as exc:
        raise ParameterError(f"--scheduler {scheduler}: unknown host {host!r} ({exc.strerror})") from None
    except OSError as exc:
        raise ParameterError(f"--scheduler {scheduler}: no Dask scheduler answers there "
                             f"({exc.strerror or 'timed out'})") from None


def run_dask(run: Run, params: Any, preset: str, scheduler: str, style: Any = None) -> None:
    """One task per film on the Dask cluster at ``scheduler``; progress comes back as worker events.

    A worker that dies is handled by Dask (the task is retried elsewhere, then KilledWorker); a
    lost scheduler or a cluster left without workers raises AutohapticsError (module docstring)."""
    try:
        from distributed import Client
    except ImportError as exc:  # pragma: no cover - dask[distributed] is a dependency
        raise AutohapticsError(f"--scheduler needs dask[distributed]: {exc}") from None
    with _dask_logs_off():
        _run_on(Client, run, params, preset, scheduler, style)


def _run_on(Client, run: Run, params: Any, preset: str, scheduler: str, style: Any = None) -> None:
    try:
        client = Client(scheduler, timeout=f"{CONNECT_S}s", set_as_default=False)
    except (OSError, TimeoutError, ValueError) as exc:
        raise AutohapticsError(f"cannot connect to the Dask scheduler at {scheduler}: {failure_reason(exc)}") from None
    topic = f"autohaptics-batch-{uuid.uuid4().hex}"
    messages: "queue_mod.SimpleQueue[Any]" = queue_mod.SimpleQueue()
    futures: dict = {}
    lost = False
    try:
        client.subscribe_topic(topic, lambda event: messages.put(event[1]))
        for film in run.films:
            fut = client.submit(process_film, film.index, str(film.source), params, preset, film.skip_sha, topic=topic,
                                style=style, key=f"autohaptics-film-{film.index}-{topic[-12:]}", pure=False)
            futures[fut] = film
        _follow(client, futures, messages, run, scheduler)
    except _SchedulerLost:
        lost = True
        raise
    except BaseException:
        client.cancel(list(futures))
        raise
    finally:
        _close(client, topic, lost)


class _SchedulerLost(AutohapticsError):
    """The scheduler went away; nothing more can be asked of it."""


def _follow(client, futures: dict, messages, run: Run, scheduler: str) -> None:
    """Record each film as its task ends; raise when the cluster can no longer finish the rest."""
    from distributed import wait as dask_wait

    pending = set(futures)
    watch = _Watch(scheduler)
    while pending:
        try:
            with client.as_current():
                dask_wait(list(pending), timeout=0.5, return_when="FIRST_COMPLETED")
        except TimeoutError:
            pass
        except Exception as exc:  # the client cancels every future when it loses the scheduler
            if type(exc).__name__ != "FuturesCancelledError":
                raise
        _drain_simple(messages, run)
        if client.status != "running" and any(f.status == "cancelled" for f in pending):
            raise _SchedulerLost(f"lost the Dask scheduler at {scheduler}; {len(pending)} film(s) not done "
                                 "(finished ones are kept)")
        for fut in [f for f in pending if f.done()]:
            pending.discard(fut)
            _finish(run, futures[fut], fut)
        if pending:
            watch.check(client, len(pending))


class _Watch:
    """When the scheduler was last reachable and the cluster last had a worker."""

    def __init__(self, scheduler: str):
        self.scheduler = scheduler
        self.connected_at = self.workers_at = time.monotonic()

    def check(self, client, n_pending: int) -> None:
        now = time.monotonic()
        if client.status == "running":
            self.connected_at = now
        elif now - self.connected_at > LOST_SCHEDULER_S:
            raise _SchedulerLost(f"lost the Dask scheduler at {self.scheduler} for {LOST_SCHEDULER_S:g} s; "
                                 f"{n_pending} film(s) not done (finished ones are kept)")
        if client.status == "running":
            workers = (client.scheduler_info() or {}).get("workers") or {}
            if workers:
                self.workers_at = now
            elif now - self.workers_at > NO_WORKERS_S:
                raise AutohapticsError(f"the Dask cluster at {self.scheduler} has had no worker for "
                                       f"{NO_WORKERS_S:g} s; {n_pending} film(s) not done (finished ones are kept)")


def _finish(run: Run, film, fut) -> None:
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


def _close(client, topic: str, lost: bool) -> None:
    """Close the client within ``CLOSE_S``, asking nothing of a scheduler that is gone."""
    try:
        if not lost:
            client.unsubscribe_topic(topic)
        client.close(timeout=CLOSE_S)
    except Exception:  # closing is best effort: the run's outcome is already decided
        pass


@contextlib.contextmanager
def _dask_logs_off():
    """Drop every record that reaches the handlers of Dask's loggers (module docstring) meanwhile."""
    handlers = {handler for name, logger in list(logging.Logger.manager.loggerDict.items())
                if name.split(".")[0] in _DASK_LOGGERS and isinstance(logger, logging.Logger)
                for handler in logger.handlers}
    for handler in handlers:
        handler.addFilter(_drop)
    try:
        yield
    finally:
        for handler in handlers:
            handler.removeFilter(_drop)


def _drop(record: logging.LogRecord) -> bool:
    return False


def _drain_simple(messages: "queue_mod.SimpleQueue[Any]", run: Run) -> None:
    while True:
        try:
            msg = messages.get_nowait()
        except queue_mod.Empty:
            return
        if isinstance(msg, (tuple, list)) and len(msg) >= 2:
            run.on_message(tuple(msg))
