"""Which analysed frames get saliency, decided in the video pass's frame order.

Saliency runs only where the chair vibrates: an analysed frame's weights are computed when a tick
from it up to the next analysed frame vibrates (the ticks between hold its values). Which ticks
vibrate follows from the audio pass; when that pass runs beside the video pass the mask is not
known at first (:class:`LaterMask`), and the frames wait in order until it is, so the weights are
computed for the same frames, with the same inputs, in the same order as when the audio came first.
Where a frame's weights depend on its own proxies alone, frames beyond the waiting room are weighed
at once and only their weights wait: the same weights for the same frames, some computed for nothing.
"""

from __future__ import annotations

import threading
from collections.abc import Callable
from typing import Any

import numpy as np

from autohaptics.progress import CancelToken, check_cancel

# frames waiting for the mask hold their proxies: beyond this many bytes they are weighed at once
# (SaliencyQueue's ``ahead``) or the video pass waits for the mask
MAX_WAITING_BYTES = 32 << 20


class LaterMask:
    """A bool tick mask decided by another thread: ``value`` is None until :meth:`set`;
    :meth:`close` without a value (the other thread failed) releases whoever waits."""

    def __init__(self):
        self.value: np.ndarray | None = None
        self._done = threading.Event()

    def set(self, mask: np.ndarray) -> None:
        self.value = np.asarray(mask, bool)
        self._done.set()

    def close(self) -> None:
        self._done.set()

    def wait(self, timeout_s: float | None = None) -> bool:
        """True once the mask is set or abandoned."""
        return self._done.wait(timeout_s)


class AbandonedMask(RuntimeError):
    """The thread deciding a :class:`LaterMask` ended without a value."""


class SaliencyQueue:
    """Analysed frames in order, each weighed (``weigh(width, rgb, luma)``) and its weights handed
    to ``commit(k, weights)`` once the mask says a tick from it up to the next analysed frame
    needs saliency.

    need : bool [shape=(n,)] or a :class:`LaterMask`; stride : ticks per analysed frame;
    max_bytes : room for the proxies of frames waiting for the mask (default ``MAX_WAITING_BYTES``);
    ahead : when the waiting frames outgrow that room, weigh them at once and let their weights
        wait instead (a long film's audio pass ends long after the room is full); only for a
        ``weigh`` whose result depends on its arguments alone. Else the queue waits for the mask.
    cancel : checked while waiting for the mask.
    ``weighed_ahead``, ``unused``: frames weighed before the mask was known, and those of them it
    did not need (their work was spent for nothing).
    """

    def __init__(self, need: np.ndarray | LaterMask, weigh: Callable[[int, np.ndarray, np.ndarray | None], Any],
                 commit: Callable[[int, Any], None], *, stride: int = 1, max_bytes: int | None = None,
                 ahead: bool = False, cancel: CancelToken | None = None):
        self._later = need if isinstance(need, LaterMask) else None
        self.need = None if self._later is not None else np.asarray(need, bool)
        self._weigh, self._commit, self._stride, self._cancel = weigh, commit, int(stride), cancel
        self._max_bytes = MAX_WAITING_BYTES if max_bytes is None else int(max_bytes)
        self._ahead = bool(ahead)
        # (tick, width, rgb, luma, weights): the proxies until weighed ahead, then the weights alone
        self._waiting: list[tuple[int, int, np.ndarray | None, np.ndarray | None, Any]] = []
        self._bytes = 0
        self.weighed_ahead = 0
        self.unused = 0

    def may_need(self) -> bool:
        """Whether any frame may need saliency (a mask not known yet may)."""
        return self.need is None or bool(self.need.any())

    def add(self, k: int, width: int, rgb: np.ndarray, luma: np.ndarray | None) -> None:
        """The analysed frame of tick ``k`` (``width`` px wide; its RGB and luma proxies)."""
        self._poll()
        self._decide(upto=k)
        if self.need is not None and not self._waiting and self.need[k:k + self._stride].any():
            self._commit(k, self._weigh(width, rgb, luma))
            return
        self._waiting.append((k, width, rgb, luma, None))
        self._bytes += _nbytes(rgb, luma)
        if self.need is None and self._bytes > self._max_bytes:
            if self._ahead:
                self._weigh_waiting()
            else:
                self._wait()
                self._decide(upto=None)

    def finish(self, n: int) -> None:
        """Decide every waiting frame (the last one's ticks run to ``n``), waiting for the mask."""
        if self.need is None:
            self._wait()
        self._decide(upto=n)

    def _poll(self) -> None:
        if self.need is None and self._later.value is not None:
            self.need = self._later.value

    def _wait(self) -> None:
        while not self._later.wait(0.2):
            check_cancel(self._cancel)
        self._poll()
        if self.need is None:
            raise AbandonedMask("the pass deciding which ticks need saliency ended without a result")

    def _weigh_waiting(self) -> None:
        """Weigh every waiting frame now; their weights wait for the mask instead of their proxies."""
        for i, (k, width, rgb, luma, weights) in enumerate(self._waiting):
            if weights is None:
                self._waiting[i] = (k, width, None, None, self._weigh(width, rgb, luma))
                self.weighed_ahead += 1
        self._bytes = 0

    def _decide(self, *, upto: int | None) -> None:
        """Commit or drop the waiting frames whose decision is due: each up to the next one's
        tick, the last up to ``upto`` (None: the last keeps waiting for the next frame)."""
        if self.need is None or not self._waiting:
            return
        keep = self._waiting[-1:] if upto is None else []
        due = self._waiting[:-1] if upto is None else self._waiting
        ends = [e[0] for e in due[1:]] + [keep[0][0] if keep else upto]
        for (k, width, rgb, luma, weights), end in zip(due, ends):
            if self.need[k:max(end, k + self._stride)].any():
                self._commit(k, weights if weights is not None else self._weigh(width, rgb, luma))
            elif weights is not None:
                self.unused += 1
        self._waiting = keep
        self._bytes = sum(_nbytes(e[2], e[3]) for e in keep)


def _nbytes(*arrays: np.ndarray | None) -> int:
    return sum(a.nbytes for a in arrays if a is not None)
