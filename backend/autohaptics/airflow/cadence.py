"""The repeated pictures of a frame-rate conversion, and a flow pair's time in the picture's own steps.

A 24 or 25 fps film shown at 30 or 50 fps repeats a picture at a fixed period (24 -> 30: one frame
in 5; 25 -> 30: one in 6; 25 -> 50: one in 2). Two frames two apart then hold one picture step or
two, and motion divided by the stream's time alternates 0.6 / 1.2 x. :class:`Cadence` finds the
repeats from each decoded frame's difference to the frame before (a coarse luma sample): a frame
that differs far less than both its neighbours do is a repeat (where the cadence places one beside
a still frame, far less than the other neighbour: a 24 fps film made 25 fps by repeating a picture a
second, then shown at 30, puts two repeats side by side). A pair's time leaves out the intervals
that end on a repeat, and three repeats at one period (a cadence) make each picture
step last period / (period - 1) intervals: a pair of a 25 -> 30 fps conversion then reads its
steps over 40 ms each, whether it takes in a repeat or not, and a stretch animated on twos reads
as a 12 fps picture, as pairs of consecutive frames read it. Until three repeats are seen a pair
reads its steps over the stream's intervals (1.2 x at 25 -> 30 fps, uniform too). A pair's last
frame has no successor to be judged by yet: the video pass holds the pair one frame, and the
cadence places a repeat where a frame cannot be judged. A still picture or a slow one differs
from its neighbours too little, or too evenly, to be a repeat. docs/BENCHMARKS.md, "Screener
encodes", fifth stop.
"""

from __future__ import annotations

from collections import deque

import numpy as np

MAX_PERIOD = 12  # frames; the longest cadence looked for (24 -> 25 fps repeats every 25th: not one)
FLOOR = 0.1  # mean grey levels; neighbours' differences below this are too small to judge a repeat by
_HISTORY_S = 2.0  # how far back the frames' repeat marks are kept, s


class Cadence:
    """Repeats and the pair time of one stream, fed every decoded frame in order.

    interval_s : the stream's nominal frame interval, s (0: unknown; the stream's time always).
    ratio : a frame is a repeat when its difference to the frame before is under ``ratio`` times
        both neighbours' (0: never; the stream's time always, the thesis).
    """

    def __init__(self, interval_s: float, ratio: float):
        self.interval = float(interval_s) if interval_s > 0 and np.isfinite(interval_s) else 0.0
        self.ratio = float(ratio) if self.interval > 0 else 0.0
        self.count = 0  # frames seen
        self.found = 0  # repeats found
        self._prev: tuple | None = None  # (time, sample) of the frame before
        self._diffs: deque = deque(maxlen=3)  # differences of the last three frames to their frames before
        self._repeats: deque = deque(maxlen=3)  # indices of the last repeats found
        self._frames: deque = deque()  # [index, time, interval to the frame before, repeat] of recent frames

    def add(self, time_s: float, sample: np.ndarray | None) -> None:
        """Take the next decoded frame: its time, s, and a coarse luma sample (None: unknown)."""
        if self.ratio <= 0:
            return
        i, self.count = self.count, self.count + 1
        d = None
        if sample is not None and self._prev is not None:
            pt, ps = self._prev
            if ps.shape == sample.shape and 0.5 * self.interval < time_s - pt < 1.5 * self.interval:
                d = float(np.abs(sample.astype(np.int16) - ps).mean())
        self._frames.append([i, time_s, time_s - self._prev[0] if self._prev else 0.0, None])
        self._prev = (time_s, sample)
        self._diffs.append(d)
        while self._frames[0][1] < time_s - _HISTORY_S:
            self._frames.popleft()
        if len(self._diffs) == 3 and None not in self._diffs:
            j = i - 1  # the middle frame, judged now that both its neighbours are known
            d0, d1, d2 = self._diffs
            if min(d0, d2) > FLOOR:
                repeat = d1 < self.ratio * min(d0, d2)
            elif max(d0, d2) > FLOOR and self.predicted(j):  # a repeat of the film's own beside it
                repeat = d1 < self.ratio * max(d0, d2)
            else:
                return
            if len(self._frames) > 1:
                self._frames[-2][3] = repeat
            if repeat:
                self._repeats.append(j)
                self.found += 1
            elif self.predicted(j):  # the cadence broke (an edit, a new rate): found again from scratch
                self._repeats.clear()

    def period(self) -> int:
        """The cadence's period, frames, while one holds (the last three repeats equally apart), else 0."""
        if len(self._repeats) < 3:
            return 0
        a, b, c = self._repeats
        return c - b if 2 <= c - b <= MAX_PERIOD and b - a == c - b else 0

    def predicted(self, index: int) -> bool:
        """Whether the cadence places a repeat at frame ``index`` (0-based, in decoding order)."""
        p = self.period()
        return bool(p) and (index - self._repeats[-1]) % p == 0

    def pair_time(self, t0: float, t1: float) -> float:
        """A flow pair's time from a frame at ``t0`` to one at ``t1``, s: the intervals of the frames
        after the first that are not repeats (as judged, or where a frame could not be judged, as
        the cadence places them), times period / (period - 1) while a cadence holds (each picture
        step then lasts that many frame intervals); ``t1 - t0`` when none is left."""
        span = max(t1 - t0, 1e-3)
        if self.ratio <= 0:
            return span
        moving = 0.0
        for i, t, dt, rep in reversed(self._frames):  # newest first: a pair spans the last few frames
            if t <= t0:
                break
            if t <= t1 and not (rep if rep is not None else self.predicted(i)):
                moving += dt
        if moving <= 1e-3:
            return span
        p = self.period()
        return moving * p / (p - 1) if p else moving
