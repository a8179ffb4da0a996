"""The video pass's flow pairs, judged in the order they come, their optical flow computed beside
the pass when the pass is the slower side.

When the decoder is ahead of the analysis (it still held half its queue when the pass took the
pair's second frame, ``Frame.ahead``), the main thread is the video pass's longest path and the
other core has time to spare: a pair that needs its optical flow has it computed in a worker
thread (OpenCV computes it without the interpreter lock) while the pass goes on with the next
frames, and is finished (magnitudes, depth) once the flow is there. When the decoder is the slower
side the flow is computed at once, in the pass: a third busy thread would only take turns with the
decoder. Either way each pair is judged by the same functions from the same arrays and stored in
the order the pairs came, so the results are those of judging each pair as it comes.
"""

from __future__ import annotations

import queue
import threading
import time
from collections import deque
from collections.abc import Callable

import numpy as np

from autohaptics.airflow.flow import optical_flow
from autohaptics.airflow.pair import PairMotion, PairParams, motion_from_flow, pair_motion, pair_verdict

# pairs waiting for their flow beyond this many: the pass waits for the oldest (its frames, and so
# their decoded pictures, are held until it is judged)
MOST_WAITING = 2


class _Flow:
    """One pair's optical flow, computed in the worker: ``value`` (or ``error``) once ``done``."""

    __slots__ = ("args", "done", "value", "error", "seconds")

    def __init__(self, args: tuple):
        self.args = args
        self.done = threading.Event()
        self.value: np.ndarray | None = None
        self.error: BaseException | None = None
        self.seconds = 0.0


class PairJudge:
    """Flow pairs of one video pass, each judged (:func:`~autohaptics.airflow.pair.pair_motion`)
    and handed to ``store(tick, PairMotion)`` in the order :meth:`add` was called.

    timer(stage, fn, *args, **kwargs) runs a stage in the pass's thread, timed; ``on_flow(seconds)``
    counts a flow computed in the worker. beside : None follows each pair's frame (``ahead``);
    True or False computes every flow beside the pass, or none.
    """

    beside: bool | None = None

    def __init__(self, params: PairParams, store: Callable[[int, PairMotion], None], *, depth_backend=None,
                 timer: Callable, luma_signature: Callable[[np.ndarray], np.ndarray],
                 on_flow: Callable[[float], None] = lambda seconds: None):
        self.params, self._store, self._depth_backend = params, store, depth_backend
        self._timer, self._luma_signature, self._on_flow = timer, luma_signature, on_flow
        self._order: deque = deque()  # (tick, PairMotion, None) judged, or (tick, _Flow, what finishes it)
        self._jobs: queue.SimpleQueue | None = None
        self._worker: threading.Thread | None = None

    def add(self, tick: int, gray0: np.ndarray, gray1: np.ndarray, rgb0: np.ndarray, sig0: np.ndarray | None,
            successor_sig: Callable[[], np.ndarray], dt_s: float, *, ahead: bool = False) -> None:
        """A pair of tick ``tick`` (arguments as ``pair_motion``); ``ahead``: the decoder is ahead of
        the pass at its second frame."""
        if not (ahead if self.beside is None else self.beside):
            result = pair_motion(gray0, gray1, rgb0, sig0, successor_sig, dt_s, params=self.params,
                                 depth_backend=self._depth_backend, timer=self._timer,
                                 luma_signature=self._luma_signature)
            self._order.append((tick, result, None))
        elif (verdict := pair_verdict(gray0, gray1, params=self.params, timer=self._timer,
                                      luma_signature=self._luma_signature)) is not None:
            self._order.append((tick, verdict, None))
        else:
            self._order.append((tick, self._submit((gray0, gray1)), (gray0, rgb0, sig0, successor_sig, dt_s)))
        self._take(wait=sum(isinstance(e[1], _Flow) for e in self._order) > MOST_WAITING)

    def finish(self) -> None:
        """Judge and store every pair still waiting, then stop the worker."""
        try:
            while self._order:
                self._take(wait=True)
        finally:
            self.close()

    def close(self) -> None:
        """Stop the worker once its flow at hand is done (pairs still waiting are dropped: the pass
        ended early)."""
        if self._jobs is not None:
            self._jobs.put(None)
            self._worker.join()
            self._jobs = self._worker = None
        self._order.clear()

    def _take(self, *, wait: bool) -> None:
        """Store the pairs at the head of the order that are judged or whose flow is done; with
        ``wait``, wait for the first one's flow."""
        while self._order:
            tick, result, rest = self._order[0]
            if isinstance(result, _Flow):
                if not result.done.is_set() and not wait:
                    return
                result.done.wait()
                if result.error is not None:
                    raise result.error
                self._on_flow(result.seconds)
                result = motion_from_flow(result.value, *rest, params=self.params, depth_backend=self._depth_backend,
                                          timer=self._timer)
            self._order.popleft()
            self._store(tick, result)
            wait = False

    def _submit(self, pair: tuple[np.ndarray, np.ndarray]) -> _Flow:
        if self._jobs is None:
            self._jobs = queue.SimpleQueue()
            self._worker = threading.Thread(target=_work, args=(self._jobs, self.params), name="autohaptics-flow",
                                            daemon=True)
            self._worker.start()
        job = _Flow(pair)
        self._jobs.put(job)
        return job


def _work(jobs: queue.SimpleQueue, params: PairParams) -> None:
    """The worker: each job's optical flow, until a None."""
    while (job := jobs.get()) is not None:
        t0 = time.perf_counter()
        try:
            job.value = optical_flow(*job.args, params=params.flow)
        except BaseException as exc:  # handed to the pass, re-raised there
            job.error = exc
        job.seconds = time.perf_counter() - t0
        job.done.set()
