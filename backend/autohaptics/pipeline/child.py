"""Run a function in a forked child process beside the caller: its progress and result come back
over a pipe, and a caller that stops early kills it.

Why a process: the audio pass's compiled kernels and per-chunk Python hold the GIL, so in a thread
beside the video pass it only takes turns with it; a forked child shares the parent's imports and
memory pages and runs on the other core. POSIX only (:func:`can_fork`).
"""

from __future__ import annotations

import ctypes
import gc
import os
import pickle
import signal
import struct
import threading
import traceback
from collections.abc import Callable
from typing import Any

from autohaptics.progress import CancelToken, check_cancel


_PR_SET_PDEATHSIG = 1


def can_fork() -> bool:
    return hasattr(os, "fork")


class ChildFailed(RuntimeError):
    """The child died or its error could not be sent back."""


class _Pipe:
    """One end of an ``os.pipe``: pickled messages, each after its length (8 bytes, big-endian);
    not ``multiprocessing.connection``, whose import costs a process ~15 ms of CPU."""

    _HEAD = struct.Struct("!Q")

    def __init__(self, fd: int):
        self.fd = fd

    def send(self, obj: Any) -> None:
        data = pickle.dumps(obj, protocol=pickle.HIGHEST_PROTOCOL)
        for view in (memoryview(self._HEAD.pack(len(data))), memoryview(data)):
            while view:
                view = view[os.write(self.fd, view):]

    def recv(self) -> Any:
        """The next message; EOFError when the writer closed its end first."""
        return pickle.loads(self._read(self._HEAD.unpack(self._read(self._HEAD.size))[0]))

    def _read(self, n: int) -> bytes:
        parts, left = [], n
        while left:
            chunk = os.read(self.fd, min(left, 1 << 20))
            if not chunk:
                raise EOFError("the pipe closed")
            parts.append(chunk)
            left -= len(chunk)
        return b"".join(parts)

    def close(self) -> None:
        os.close(self.fd)


class Child:
    """``fn(report)`` in a forked process, where ``report(fraction)`` sends progress (0..1).

    :meth:`result` waits for the value (re-raising the child's exception); ``on_progress``,
    ``on_result`` and, once the child is done either way, ``on_end`` are called in a receiving
    thread of the parent. Use as a context manager: leaving it early kills and reaps the child.
    """

    def __init__(self, fn: Callable[[Callable[[float], None]], Any], *,
                 on_progress: Callable[[float], None] = lambda f: None,
                 on_result: Callable[[Any], None] = lambda v: None, on_end: Callable[[], None] = lambda: None):
        self._fn, self._on_progress, self._on_result, self._on_end = fn, on_progress, on_result, on_end
        self._outcome: tuple[str, Any] | None = None
        self._done = threading.Event()
        self.pid = 0

    def __enter__(self) -> "Child":
        r, w = os.pipe()
        # the parent's objects are frozen across the fork, so the child's garbage collector never
        # finalises them: a decoded frame in a reference cycle would free FFmpeg's thread pools
        # there, whose threads exist only in the parent (the child hung in pthread_cond_destroy)
        pid, enabled = -1, gc.isenabled()
        gc.disable()
        gc.freeze()
        try:
            pid = os.fork()
        finally:
            if pid != 0:  # the parent, or a fork that failed: its objects thaw again
                gc.unfreeze()
            if enabled:
                gc.enable()
        if pid == 0:  # the child: nothing of the parent runs here but fn
            os.close(r)
            _run_child(self._fn, _Pipe(w))
        os.close(w)
        self.pid = pid
        self._conn = _Pipe(r)
        threading.Thread(target=self._receive, name=f"child-{pid}", daemon=True).start()
        return self

    def _receive(self) -> None:
        try:
            while True:
                kind, value = self._conn.recv()
                if kind == "progress":
                    self._on_progress(value)
                    continue
                if kind == "ok":
                    self._on_result(value)
                self._outcome = (kind, value)
                return
        except (EOFError, OSError):
            self._outcome = ("error", ChildFailed("the child process ended without a result"))
        finally:
            self._done.set()
            self._on_end()

    def failure(self) -> BaseException | None:
        """The child's exception once it has failed, else None."""
        outcome = self._outcome
        return outcome[1] if outcome is not None and outcome[0] != "ok" else None

    def result(self, cancel: CancelToken | None = None) -> Any:
        """The child's value; its exception re-raised. ``cancel`` is checked while waiting: once
        set, the child is killed and CancelledError raised."""
        while not self._done.wait(0.2):
            if cancel is not None and cancel.is_set():
                self.kill()
                check_cancel(cancel)
        kind, value = self._outcome
        if kind != "ok":
            raise value
        return value

    def kill(self) -> None:
        if self.pid:
            try:
                os.kill(self.pid, signal.SIGKILL)
            except ProcessLookupError:
                pass

    def __exit__(self, exc_type, *exc) -> None:
        if exc_type is not None or not self._done.is_set():
            self.kill()
        try:
            os.waitpid(self.pid, 0)
        except ChildProcessError:
            pass
        self._done.wait(5.0)
        self._conn.close()


def _die_with_parent() -> None:
    """Linux: the kernel kills this process when its parent dies (a killed worker leaves no child
    working on for nobody); elsewhere the child ends when it finds the pipe closed."""
    try:
        ctypes.CDLL(None, use_errno=True).prctl(_PR_SET_PDEATHSIG, signal.SIGKILL)
    except (OSError, AttributeError):
        pass


def _run_child(fn: Callable, conn: _Pipe) -> None:
    """The forked child's whole life: run ``fn``, send its outcome, exit without the parent's
    clean-up (atexit handlers, buffered files and threads belong to the parent)."""
    status = 0
    last = [-1.0]
    _die_with_parent()

    def report(fraction: float) -> None:
        if fraction - last[0] >= 0.01 or fraction >= 1.0:
            last[0] = fraction
            conn.send(("progress", float(fraction)))

    try:
        try:
            conn.send(("ok", fn(report)))
        except BaseException as exc:  # noqa: BLE001 - every failure goes back to the parent
            status = 1
            try:
                conn.send(("error", exc))
            except Exception:  # not picklable: its text
                conn.send(("error", ChildFailed("".join(traceback.format_exception_only(exc)).strip())))
        conn.close()
    finally:
        os._exit(status)
