"""The chair service: one per application (``app.state.chair``), started and stopped with its lifespan.

It owns at most one :class:`~autohaptics.chair.ChairLink` (which reconnects by itself) and its
:class:`~autohaptics.chair.ChairPlayer`, and turns what the routes receive into chair commands:

- :meth:`ChairService.connect` handshakes with a port; :meth:`~ChairService.disconnect` sends STOP
  and closes it.
- :meth:`~ChairService.playback` takes the browser's reports (play, pause, seek, with the video
  position). The player's own 10 Hz clock sends the frames of the project's composed timeline
  (generated + edits at the current revision). A report while playing corrects the clock's drift
  without resending or skipping ticks (:meth:`ChairPlayer.sync`); a drift beyond
  ``DRIFT_SEEK_S`` is a seek. A ``heartbeat`` (once a second while the video plays) never starts
  playback; an ``initial`` report (a page connecting) never stops a running push.
- A monitor thread follows the project's revision (an edit, undo, a re-derive, a finished job)
  and hands the new composed timeline to the player; it also publishes the status to the SSE
  subscribers, at once on a change and at least every ``STATUS_INTERVAL_S``.
- :meth:`~ChairService.stop`: STOP now, every output off; it also cancels a push and any playback
  command that was still under way.
- :meth:`~ChairService.update_settings`: latency offset and comfort, stored in the database
  (``settings`` row ``chair``) and applied to the running player.
- :meth:`~ChairService.push`: a range of a timeline played by :func:`autohaptics.chair.push` in a
  thread; its progress is part of the status.

Temperature is clamped to the chair's safe range (from its HELLO) by
:func:`autohaptics.chair.compose_frame`; the chair clamps again on its side.
"""

from __future__ import annotations

import logging
import math
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

from autohaptics.chair import ChairLink, ChairPlayer, DeviceProfile, follow_range, list_ports, start_range
from autohaptics.errors import AutohapticsError, CancelledError, ParameterError
from autohaptics.server.chair_settings import (
    SETTINGS_KEY,
    diagnostics,
    merge_settings,
    settings_to_comfort,
    signature,
    stored_settings,
)
from autohaptics.server.sse import Subscribers, Subscription
from autohaptics.server.store import Conflict, NotFound, Store
from autohaptics.server.composer import Composer

log = logging.getLogger("autohaptics.server.chair")

STATUS_INTERVAL_S = 0.5  # the SSE status cadence while nothing changes
POLL_S = 0.1  # how often the monitor looks at the project's revision and the status
DRIFT_SEEK_S = 0.15  # a reported position further than this from the chair's clock is a seek
QUEUE_SIZE = 16  # status events kept for a slow SSE client (older ones are dropped)
@dataclass
class _Push:
    project_id: str
    start_s: float
    end_s: float
    cancel: threading.Event
    state: str = "running"  # running | done | cancelled | failed
    progress: float = 0.0
    error: str | None = None
    thread: threading.Thread | None = None
    player: ChairPlayer | None = None  # plays the range; STOP stops it before answering

    def to_dict(self) -> dict:
        return {"project_id": self.project_id, "start_s": self.start_s, "end_s": self.end_s, "state": self.state,
                "progress": round(self.progress, 4), "error": self.error}


class ChairService:
    """The application's chair (see the module docstring). Thread-safe."""

    def __init__(self, store: Store, composer: Composer, *, link_options: dict | None = None):
        self.store = store
        self.composer = composer
        self._link_options = dict(link_options or {})
        self._lock = threading.RLock()  # short: the fields below; never held while composing or waiting
        self._commands = threading.Lock()  # one connect / disconnect / playback / push at a time
        self._link: ChairLink | None = None
        self._player: ChairPlayer | None = None
        self._unsubscribe: list[Callable[[], None]] = []
        self._project: str | None = None
        self._revision: int | None = None
        self._push: _Push | None = None
        self._error: str | None = None
        self._stops = 0  # STOPs so far: a command that started before a STOP is dropped
        self._drift_s: float | None = None
        self._drift_seeks = 0
        self._settings = stored_settings(store)
        self._subscribers = Subscribers(maxsize=QUEUE_SIZE)
        self._wake = threading.Event()
        self._closing = threading.Event()
        self._monitor: threading.Thread | None = None

    # ---------------------------------------------------------------- lifecycle
    def start(self) -> None:
        self._closing.clear()
        self._monitor = threading.Thread(target=self._run, name="chair-service", daemon=True)
        self._monitor.start()

    def close(self) -> None:
        """Disconnect (STOP first), stop the monitor, end the SSE streams."""
        self.disconnect()
        self._closing.set()
        self._wake.set()
        if self._monitor is not None:
            self._monitor.join(5.0)
            self._monitor = None
        self._subscribers.close_all()

    # ------------------------------------------------------------------- ports
    @staticmethod
    def ports() -> list[dict]:
        return [p.to_dict() for p in list_ports()]

    # -------------------------------------------------------------- connection
    def connect(self, port: str) -> dict:
        """Handshake with the chair on ``port`` (replacing the current connection); DeviceError when
        it cannot be opened or does not answer."""
        with self._commands:
            with self._lock:
                current = self._link
            if current is not None and current.port == port:
                return self.status()
            self._disconnect()
            link = ChairLink(port, **self._link_options)
            try:
                link.connect()
            except AutohapticsError as exc:
                with self._lock:
                    self._error = str(exc)
                self._wake.set()
                raise
            with self._lock:
                comfort, latency = settings_to_comfort(self._settings), self._settings["latency_ms"]
            player = ChairPlayer(link, None, comfort=comfort, latency_offset_ms=latency)
            unsubscribe = [link.on(event, self._on_link_event) for event in ("connected", "disconnected", "status")]
            with self._lock:
                self._link, self._player, self._unsubscribe = link, player, unsubscribe
                self._project = self._revision = None
                self._error = None
                self._drift_s, self._drift_seeks = None, 0
        self._wake.set()
        return self.status()

    def disconnect(self) -> dict:
        """STOP, then close the port (nothing happens when no chair is connected)."""
        with self._commands:
            self._disconnect()
        self._wake.set()
        return self.status()

    def _disconnect(self) -> None:
        with self._lock:
            link, player, unsubscribe, pushing = self._link, self._player, self._unsubscribe, self._push
            self._link = self._player = None
            self._unsubscribe = []
            self._project = self._revision = None
        if pushing is not None:
            pushing.cancel.set()
            if pushing.thread is not None:
                pushing.thread.join(5.0)
        for fn in unsubscribe:
            fn()
        if player is not None:
            player.close()
        if link is not None:
            link.close()

    def _on_link_event(self, *args: Any) -> None:
        self._wake.set()

    # ---------------------------------------------------------------- playback
    def playback(self, project_id: str, state: str, position_s: float, *, heartbeat: bool = False,
                 initial: bool = False) -> dict:
        """The browser's report: ``state`` play / pause / seek at ``position_s`` (seconds of video).

        A heartbeat only corrects the clock while the chair already plays this project. An initial
        report (where a page's player is when it connects: no viewer's action) leaves a running push
        alone; any other report stops it."""
        if not math.isfinite(position_s) or position_s < 0:
            raise ParameterError(f"position_s must be a finite number of seconds >= 0, got {position_s!r}")
        with self._lock:
            stops = self._stops
            player, pushing, current = self._player, self._push, self._project
        if player is None:
            raise Conflict("no chair is connected; connect one first")
        pushing_now = pushing is not None and pushing.state == "running"
        if (initial and pushing_now) or (heartbeat and (state != "play" or player.state != "playing"
                                                        or current != project_id or pushing_now)):
            return self.status()
        with self._commands:
            self._cancel_push()
            with self._lock:
                if self._player is not player:
                    raise Conflict("the chair was disconnected meanwhile")
                loaded = self._project == project_id and self._revision is not None
            if not loaded:
                self._load(player, project_id)
            with self._lock:
                if self._stops != stops:  # a STOP came in meanwhile: it wins
                    return self.status()
                if state == "play":
                    if player.state == "playing":
                        self._follow(player, position_s, report=True)
                    else:
                        player.play(position_s)
                elif state == "pause":
                    player.pause(position_s)
                elif state == "seek":
                    if player.state == "playing":
                        self._follow(player, position_s, report=False)
                    else:
                        player.seek(position_s)
                else:
                    raise ParameterError(f"state must be play, pause or seek, got {state!r}")
        self._wake.set()
        return self.status()

    def _follow(self, player: ChairPlayer, position_s: float, *, report: bool) -> None:
        """Move the playing clock to ``position_s``: a small drift is corrected without resending or
        skipping ticks, a larger one is a seek (the current tick goes out at once). ``report``: a
        play report (its drift is kept for the status), not a seek."""
        drift = position_s - player.position_s
        if abs(drift) <= DRIFT_SEEK_S:
            player.sync(position_s)
        else:
            player.seek(position_s)
        if report:
            self._drift_s = drift
            self._drift_seeks += abs(drift) > DRIFT_SEEK_S

    def _load(self, player: ChairPlayer, project_id: str) -> None:
        composed = self.composer.compose(project_id)
        player.set_timeline(composed.timeline)
        with self._lock:
            self._project, self._revision = project_id, composed.revision

    def _follow_revision(self) -> None:
        """Give the player the new composed timeline when the project's revision moved on."""
        with self._lock:
            pid, revision, player = self._project, self._revision, self._player
        if pid is None or player is None:
            return
        try:
            if self.store.revision(pid) == revision:
                return
            composed = self.composer.compose(pid)
        except NotFound as exc:  # the project (or its timeline) is gone: nothing left to play
            player.stop()
            with self._lock:
                if self._player is player and self._project == pid:
                    self._project = self._revision = None
                    self._error = f"playback stopped: {exc}"
            return
        with self._lock:
            if self._player is not player or self._project != pid:
                return
            player.set_timeline(composed.timeline)
            self._revision = composed.revision

    # -------------------------------------------------------------------- stop
    def stop(self) -> dict:
        """STOP now: every output off, playback stopped (position kept), a running push cancelled.

        Final: when this returns, the push's player has written its STOP after its last frame, so no
        frame of the push reaches the chair later, and the status says the push is cancelled."""
        with self._lock:
            self._stops += 1
            link, player, pushing = self._link, self._player, self._push
            if pushing is not None and pushing.state == "running":
                pushing.state = "cancelled"
                pushing.cancel.set()
            else:
                pushing = None
        if pushing is not None and pushing.player is not None:
            pushing.player.stop()
        if player is not None:
            player.stop()
        elif link is not None:
            link.send_stop()
        self._wake.set()
        return self.status()

    # ---------------------------------------------------------------- settings
    @property
    def settings(self) -> dict:
        with self._lock:
            return {"latency_ms": self._settings["latency_ms"],
                    "comfort": {"scale": self._settings["comfort"]["scale"],
                                "mute": dict(self._settings["comfort"]["mute"])}}

    def update_settings(self, *, latency_ms: float | None = None, scale: float | None = None,
                        mute: dict[str, bool] | None = None) -> dict:
        """Change and store the latency offset and comfort; the running player uses them at once."""
        with self._lock:
            doc = merge_settings(self._settings, latency_ms=latency_ms, scale=scale, mute=mute)
            self.store.put_setting(SETTINGS_KEY, doc)
            self._settings = doc
            player = self._player
        if player is not None:
            player.set_comfort(settings_to_comfort(doc))
            player.set_latency_offset_ms(doc["latency_ms"])
        self._wake.set()
        return self.settings

    # -------------------------------------------------------------------- push
    def push(self, project_id: str, start_s: float, end_s: float) -> dict:
        """Play ``[start_s, end_s)`` of the project's composed timeline on the chair in a thread
        (live playback stops first). Conflict while another push runs or no chair is connected."""
        with self._commands:
            with self._lock:
                link, player, running = self._link, self._player, self._push
                comfort = settings_to_comfort(self._settings)
                stops = self._stops
            if link is None or player is None:
                raise Conflict("no chair is connected; connect one first")
            if running is not None and running.state == "running":
                raise Conflict("a push is already running; stop it first")
            if not link.connected:
                raise Conflict(f"the chair on {link.port} is reconnecting; try again when it is back")
            composed = self.composer.compose(project_id)
            duration = composed.timeline.duration_s
            if not (math.isfinite(start_s) and math.isfinite(end_s)) or start_s < 0:
                raise ParameterError(f"start_s and end_s must be finite seconds >= 0, got {start_s!r}, {end_s!r}")
            end = min(end_s, duration)
            if start_s >= end:
                raise ParameterError(f"push range is empty: start {start_s:g} s, end {end_s:g} s "
                                     f"(the timeline is {duration:g} s)")
            job = _Push(project_id=project_id, start_s=float(start_s), end_s=float(end), cancel=threading.Event())
            with self._lock:  # a STOP either comes before (nothing starts) or finds job.player to stop
                if self._stops != stops:
                    return self.status()
                if player.state == "playing":
                    player.pause()
                job.player, start, end = start_range(link, composed.timeline, start_s=job.start_s, end_s=job.end_s,
                                                     comfort=comfort)
                job.thread = threading.Thread(target=self._run_push, args=(job, start, end),
                                              name="chair-push", daemon=True)
                self._push = job
            job.thread.start()
        self._wake.set()
        return self.status()

    def _run_push(self, job: _Push, start: float, end: float) -> None:
        def progress(stage: str, fraction: float) -> None:
            job.progress = fraction

        outcome, error = "done", None
        try:
            follow_range(job.player, start, end, progress=progress, cancel=job.cancel)
        except CancelledError:
            outcome = "cancelled"
        except Exception as exc:  # reported in the status; the chair got STOP from follow_range()
            outcome, error = "failed", f"{exc}" if isinstance(exc, AutohapticsError) else repr(exc)
        with self._lock:
            if job.state == "running":  # a STOP has already said "cancelled"
                job.state, job.error = outcome, error
        self._wake.set()

    def _cancel_push(self) -> None:
        with self._lock:
            job = self._push
        if job is not None and job.state == "running":
            job.cancel.set()
            if job.thread is not None:
                job.thread.join(5.0)

    # ------------------------------------------------------------------ status
    def profile(self) -> DeviceProfile | None:
        """The connected chair's temperature profile (its HELLO); None when no chair is connected."""
        link = self._link
        return link.profile if link is not None else None

    def status(self) -> dict:
        with self._lock:
            link, player, pushing = self._link, self._player, self._push
            pid, revision, error = self._project, self._revision, self._error
            drift, drift_seeks = self._drift_s, self._drift_seeks
        ps = player.status() if player is not None else None
        ls = ps.link if ps is not None else (link.status().to_dict() if link is not None else None)
        pushing_now = pushing is not None and pushing.state == "running"
        return {
            "connected": bool(ls and ls["connected"]),
            "state": ls["state"] if ls else "idle",
            "port": ls["port"] if ls else None,
            "capabilities": ls["capabilities"] if ls else None,
            "frames_sent": ls["frames_sent"] if ls else 0,
            "frames_dropped": ls["frames_dropped"] if ls else 0,
            "last_tick": ls["last_tick_sent"] if ls else None,
            "reconnects": ls["reconnects"] if ls else 0,
            "diagnostics": diagnostics(ls),
            "error": error or (ps.error if ps is not None else None),
            "playing": bool(ps is not None and ps.state == "playing") or pushing_now,
            "position_s": ps.position_s if ps is not None else 0.0,
            "playback": {
                "state": ps.state if ps is not None else "idle", "project_id": pid, "revision": revision,
                "duration_s": ps.duration_s if ps is not None else None,
                "ticks_skipped": ps.ticks_skipped if ps is not None else 0,
                "clock_priority": ps.clock_priority if ps is not None else None,
                "drift_s": drift, "drift_seeks": drift_seeks,
            },
            "push": pushing.to_dict() if pushing is not None else None,
            "settings": self.settings,
        }

    # --------------------------------------------------------------- streaming
    def subscribe(self) -> Subscription:
        """A status stream on the running event loop: the current status, then every change."""
        return self._subscribers.subscribe([("status", self.status())])

    def _run(self) -> None:
        last_sig, last_sent = None, 0.0
        while not self._closing.is_set():
            woken = self._wake.wait(POLL_S)
            self._wake.clear()
            if self._closing.is_set():
                return
            try:
                self._follow_revision()
                if not self._subscribers:
                    continue
                status = self.status()
                sig = signature(status)
                now = time.monotonic()
                if woken or sig != last_sig or now - last_sent >= STATUS_INTERVAL_S:
                    last_sig, last_sent = sig, now
                    self._subscribers.publish(("status", status))
            except Exception:  # keep following; the next round tries again
                log.exception("chair service monitor")
