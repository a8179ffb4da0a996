"""Which analysed frames get saliency, decided in the video pass's frame order.

Saliency runs only where the chair vibrates: an analysed frame's weights are computed when a tick
from it up to the next analysed frame vibrates (the ticks between hold its values). Which ticks
vibrate follows from the audio pass; when that pass runs beside the video pass the mask is not
known at first (:class:`LaterMask`), and the frames wait in order until it is, so the weights are
computed for the same frames, with the same inputs, in the same order as when the audio came first.
"""

from __future__ import annotations

import threading
from collections.abc import Callable

import numpy as np

from autohaptics.progress import CancelToken, check_cancel

# frames waiting for the mask hold their proxies: beyond this many bytes the video pass waits
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
    """Analysed frames in order, each computed (``compute(k, width, rgb, luma)``) once the mask
    says a tick from it up to the next analysed frame needs saliency.

    need : bool [shape=(n,)] or a :class:`LaterMask`; stride : ticks per analysed frame;
    cancel : checked while waiting for the mask.
    """

    def __init__(self, need: np.ndarray | LaterMask, compute: Callable[[int, int, np.ndarray, np.ndarray | None], None],
                 *, stride: int = 1, max_bytes: int | None = None, cancel: CancelToken | None = None):
        self._later = need if isinstance(need, LaterMask) else None
        self.need = None if self._later is not None else np.asarray(need, bool)
        self._compute, self._stride, self._cancel = compute, int(stride), cancel
        self._max_bytes = MAX_WAITING_BYTES if max_bytes is None else int(max_bytes)
        self._waiting: list[tuple[int, int, np.ndarray, np.ndarray | None]] = []
        self._bytes = 0

    def may_need(self) -> bool:
        """Whether any frame may need saliency (a mask not known yet may)."""
        return self.need is None or bool(self.need.any())

    def add(self, k: int, width: int, rgb: np.ndarray, luma: np.ndarray | None) -> None:
        """The analysed frame of tick ``k`` (``width`` px wide; its RGB and luma proxies)."""
        self._poll()
        self._decide(upto=k)
        if self.need is not None and not self._waiting and self.need[k:k + self._stride].any():
            self._compute(k, width, rgb, luma)
            return
        self._waiting.append((k, width, rgb, luma))
        self._bytes += rgb.nbytes + (0 if luma is None else luma.nbytes)
        if self.need is None and self._bytes > self._max_bytes:
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

    def _decide(self, *, upto: int | None) -> None:
        """Compute or drop the waiting frames whose decision is due: each up to the next one's
        tick, the last up to ``upto`` (None: the last keeps waiting for the next frame)."""
        if self.need is None or not self._waiting:
            return
        keep = self._waiting[-1:] if upto is None else []
        due = self._waiting[:-1] if upto is None else self._waiting
        ends = [e[0] for e in due[1:]] + [keep[0][0] if keep else upto]
        for (k, width, rgb, luma), end in zip(due, ends):
            if self.need[k:max(end, k + self._stride)].any():
                self._compute(k, width, rgb, luma)
        self._waiting = keep
        self._bytes = sum(e[2].nbytes + (0 if e[3] is None else e[3].nbytes) for e in keep)
