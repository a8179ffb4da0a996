"""The repeated pictures of a frame-rate conversion, and a flow pair's time in the picture's own steps.

A 24 or 25 fps film shown at another rate repeats its pictures: 25 -> 30 fps one frame in 6, 24 -> 50 each picture
twice and every twelfth three times, 24 -> 59.94 (a US 720p broadcast) in runs of 2 and 3 in turn, 24 -> 120 five
times. Two frames a fixed number apart then hold a varying number of picture steps, and motion divided by the
stream's time reads up to 2.5 x where a pair ends on a picture's first frame. :class:`Cadence` judges each decoded
frame from its difference to the frame before (a coarse luma sample): it is a repeat when that is coding noise
(under ``REPEAT_MAX``) and far less than the largest difference within ``REACH`` frames before it and the largest
within ``REACH`` frames after it both are (a run of up to ``REACH`` repeats has a step on either side within that
reach; a picture that slows down or speeds up has no step on one side, so its small differences are steps; action
beside a flash or a cut differs by more than noise). A frame is judged once ``REACH`` frames after it are seen. A
pair's time counts the frames after its first that are steps, each lasting its own interval times the picture's mean
step over its last ``MEAN_STEPS`` steps (frames / steps of whole runs: 2.5 at 24 -> 59.94, 1.2 at 25 -> 30, 2 on a
stretch animated on twos, about 1 in a variable-rate stream, whose intervals are its own); a frame that could not be
judged (no frame right before it, a still picture) counts its own interval, which is what it lasts on average either
way. A run of more frames than ``HELD_S`` holds, rounded up (2 at 24 fps, 3 at 30, 10 at 120), is no conversion's
but a picture held (a still shot's pictures that a codec keeps between its key frames, a freeze): it is left out of
the mean step, and the step after it lasts the time since the run's own step, over which the picture's motion
gathered (not in a variable-rate stream, whose repeats last nothing). docs/BENCHMARKS.md, "Screener encodes" (fifth
stop), "Stop 60" and "Stop 68".
"""

from __future__ import annotations

import math
from collections import deque

import numpy as np

REACH = 5  # frames on either side of a frame in which a step is looked for (24 fps at 120: runs of 5)
MAX_STEP_FRAMES = 6.0  # the longest mean step, frame intervals (24 fps at 144 Hz)
HELD_S = 1 / 12  # the longest run of a cadence, s (a 12 fps picture: animation on twos at 24 fps, and at 30 fps
# a film's own repeat beside a conversion's, 3 frames); a run of more frames is a picture held
FLOOR = 0.5  # mean grey levels; steps around a frame below this are too small to judge a repeat by
REPEAT_MAX = 2.5  # mean grey levels; a repeat differs by coding noise at most (beside a flash or a cut,
# action's large differences are small)
HISTORY_S = 2.0  # how far back the frames' judgements are kept, s
MEAN_STEPS = 24  # the picture's latest steps the mean step is taken over (or the history's, where fewer)
MIN_REPEATS = 1 / 12  # repeats per step under which a stretch holds no conversion (a picture held now and then)
MIN_STEPS = 6  # steps judged in the history before their mean step replaces the frame interval
DENSE = 0.8  # the share of recent frames with a known difference from which pairs wait for judgements
WAIT_S = 1.0  # how long a pair waits for the mean step while fewer steps are judged, s


class Cadence:
    """Repeats and the pair time of one stream, fed every decoded frame in order.

    interval_s : the stream's nominal frame interval, s (0: unknown; the stream's time always).
    ratio : a frame is a repeat when its difference to the frame before is under ``ratio`` times
        the level of the steps around it (0: never; the stream's time always, the thesis).
    variable : a variable-rate stream: its frames hold no conversion's runs, so a step lasts its own
        interval (the mean step is one), and a repeat (a picture held) nothing.
    """

    def __init__(self, interval_s: float, ratio: float, variable: bool = False):
        self.interval = float(interval_s) if interval_s > 0 and np.isfinite(interval_s) else 0.0
        self.ratio = float(ratio) if self.interval > 0 else 0.0
        self.variable = bool(variable)
        # the most frames a cadence's run holds (0: any, in a variable-rate stream, whose repeats last nothing)
        self.longest_run = math.ceil(round(HELD_S / self.interval, 6)) if self.interval and not self.variable else 0
        self.count = 0  # frames seen
        self.found = 0  # repeats found
        self.judged = 0  # frames judged (a repeat or a step)
        self._prev: tuple | None = None  # (time, sample) of the frame before
        self._diffs: deque = deque(maxlen=2 * REACH + 1)  # recent frames' differences to their frames before
        self._frames: deque = deque()  # [index, time, interval to the frame before, repeat] of recent frames
        self._step: tuple[int, float, int] = (-1, 1.0, 0)  # (frames seen, _mean() then)
        self._judged_s = -np.inf  # the time of the newest frame judged

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
        while len(self._frames) > REACH + 1 and self._frames[0][1] < time_s - HISTORY_S:
            self._frames.popleft()
        if len(self._diffs) == 2 * REACH + 1:
            for pos in range(1, REACH) if self.count == 2 * REACH + 1 else ():
                self._judge(pos)  # the first frames, by the fewer frames before them
            self._judge(REACH)  # the frame REACH frames back, now that the differences after it are known

    def finish(self) -> None:
        """Judge the last frames, fewer than ``REACH`` frames from the end, by the frames after them there
        are, or by the ones before alone where those hold no step (the file ends inside a run as often
        as a picture slows down in its last frames)."""
        if self.ratio <= 0:
            return
        for pos in range(max(0, len(self._diffs) - REACH), len(self._diffs)):
            self._judge(pos, ended=True)
        self._diffs.clear()
        self._step = (-1, 1.0, 0)

    def _judge(self, pos: int, ended: bool = False) -> None:
        """Judge the frame whose difference is ``self._diffs[pos]`` (``ended``: the last frames seen)."""
        diffs = list(self._diffs)
        before = [x for x in diffs[max(0, pos - REACH):pos] if x is not None]
        after = [x for x in diffs[pos + 1:] if x is not None]
        if diffs[pos] is None or not before or not (after or ended):
            return
        # the last frames: a file that ends inside a run has no step after them
        level = min(max(before), max(after)) if after and (max(after) > FLOOR or not ended) else max(before)
        if level <= FLOOR:
            return
        frame = self._frames[pos - len(diffs)]
        frame[3] = repeat = diffs[pos] < min(self.ratio * level, REPEAT_MAX)
        self.found += repeat
        self.judged += 1
        self._judged_s = frame[1]

    @property
    def judges_newest(self) -> bool:
        """Whether the newest frame is to be judged: its difference to the frame before is known, as most
        of the recent frames' are (a decode that skips frames gives few: a pair ending there need not wait
        for the judgement, and a pair held makes the flow of the pairs after it wait too)."""
        return bool(self.ratio) and bool(self._diffs) and self._diffs[-1] is not None and self._dense()

    def _dense(self) -> bool:
        """Whether most recent frames' differences are known (``DENSE`` of them: a decode of every frame)."""
        return sum(d is not None for d in self._diffs) >= DENSE * len(self._diffs)

    @property
    def settled_s(self) -> float:
        """The time up to which pairs may be timed, s: the newest frame whose judgement is final (judged,
        or never to be), or ``WAIT_S`` before it while the history holds judged frames but fewer than
        ``MIN_STEPS`` whole runs (the mean step still unknown: at 120 fps a pair's two steps would read
        as 2 intervals, 5 x), where most frames are judged (``DENSE``); -inf before the first such frame."""
        if not self.ratio or len(self._frames) <= REACH:
            return -np.inf
        t = self._frames[-1 - REACH][1]
        # not where nothing is judged, nor where the decode skips frames (its pairs are not held)
        waits = self._mean()[1] < MIN_STEPS and self._judged_s >= t - HISTORY_S and self._dense()
        return t - WAIT_S if waits else t

    def step_s(self) -> float:
        """The picture's mean step, s: the frame interval x frames / steps of the latest ``MEAN_STEPS``
        whole runs, at most ``MAX_STEP_FRAMES`` intervals; the frame interval until ``MIN_STEPS`` runs are
        judged, under ``MIN_REPEATS`` and in a variable-rate stream."""
        return self.interval * self._mean()[0]

    def _mean(self) -> tuple[float, int]:
        """The mean step over the latest ``MEAN_STEPS`` steps in the history, frame intervals, and the
        steps it is taken over."""
        if self._step[0] != self.count:
            # whole runs (a step and the repeats after it) before the newest step, back to a frame not judged
            frames = runs = pending = 0
            started = False
            for _, _, _, rep in reversed(self._frames):
                if started and rep is None:
                    break
                if started and rep:
                    pending += 1
                elif started and self._held(pending + 1):
                    pending = 0  # a picture held: not the cadence's
                elif started:
                    frames, runs, pending = frames + pending + 1, runs + 1, 0
                    if runs == MEAN_STEPS:
                        break
                started = started or rep is False
            mean = min(frames / runs, MAX_STEP_FRAMES) if runs >= MIN_STEPS and not self.variable else 1.0
            mean = mean if mean >= 1.0 + MIN_REPEATS else 1.0
            self._step = (self.count, mean, runs)
        return self._step[1], self._step[2]

    def _held(self, run: int) -> bool:
        """Whether a run of ``run`` frames (a step and its repeats) is a picture held, not a cadence's."""
        return 0 < self.longest_run < run

    def least_span_s(self, steps: float) -> float:
        """A flow pair's least span for ``steps`` of the picture's steps, s: ``steps`` frame intervals
        where each frame is a step, else to the frame that ends ``steps`` + 1/2 steps, a quarter interval
        spared (at 24 -> 59.94 fps, 1.5 steps: 5 frames, always two of the picture's steps, as 2 frames
        are at 24 fps; at 24 -> 30, 2 frames as without repeats)."""
        step = self.step_s() if self.ratio else self.interval
        return steps * self.interval if step <= self.interval else (steps + 0.5) * step - 0.75 * self.interval

    def pair_time(self, t0: float, t1: float) -> float:
        """A flow pair's time from a frame at ``t0`` to one at ``t1``, s: each frame after the first
        that is a step lasts its interval times the mean step (:meth:`step_s` in intervals), or, after
        a picture held (a run of more frames than ``HELD_S`` holds), the time since that run's step; a
        repeat lasts nothing, a frame not judged its own interval; ``t1 - t0`` when that leaves nothing."""
        span = max(t1 - t0, 1e-3)
        if self.ratio <= 0:
            return span
        frames = self._frames
        mean = None
        total = 0.0
        for j in range(len(frames) - 1, -1, -1):  # newest first: a pair spans the last few frames
            _, t, dt, rep = frames[j]
            if t <= t0:
                break
            if t > t1 or rep:
                continue
            if rep is None:
                total += dt
                continue
            k = j - 1  # the step of the run before this one
            while k >= 0 and frames[k][3]:
                k -= 1
            if k >= 0 and frames[k][3] is False and self._held(j - k):
                total += t - frames[k][1]
            else:
                mean = self._mean()[0] if mean is None else mean
                total += dt * mean
        return total if total > 1e-3 else span
