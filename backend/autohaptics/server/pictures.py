"""A project's pictures on disk: shot posters (``posters/<tick>.jpg``) and filmstrip tiles
(``filmstrip/<step>-<tile>.jpg``), made on demand in the server (:meth:`Pictures.poster`, :meth:`Pictures.tile`: a request's worker
thread, at once) and ahead in a separate low-priority process (:mod:`.ahead`), bounded per project
(oldest files evicted, the ahead files counted too), gone with the project.

Filmstrip: frames ``FRAME_H`` px high at the active picture's aspect, ``PER_TILE`` to a tile side by
side; frame k of tile i at step s is the picture at tick (PER_TILE i + k) s; steps 1, 2, 4, ... up to
the first power of two >= n_ticks / PER_TILE (the whole film in one tile).

Ahead (:meth:`Pictures.ahead`: after a job, when a timeline is opened): the shots' similarity
features, the filmstrip steps of at most ``AHEAD_FRAMES`` frames, coarsest first, then every
shot's poster. A server thread plans them and hands the process one picture at a time: it waits
while any generation job is queued or running, and stops (the picture in progress left unmade)
when the server stops or the project goes (:meth:`Pictures.forget`).
"""

from __future__ import annotations

import logging
import os
import threading
from collections import deque
from collections.abc import Callable
from pathlib import Path

from autohaptics.server import posters
from autohaptics.server.ahead import AheadMaker, MakerGone
from autohaptics.server.shots import features_of, poster_ticks
from autohaptics.server.store import NotFound, file_key

log = logging.getLogger("autohaptics.server.pictures")

PER_TILE = 16
FRAME_H = 45  # px
AHEAD_FRAMES = 1024  # the background makes the filmstrip steps of at most this many frames
FOLDERS = ("posters", "filmstrip")


def steps(n_ticks: int) -> list[int]:
    """The filmstrip's steps (ticks between frames): 1, 2, 4, ... up to one tile for the film."""
    out = [1]
    while out[-1] * PER_TILE < n_ticks:
        out.append(out[-1] * 2)
    return out


def n_tiles(n_ticks: int, step: int) -> int:
    return -(-int(n_ticks) // (PER_TILE * int(step)))


def frame_width(film: posters.Film) -> int:
    """A filmstrip frame's width (px): ``FRAME_H`` high at the active picture's aspect."""
    return max(2, round(FRAME_H * film.aspect))


def tile_ticks(n_ticks: int, step: int, tile: int) -> list[int]:
    """The ticks of a tile's frames (fewer than ``PER_TILE`` in the film's last tile)."""
    first = PER_TILE * tile * step
    return list(range(first, min(first + PER_TILE * step, n_ticks), step))


class Pictures:
    """The picture files of every project under ``store``; ``busy()`` says when to wait (a job runs)."""

    def __init__(self, store, composer, *, bound_bytes: int, busy: Callable[[], bool],
                 mp_context: str = "spawn"):
        self.store, self.composer, self.bound, self.busy = store, composer, int(bound_bytes), busy
        self.maker = AheadMaker(mp_context)  # the process started on the first picture made ahead
        self._lock = threading.Condition()
        self._files: dict[Path, threading.Lock] = {}
        self._used: dict[str, int] = {}  # bytes on disk per project, counted from a scan
        self._films: dict[str, tuple[tuple, posters.Film]] = {}
        self._queue: deque[str] = deque()
        self._current: str | None = None
        self._cancelled: set[str] = set()
        self._planned: dict[str, tuple] = {}  # the state each project's pictures were last made ahead for
        self._stop = False
        self._thread = threading.Thread(target=self._run, name="pictures", daemon=True)
        self._thread.start()

    # ------------------------------------------------------------------ on demand
    def film(self, pid: str) -> posters.Film:
        project = self.store.get_project(pid)
        media_path, analysis_path = self.store.media_path(project), self.store.analysis_path(pid)
        key = tuple(file_key(p) for p in (media_path, analysis_path))
        with self._lock:
            hit = self._films.get(pid)
        if hit is not None and hit[0] == key:
            return hit[1]
        made = posters.film(media_path, analysis_path)
        with self._lock:
            self._films[pid] = (key, made)
        return made

    def n_ticks(self, pid: str) -> int:
        return self.composer.require_generated(pid).n_ticks

    def geometry(self, pid: str) -> dict:
        """``{frame_w, frame_h, per_tile, steps}`` of the project's filmstrip."""
        n = self.n_ticks(pid)
        return {"frame_w": frame_width(self.film(pid)), "frame_h": FRAME_H,
                "per_tile": PER_TILE, "steps": steps(n)}

    def poster(self, pid: str, tick: int, *, cancel: Callable[[], bool] = lambda: False) -> bytes:
        """The poster JPEG of ``tick`` (NotFound outside the timeline)."""
        n = self.n_ticks(pid)
        if not 0 <= tick < n:
            raise NotFound(f"tick {tick} is not in this film's timeline (0..{n - 1})")

        def make() -> bytes:
            film = self.film(pid)
            return posters.picture_jpeg(film, [tick], posters.poster_size(film), cancel=cancel)
        return self._file(pid, "posters", f"{tick}.jpg", make)

    def tile(self, pid: str, step: int, tile: int, *, cancel: Callable[[], bool] = lambda: False) -> bytes:
        """The filmstrip tile JPEG (NotFound for a step not in the list or a tile past the end)."""
        geo = self.geometry(pid)
        n = self.n_ticks(pid)
        if step not in geo["steps"]:
            raise NotFound(f"step {step} is not one of this filmstrip's steps ({', '.join(map(str, geo['steps']))})")
        if not 0 <= tile < n_tiles(n, step):
            raise NotFound(f"tile {tile} is not in this filmstrip at step {step} (0..{n_tiles(n, step) - 1})")

        return self._file(pid, "filmstrip", f"{step}-{tile}.jpg", lambda: posters.picture_jpeg(
            self.film(pid), tile_ticks(n, step, tile), (geo["frame_w"], FRAME_H), cancel=cancel))

    def _file(self, pid: str, folder: str, name: str, make: Callable[[], bytes]) -> bytes:
        """The bytes of a picture file, made (once, by one maker) when it is not on disk."""
        path = self.store.project_dir(pid) / folder / name
        data = _read(path)
        if data is not None:
            return data
        with self._lock:
            gate = self._files.setdefault(path, threading.Lock())
        with gate:
            data = _read(path)
            if data is None:
                data = make()
                self._write(pid, path, data)
        with self._lock:
            self._files.pop(path, None)
        return data

    def _write(self, pid: str, path: Path, data: bytes) -> None:
        if not posters.write(path, data):
            raise NotFound(f"project {pid} was removed")
        self._count(pid, len(data))

    def _count(self, pid: str, size: int) -> None:
        """Count a new picture file of ``size`` bytes; trim the project's files past the bound."""
        with self._lock:
            used = self._used.get(pid)
            self._used[pid] = (used if used is not None else 0) + size
            over = used is None or self._used[pid] > self.bound
        if over:
            self._trim(pid)

    def _trim(self, pid: str) -> None:
        """Count the project's picture files and remove the oldest while they pass the bound (down
        to 90 % of it, so a full cache does not trim at every new file)."""
        files = []
        for folder in FOLDERS:
            try:
                entries = list(os.scandir(self.store.project_dir(pid) / folder))
            except FileNotFoundError:
                continue
            for entry in entries:
                try:
                    st = entry.stat()
                except FileNotFoundError:
                    continue
                if entry.name.endswith(".jpg"):
                    files.append((st.st_mtime_ns, entry.path, st.st_size))
        used = sum(f[2] for f in files)
        if used > self.bound:
            for _, path, size in sorted(files):
                if used <= 0.9 * self.bound:
                    break
                Path(path).unlink(missing_ok=True)
                used -= size
        with self._lock:
            self._used[pid] = used

    def used_bytes(self, pid: str) -> int:
        """Bytes of the project's picture files as last counted."""
        with self._lock:
            return self._used.get(pid, 0)

    # ------------------------------------------------------------------ ahead
    def ahead(self, pid: str) -> None:
        """Make the project's coarse filmstrip steps and its posters in the background (soon)."""
        with self._lock:
            self._cancelled.discard(pid)
            if pid not in self._queue:
                self._queue.append(pid)
                self._lock.notify_all()

    def forget(self, pid: str) -> None:
        """Stop making the project's pictures and wait until none is being made (before its folder
        goes): the picture in progress is left unmade, or its process killed after 10 s."""
        with self._lock:
            self._cancelled.add(pid)
            if pid in self._queue:
                self._queue.remove(pid)
            if self._current == pid:
                self.maker.cancel()
            self._lock.notify_all()
            if not self._lock.wait_for(lambda: self._current != pid, timeout=10.0):
                log.warning("project %s: the picture process did not stop in 10 s; killed", pid)
                self.maker.kill()
                self._lock.wait_for(lambda: self._current != pid, timeout=10.0)
            for table in (self._used, self._films, self._planned):
                table.pop(pid, None)

    def wait_idle(self, timeout_s: float = 60.0) -> bool:
        """True once nothing is queued or being made ahead (within ``timeout_s``)."""
        with self._lock:
            return self._lock.wait_for(lambda: not self._queue and self._current is None, timeout=timeout_s)

    def close(self) -> None:
        """Stop making pictures ahead and stop the picture process."""
        with self._lock:
            self._stop = True
            self.maker.cancel()
            self._lock.notify_all()
        self._thread.join(timeout=15.0)
        self.maker.close()

    def _run(self) -> None:
        while True:
            with self._lock:
                self._lock.wait_for(lambda: self._stop or self._queue)
                if self._stop:
                    return
                pid = self._current = self._queue.popleft()
            try:
                self._make_ahead(pid)
            except MakerGone as exc:  # started again for the next project that asks
                log.warning("project %s: pictures not made ahead (%s)", pid, exc)
            except Exception as exc:  # a request for the same picture reports it
                log.info("project %s: pictures not made ahead (%s)", pid, exc)
            finally:
                with self._lock:
                    self._current = None
                    self._lock.notify_all()

    def _stopped(self, pid: str) -> bool:
        return self._stop or pid in self._cancelled

    def _make_ahead(self, pid: str) -> None:
        composed = self.composer.compose(pid)
        analysis = self.composer.analysis(pid)
        state = (composed.revision, file_key(self.store.analysis_path(pid)))
        with self._lock:
            if self._planned.get(pid) == state:
                return
        if analysis is not None:
            features_of(pid, analysis, composed)  # a shot's similar shots then answer at once
        n = composed.timeline.n_ticks
        film, folder = self.film(pid), self.store.project_dir(pid)
        frame = (frame_width(film), FRAME_H)
        work = [(folder / "filmstrip" / f"{s}-{t}.jpg", tile_ticks(n, s, t), frame)
                for s in reversed(steps(n)) if -(-n // s) <= AHEAD_FRAMES for t in range(n_tiles(n, s))]
        if analysis is not None:
            size = posters.poster_size(film)
            work += [(folder / "posters" / f"{tick}.jpg", [tick], size) for tick in poster_ticks(analysis, composed)]
        for path, ticks, size in work:
            while self.busy() and not self._stopped(pid):
                with self._lock:
                    self._lock.wait_for(lambda: self._stopped(pid), timeout=0.5)
            with self._lock:
                if self._stopped(pid):
                    return
                self.maker.arm()  # under the lock: a forget() now cancels this picture
            if path.exists():
                continue
            made = self.maker.make(path, film, ticks, size)
            if made is None:  # cancelled, or the project's folder is gone
                return
            self._count(pid, made)
        with self._lock:
            self._planned[pid] = state


def _read(path: Path) -> bytes | None:
    try:
        return path.read_bytes()
    except FileNotFoundError:
        return None
