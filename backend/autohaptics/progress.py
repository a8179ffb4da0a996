"""Progress reporting and cancellation shared by the CLI, jobs and the pipeline.

A progress callback is ``progress(stage: str, fraction: float)`` with fraction in [0, 1] for the
whole run. A cancel token is anything with ``is_set() -> bool`` (``threading.Event`` works);
:func:`check_cancel` raises :class:`CancelledError` when it is set.
"""

from __future__ import annotations

import sys
import time
from collections.abc import Callable
from typing import IO, Protocol

from autohaptics.errors import CancelledError

ProgressFn = Callable[[str, float], None]


class CancelToken(Protocol):
    def is_set(self) -> bool: ...


def check_cancel(cancel: CancelToken | None) -> None:
    """Raise CancelledError if ``cancel`` is set."""
    if cancel is not None and cancel.is_set():
        raise CancelledError("cancelled by request")


def null_progress(stage: str, fraction: float) -> None:
    """A progress callback that ignores everything."""


class ProgressBar:
    """A one-line text progress bar on stderr, redrawn at most 10 times a second.

    Silent when ``stream`` is not a terminal unless ``force`` is set (then it prints a line per
    10 %), so logs stay readable.
    """

    def __init__(self, label: str = "", *, stream: IO[str] | None = None, width: int = 30, force: bool = False):
        self.label = label
        self.stream = stream or sys.stderr
        self.width = width
        self.tty = bool(getattr(self.stream, "isatty", lambda: False)())
        self.force = force
        self._last_draw = 0.0
        self._last_decile = -1
        self._start = time.monotonic()
        self._done = False

    def __call__(self, stage: str, fraction: float) -> None:
        fraction = min(1.0, max(0.0, float(fraction)))
        now = time.monotonic()
        if self.tty:
            if now - self._last_draw < 0.1 and fraction < 1.0:
                return
            self._last_draw = now
            filled = int(round(self.width * fraction))
            elapsed = now - self._start
            bar = "#" * filled + "-" * (self.width - filled)
            self.stream.write(f"\r{self.label} [{bar}] {fraction * 100:5.1f}% {stage:<12.12} {elapsed:6.1f}s")
            self.stream.flush()
        elif self.force:
            decile = int(fraction * 10)
            if decile > self._last_decile:
                self._last_decile = decile
                self.stream.write(f"{self.label} {decile * 10:3d}% {stage}\n")
                self.stream.flush()

    def close(self) -> None:
        if self.tty and not self._done:
            self.stream.write("\n")
            self.stream.flush()
        self._done = True

    def __enter__(self) -> "ProgressBar":
        return self

    def __exit__(self, *exc) -> None:
        self.close()
