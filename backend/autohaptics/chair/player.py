"""Live playback on the chair, in step with the browser's video.

A :class:`ChairPlayer` owns a 10 Hz clock. The caller reports what the viewer does
(:meth:`~ChairPlayer.play`, :meth:`~ChairPlayer.pause`, :meth:`~ChairPlayer.seek` with the video
position in seconds); between reports the player extrapolates the position with
``time.monotonic`` and sends the frame of each tick when the position reaches it:

- tick sent at wall time t: ``floor((position(t) + latency_offset) / 0.1)``. A positive
  ``latency_offset_ms`` (-500..+500) sends every tick earlier, for a chair that responds late.
- while playing, ticks are consecutive (no duplicates, no gaps); a seek, a play or a reconnect
  sends the current tick at once and continues from there. If the process stalls for more than
  ``MAX_CATCH_UP_TICKS`` ticks, the player jumps to the current tick (counted in
  ``ticks_skipped``) rather than replaying stale ones in a burst.
- pause and stop send STOP (all outputs off now; the chair's temperature returns to neutral at
  its slew rate); the position is kept. At the end of the timeline (or of ``play(until_s=)``)
  the player sends STOP and enters "ended".

:func:`push` plays a range of a timeline to the chair, paced at 10 Hz, and blocks until done.
"""

from __future__ import annotations

import math
import os
import threading
import time
from collections.abc import Callable
from dataclasses import asdict, dataclass

from autohaptics.chair.comfort import Comfort, compose_frame
from autohaptics.chair.link import ChairLink
from autohaptics.errors import DeviceError, ParameterError
from autohaptics.progress import CancelToken, ProgressFn, check_cancel
from autohaptics.timebase import TICK_S
from autohaptics.timeline import Timeline

MAX_CATCH_UP_TICKS = 2
CLOCK_NICE = -10  # the clock thread's nice value when the process may raise it (CAP_SYS_NICE)
LATENCY_OFFSET_RANGE_MS = (-500.0, 500.0)
_EPS = 1e-9


@dataclass(frozen=True)
class PlayerStatus:
    state: str  # "idle" | "playing" | "paused" | "stopped" | "ended"
    position_s: float
    duration_s: float | None
    tick: int | None  # last tick sent
    frames_sent: int
    frames_dropped: int  # ticks due while the link was down
    ticks_skipped: int
    latency_offset_ms: float
    comfort: dict
    error: str | None  # why playback stopped on its own, if it did
    clock_priority: str  # "nice -10" when the clock thread could raise its priority, else "normal"
    link: dict

    def to_dict(self) -> dict:
        return asdict(self)


def check_latency_offset_ms(value: float) -> float:
    lo, hi = LATENCY_OFFSET_RANGE_MS
    try:
        v = float(value)
    except (TypeError, ValueError):
        raise ParameterError(f"latency offset must be a number of milliseconds, got {value!r}") from None
    if not math.isfinite(v) or not lo <= v <= hi:
        raise ParameterError(f"latency offset must be within {lo:g}..{hi:g} ms, got {value!r}")
    return v


def _check_position(position_s: float) -> float:
    try:
        v = float(position_s)
    except (TypeError, ValueError):
        raise ParameterError(f"position must be a number of seconds, got {position_s!r}") from None
    if not math.isfinite(v) or v < 0:
        raise ParameterError(f"position must be a finite number of seconds >= 0, got {position_s!r}")
    return v


class ChairPlayer:
    """Streams a timeline to a :class:`ChairLink` in step with playback. Thread-safe; call
    :meth:`close` (or use ``with``) to stop its thread."""

    def __init__(self, link: ChairLink, timeline: Timeline | None = None, *, comfort: Comfort | None = None,
                 latency_offset_ms: float = 0.0, clock_nice: int | None = CLOCK_NICE):
        self._link = link
        self._timeline = timeline.validate() if timeline is not None else None
        self._comfort = comfort if comfort is not None else Comfort()
        self._offset_s = check_latency_offset_ms(latency_offset_ms) / 1000.0
        self._clock_nice = clock_nice
        self._clock_priority = "normal"
        self._cv = threading.Condition()
        self._send_lock = threading.Lock()  # one frame or STOP on the wire at a time, in decision order
        self._state = "idle"
        self._anchor_pos = 0.0
        self._anchor_t = time.monotonic()
        self._next_tick = 0
        self._until_tick: int | None = None
        self._last_tick: int | None = None
        self._frames_sent = 0
        self._frames_dropped = 0
        self._skipped = 0
        self._error: str | None = None
        self._gen = 0  # bumped by every command, so the clock thread never overrides a newer one
        self._closed = False
        self._unsubscribe = link.on("connected", self._on_connected)
        self._thread = threading.Thread(target=self._run, name=f"chair-player {link.port}", daemon=True)
        self._thread.start()

    # ---------------------------------------------------------------- commands
    def set_timeline(self, timeline: Timeline) -> None:
        """Replace the timeline (e.g. after an edit); while playing, the current tick is resent."""
        timeline.validate()
        with self._cv:
            self._timeline = timeline
            self._resync()

    def play(self, position_s: float | None = None, *, until_s: float | None = None) -> None:
        """Start (or continue) at ``position_s`` (default: the current position); stop at ``until_s``."""
        with self._cv:
            if self._timeline is None:
                raise ParameterError("no timeline loaded: call set_timeline() before play()")
            now = time.monotonic()
            pos = self._position_at(now) if position_s is None else _check_position(position_s)
            if until_s is not None:
                until = _check_position(until_s)
                self._until_tick = max(0, math.ceil(until / TICK_S - 1e-6))
            else:
                self._until_tick = None
            self._anchor_pos, self._anchor_t = pos, now
            self._state = "playing"
            self._next_tick = max(0, self._tick_at(now))
            self._gen += 1
            self._cv.notify_all()

    def pause(self, position_s: float | None = None) -> None:
        """Hold at ``position_s`` (default: now); the chair's outputs go off (STOP)."""
        with self._send_lock:
            with self._cv:
                now = time.monotonic()
                self._anchor_pos = self._position_at(now) if position_s is None else _check_position(position_s)
                self._anchor_t = now
                was_playing = self._state == "playing"
                if self._state in ("playing", "idle", "ended", "stopped"):
                    self._state = "paused"
                self._gen += 1
                self._cv.notify_all()
            if was_playing:
                self._link.send_stop()

    def seek(self, position_s: float) -> None:
        """Jump to ``position_s``; while playing, its tick is sent at once."""
        pos = _check_position(position_s)
        with self._cv:
            now = time.monotonic()
            self._anchor_pos, self._anchor_t = pos, now
            if self._state == "ended":
                self._state = "paused"
            self._resync()

    def sync(self, position_s: float) -> float:
        """Correct the clock to a reported video position while playing, without resending or
        skipping ticks: the next tick goes out when the corrected clock reaches it (a clock that
        ran ahead waits, one that fell behind catches up like after a stall). Returns the drift
        in seconds (reported minus extrapolated position). When not playing this is a seek.

        Meant for small drifts (the browser's once-a-second reports); a clock that ran ahead by
        more than the chair's watchdog (300 ms) would leave it without frames meanwhile, so the
        caller seeks instead when the drift is large.
        """
        pos = _check_position(position_s)
        with self._cv:
            if self._state != "playing":
                drift = pos - self._anchor_pos
            else:
                now = time.monotonic()
                drift = pos - self._position_at(now)
                self._anchor_pos, self._anchor_t = pos, now
                self._gen += 1
                self._cv.notify_all()
                return drift
        self.seek(pos)
        return drift

    def stop(self) -> None:
        """STOP now: every output off; playback stops and keeps its position."""
        with self._send_lock:
            with self._cv:
                now = time.monotonic()
                self._anchor_pos, self._anchor_t = self._position_at(now), now
                self._state = "stopped"
                self._gen += 1
                self._cv.notify_all()
            self._link.send_stop()

    def set_comfort(self, comfort: Comfort) -> None:
        if not isinstance(comfort, Comfort):
            raise ParameterError(f"comfort must be a Comfort, got {type(comfort).__name__}")
        with self._cv:
            self._comfort = comfort

    def set_latency_offset_ms(self, offset_ms: float) -> None:
        """Change the latency offset (-500..+500 ms); while playing this re-anchors like a seek."""
        value = check_latency_offset_ms(offset_ms) / 1000.0
        with self._cv:
            self._offset_s = value
            self._resync()

    def wait(self, timeout_s: float | None = None) -> bool:
        """Block until playback is no longer running (ended, paused, stopped); False on timeout."""
        with self._cv:
            return self._cv.wait_for(lambda: self._state != "playing" or self._closed, timeout_s)

    def close(self) -> None:
        """Stop the clock thread; sends STOP if it was playing."""
        with self._cv:
            if self._closed:
                return
            was_playing = self._state == "playing"
            self._closed = True
            self._cv.notify_all()
        self._thread.join(5.0)
        self._unsubscribe()
        if was_playing:
            with self._send_lock:
                self._link.send_stop()

    def __enter__(self) -> "ChairPlayer":
        return self

    def __exit__(self, *exc) -> None:
        self.close()

    # ------------------------------------------------------------------ reads
    @property
    def state(self) -> str:
        return self._state

    @property
    def position_s(self) -> float:
        with self._cv:
            return self._position_at(time.monotonic())

    def status(self) -> PlayerStatus:
        link = self._link.status().to_dict()  # not under our lock: the link's listeners take it
        with self._cv:
            tl = self._timeline
            return PlayerStatus(
                state=self._state, position_s=self._position_at(time.monotonic()),
                duration_s=tl.duration_s if tl is not None else None, tick=self._last_tick,
                frames_sent=self._frames_sent, frames_dropped=self._frames_dropped, ticks_skipped=self._skipped,
                latency_offset_ms=self._offset_s * 1000.0, comfort=self._comfort.to_dict(), error=self._error,
                clock_priority=self._clock_priority, link=link)

    # ---------------------------------------------------------------- private
    def _position_at(self, now: float) -> float:
        if self._state == "playing":
            return self._anchor_pos + (now - self._anchor_t)
        return self._anchor_pos

    def _tick_at(self, now: float) -> int:
        return math.floor((self._position_at(now) + self._offset_s) / TICK_S + _EPS)

    def _due(self, tick: int) -> float:
        """Wall time (monotonic) when the clock reaches ``tick``."""
        return self._anchor_t + (tick * TICK_S - self._offset_s - self._anchor_pos)

    def _end_tick(self) -> int:
        n = self._timeline.n_ticks if self._timeline is not None else 0
        return n if self._until_tick is None else min(n, self._until_tick)

    def _resync(self) -> None:
        """Re-anchor the clock: the current tick goes out next, now. Caller holds the lock."""
        now = time.monotonic()
        if self._state == "playing":
            self._anchor_pos, self._anchor_t = self._position_at(now), now
            self._next_tick = max(0, self._tick_at(now))
        self._gen += 1
        self._cv.notify_all()

    def _on_connected(self, hello) -> None:
        with self._cv:
            self._resync()

    def _run(self) -> None:
        self._clock_priority = _raise_thread_priority(self._clock_nice)
        while True:
            with self._cv:
                while True:
                    if self._closed:
                        return
                    if self._state != "playing":
                        self._cv.wait()
                        continue
                    wait = self._due(self._next_tick) - time.monotonic()
                    if wait > 0:
                        self._cv.wait(min(wait, 0.25))
                        continue
                    break
            try:
                self._tick()
            except Exception as exc:  # never die silently with the chair running
                with self._cv:
                    self._error = f"{type(exc).__name__}: {exc}"
                    self._state = "stopped"
                    self._cv.notify_all()
                self._link.send_stop()

    def _tick(self) -> None:
        with self._send_lock:
            with self._cv:
                if self._closed or self._state != "playing":
                    return
                now = time.monotonic()
                k = self._next_tick
                if self._due(k) > now:  # moved by a seek in the meantime
                    return
                current = self._tick_at(now)
                if current - k > MAX_CATCH_UP_TICKS:  # stalled: jump to now, count what was not sent
                    target = max(k, min(current, self._end_tick()))
                    self._skipped += target - k
                    k = target
                gen = self._gen
                if k >= self._end_tick():
                    frame = None
                else:
                    frame = compose_frame(self._timeline, k, comfort=self._comfort, profile=self._link.profile)
                    self._next_tick = k + 1
            if frame is None:  # the end: STOP goes out before anyone sees "ended"
                self._link.send_stop()
                with self._cv:
                    if self._gen == gen and self._state == "playing":
                        self._state = "ended"
                        self._anchor_pos, self._anchor_t = self._end_tick() * TICK_S, time.monotonic()
                        self._cv.notify_all()
                return
            ok = self._link.send_frame(frame)
            with self._cv:
                if ok:
                    self._frames_sent += 1
                    self._last_tick = frame.tick
                else:
                    self._frames_dropped += 1


def _raise_thread_priority(nice: int | None) -> str:
    """Best effort: give the calling thread nice value ``nice`` so a busy machine (a browser
    decoding video) delays the 10 Hz clock less. Needs CAP_SYS_NICE for negative values; without
    it the thread keeps its priority. Linux applies the nice value of a thread id to that thread."""
    if nice is None or not hasattr(os, "setpriority"):
        return "normal"
    try:
        os.setpriority(os.PRIO_PROCESS, threading.get_native_id(), int(nice))
    except OSError:
        return "normal"
    return f"nice {int(nice)}"


def start_range(link: ChairLink, timeline: Timeline, *, start_s: float = 0.0, end_s: float | None = None,
                comfort: Comfort | None = None) -> tuple[ChairPlayer, float, float]:
    """A player already playing ``[start_s, end_s)`` of ``timeline`` (end default: the timeline's),
    with the range it plays. Whoever holds the player can stop it at once (:meth:`ChairPlayer.stop`:
    no frame of the range follows the STOP)."""
    if not link.connected:
        raise DeviceError(f"chair link {link.port} is not connected")
    timeline.validate()
    start = _check_position(start_s)
    end = timeline.duration_s if end_s is None else min(_check_position(end_s), timeline.duration_s)
    if start >= end:
        raise ParameterError(f"push range is empty: start {start:g} s, end {end:g} s "
                             f"(timeline is {timeline.duration_s:g} s)")
    player = ChairPlayer(link, timeline, comfort=comfort)
    try:
        player.play(start, until_s=end)
    except BaseException:
        player.close()
        raise
    return player, start, end


def follow_range(player: ChairPlayer, start: float, end: float, *, progress: ProgressFn | None = None,
                 cancel: CancelToken | None = None) -> PlayerStatus:
    """Wait for a player of :func:`start_range` to finish, reporting progress; close it (STOP when it
    was still playing). CancelledError on cancel, also when the player was stopped for it."""
    report: Callable[[str, float], None] = progress or (lambda stage, fraction: None)
    try:
        while not player.wait(0.1):
            check_cancel(cancel)
            report("push", min(1.0, (player.position_s - start) / (end - start)))
        check_cancel(cancel)
        report("push", 1.0)
        return player.status()
    finally:
        player.close()


def push(link: ChairLink, timeline: Timeline, *, start_s: float = 0.0, end_s: float | None = None,
         comfort: Comfort | None = None, progress: ProgressFn | None = None,
         cancel: CancelToken | None = None) -> PlayerStatus:
    """Play ``timeline`` from ``start_s`` to ``end_s`` (default: its end) on a connected chair,
    paced at 10 Hz; block until done and return the final status. STOP is sent at the end, on
    cancel (CancelledError) and on any error."""
    player, start, end = start_range(link, timeline, start_s=start_s, end_s=end_s, comfort=comfort)
    return follow_range(player, start, end, progress=progress, cancel=cancel)
