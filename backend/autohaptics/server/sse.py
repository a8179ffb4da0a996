"""Server-Sent Events: one helper for every stream (a job's progress, the chair's status).

A source keeps a :class:`Subscribers` set and publishes ``(event name, data)`` items from any thread;
each stream reads its own queue on its event loop. :func:`event_stream` turns a
:class:`Subscription` into the HTTP response: the initial events, then the queued ones, with a
keep-alive comment while nothing happens, until an item ends it (``None``, or an event name the
caller calls final).
"""

from __future__ import annotations

import asyncio
import json
import threading
from collections.abc import Callable
from dataclasses import dataclass

from fastapi.responses import StreamingResponse

KEEP_ALIVE_S = 15.0
Item = tuple[str, dict]


@dataclass
class Subscription:
    """What a stream reads: events so far, then a queue of later ones (None: no more will come)."""

    initial: list[Item]
    queue: asyncio.Queue | None
    close: Callable[[], None]


class Subscribers:
    """The streams listening to one source. ``maxsize`` > 0 bounds each stream's queue and drops its
    oldest item when full (a slow client gets the newest state, not a backlog); 0 keeps every item."""

    def __init__(self, maxsize: int = 0):
        self.maxsize = maxsize
        self._lock = threading.Lock()
        self._entries: list[tuple[asyncio.AbstractEventLoop, asyncio.Queue]] = []

    def subscribe(self, initial: list[Item]) -> Subscription:
        """A new stream on the running event loop, starting with ``initial``."""
        entry = (asyncio.get_running_loop(), asyncio.Queue(maxsize=self.maxsize))
        with self._lock:
            self._entries.append(entry)

        def close() -> None:
            with self._lock:
                if entry in self._entries:
                    self._entries.remove(entry)

        return Subscription(initial=initial, queue=entry[1], close=close)

    def __bool__(self) -> bool:
        with self._lock:
            return bool(self._entries)

    def publish(self, item: Item | None) -> None:
        """Queue ``item`` on every stream (None ends them); streams whose loop is gone are dropped."""
        with self._lock:
            entries = list(self._entries)
        for entry in entries:
            loop, q = entry
            try:
                loop.call_soon_threadsafe(self._put, q, item)
            except RuntimeError:  # that stream's event loop is gone
                with self._lock:
                    if entry in self._entries:
                        self._entries.remove(entry)

    def close_all(self) -> None:
        """End every stream."""
        self.publish(None)
        with self._lock:
            self._entries.clear()

    def _put(self, q: asyncio.Queue, item: Item | None) -> None:
        if self.maxsize and q.full():
            q.get_nowait()
        q.put_nowait(item)


def sse(event: str, data: dict) -> str:
    """One event in the text/event-stream format."""
    return f"event: {event}\ndata: {json.dumps(data, separators=(',', ':'))}\n\n"


def event_stream(sub: Subscription, *, final: Callable[[str], bool] = lambda name: False,
                 keep_alive_s: float = KEEP_ALIVE_S) -> StreamingResponse:
    """The HTTP response of a stream: ``sub``'s events until None or an event that is ``final``."""

    async def stream():
        try:
            for name, data in sub.initial:
                yield sse(name, data)
                if final(name):
                    return
            if sub.queue is None:
                return
            while True:
                try:
                    item = await asyncio.wait_for(sub.queue.get(), timeout=keep_alive_s)
                except asyncio.TimeoutError:
                    yield ": keep-alive\n\n"
                    continue
                if item is None:
                    return
                yield sse(*item)
                if final(item[0]):
                    return
        finally:
            sub.close()

    return StreamingResponse(stream(), media_type="text/event-stream",
                             headers={"Cache-Control": "no-cache", "X-Accel-Buffering": "no"})
