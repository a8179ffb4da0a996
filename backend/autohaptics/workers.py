"""What every worker process (server jobs, local batch pool) sets up first."""

from __future__ import annotations

import os
import threading
import time

from autohaptics.heap import bound_heap


def start_worker(parent_pid: int) -> None:
    """Exit once the parent process is gone (killed hard) instead of lingering as an orphan, and
    bound the C heap (:func:`autohaptics.heap.bound_heap`). Signals are the caller's to set."""
    bound_heap()

    def watch() -> None:
        while os.getppid() == parent_pid:
            time.sleep(1.0)
        os._exit(0)

    threading.Thread(target=watch, name="parent-watch", daemon=True).start()


__all__ = ["start_worker"]
