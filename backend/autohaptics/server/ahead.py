"""The process that makes a server's pictures ahead (:class:`AheadMaker`): spawned on first use,
one per server, at the lowest CPU priority (``os.nice(19)`` before it imports or decodes anything,
so its decoder threads inherit it), one picture per request. Decoding there never holds the
server's GIL, so the server's answers do not wait for a process the kernel gives the least CPU.

The child writes through :func:`autohaptics.server.posters.write` (temporary file and rename, the
project's folder never made): a removed project stays removed. It exits with its parent.
"""

from __future__ import annotations

import multiprocessing
import os
import threading
import time
from pathlib import Path
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from autohaptics.server.posters import Film


class MakerGone(Exception):
    """The picture process died in the middle of a picture (it is started again on the next one)."""


class AheadMaker:
    """The parent's handle on the picture process. ``pause_s`` is a test hook: the child waits that
    long before it writes each picture, so a test can act while a picture is on its way."""

    def __init__(self, mp_context: str = "spawn"):
        self.ctx = multiprocessing.get_context(mp_context)
        self.pause_s = 0.0
        self._lock = threading.Lock()  # one picture at a time
        self._proc = None
        self._conn = None
        self._cancel = self.ctx.Event()

    @property
    def pid(self) -> int | None:
        """The process id of the child (None before the first picture and after it stops)."""
        proc = self._proc
        return proc.pid if proc is not None else None

    def arm(self) -> None:
        """Let the next picture be made (clears :meth:`cancel`)."""
        self._cancel.clear()

    def cancel(self) -> None:
        """Leave the picture being made unmade (:meth:`make` answers None) until :meth:`arm`."""
        self._cancel.set()

    def make(self, path: Path, film: "Film", ticks: list[int], size: tuple[int, int]) -> int | None:
        """Make the frames of ``ticks`` at ``size`` (w, h px) side by side into ``path`` in the child:
        the bytes written; None when cancelled or the project's folder is gone. Raises
        :class:`MakerGone` when the child dies, during this picture or since the one before (the
        next call starts a new one), RuntimeError with its message when the picture fails."""
        with self._lock:
            if self._proc is not None and not self._proc.is_alive():
                code = self._proc.exitcode
                self._drop()
                raise MakerGone(f"the picture process stopped (exit code {code}, between pictures)")
            try:
                if self._proc is None:
                    self._start()
                self._conn.send((str(path), film, [int(t) for t in ticks], tuple(size), float(self.pause_s)))
                kind, value = self._conn.recv()
            except (EOFError, OSError) as exc:
                code = self._proc.exitcode if self._proc is not None else None
                self._drop()
                raise MakerGone(f"the picture process stopped (exit code {code}; {type(exc).__name__})") from None
        if kind == "error":
            raise RuntimeError(value)
        return value

    def kill(self) -> None:
        """Stop the child at once (a :meth:`make` in progress raises :class:`MakerGone`)."""
        proc = self._proc
        if proc is not None and proc.is_alive():
            proc.kill()

    def close(self, timeout_s: float = 5.0) -> None:
        """Stop the child (asked, then killed after ``timeout_s``) and wait for it."""
        self.cancel()
        if not self._lock.acquire(timeout=timeout_s):  # a picture that does not stop
            self.kill()  # its make() raises MakerGone and lets go
            self._lock.acquire()
        try:
            if self._proc is not None:
                try:
                    self._conn.send(None)
                except OSError:
                    pass
                self._proc.join(timeout_s)
            self._drop()
        finally:
            self._lock.release()

    def _start(self) -> None:
        self._drop()
        mine, theirs = self.ctx.Pipe()
        proc = self.ctx.Process(target=serve, args=(theirs, self._cancel, os.getpid()),
                                name="autohaptics-pictures", daemon=True)
        proc.start()
        theirs.close()  # the child's end lives in the child only: its death ends our recv
        self._proc, self._conn = proc, mine

    def _drop(self) -> None:
        if self._proc is not None:
            if self._proc.is_alive():
                self._proc.kill()
            self._proc.join(5.0)
        if self._conn is not None:
            self._conn.close()
        self._proc = self._conn = None


def serve(conn, cancel, parent_pid: int) -> None:
    """The child: answer ``(path, film, ticks, size, pause_s)`` requests with ``("ok", bytes
    written or None)`` or ``("error", message)`` until None or the pipe closes."""
    os.nice(19)
    from autohaptics.runner.worker import init_worker
    from autohaptics.server import posters

    init_worker(parent_pid, ignore_term=True)  # the server stops this process itself
    while True:
        try:
            request = conn.recv()
        except (EOFError, OSError):
            return
        if request is None:
            return
        path, film, ticks, size, pause_s = request
        try:
            data = posters.picture_jpeg(film, ticks, size, cancel=cancel.is_set)
            time.sleep(pause_s)
            written = None if cancel.is_set() or not posters.write(Path(path), data) else len(data)
            answer = ("ok", written)
        except posters.Cancelled:
            answer = ("ok", None)
        except Exception as exc:  # noqa: BLE001 - the parent logs it; the next picture may do
            answer = ("error", f"{type(exc).__name__}: {exc}")
        try:
            conn.send(answer)
        except OSError:
            return
