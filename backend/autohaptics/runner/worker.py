"""What every worker process (server jobs, local batch films) does first, and how it reports back."""

from __future__ import annotations

import os
import signal
import threading
import time
from collections.abc import Callable

from autohaptics.runner.heap import bound_heap

PROGRESS_STEP = 0.01  # a worker reports at most every 1 % of its work (or on a stage change)


def start_worker(parent_pid: int) -> None:
    """Exit once the parent process is gone (killed hard) instead of lingering as an orphan, and
    bound the C heap (:func:`autohaptics.runner.heap.bound_heap`). Signals are the caller's to set."""
    bound_heap()

    def watch() -> None:
        while os.getppid() == parent_pid:
            time.sleep(1.0)
        os._exit(0)

    threading.Thread(target=watch, name="parent-watch", daemon=True).start()


def init_worker(parent_pid: int, ignore_term: bool = False) -> None:
    """Initializer of pool workers and Managers: Ctrl+C (and with ``ignore_term`` SIGTERM: process
    managers signal the whole process group) is the parent's to handle, which cancels the work
    through its cancel events; then :func:`start_worker`."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    if ignore_term:
        signal.signal(signal.SIGTERM, signal.SIG_IGN)
    start_worker(parent_pid)


def warm_up() -> None:
    """Import the pipeline and load the compiled loudness and area kernels in a fresh worker (once
    per process), so the first piece of work does not wait for them."""
    import autohaptics.pipeline  # noqa: F401
    from autohaptics.intensity import compiled
    from autohaptics.media import area

    compiled.load()
    area.kernel()


def queue_sender(q) -> Callable[[tuple], None]:
    """A ``send(message)`` that puts on ``q`` and drops the message when the parent is going away."""

    def send(message: tuple) -> None:
        try:
            q.put(message)
        except Exception:  # the parent is shutting down: progress no longer matters
            pass

    return send


class Reporter:
    """A worker's progress callback ``(stage, fraction)``: messages ``(key, "progress", stage,
    fraction)`` through ``send``, at most one per ``PROGRESS_STEP`` of a stage (and its end)."""

    def __init__(self, send: Callable[[tuple], None], key):
        self.send, self.key = send, key
        self.stage, self.fraction = None, -1.0

    def event(self, kind: str, *payload) -> None:
        """Send ``(key, kind, *payload)``."""
        self.send((self.key, kind, *payload))

    def __call__(self, stage: str, fraction: float) -> None:
        fraction = min(1.0, max(0.0, float(fraction)))
        if stage == self.stage and fraction < 1.0 and fraction - self.fraction < PROGRESS_STEP:
            return
        self.stage, self.fraction = stage, fraction
        self.event("progress", stage, fraction)
