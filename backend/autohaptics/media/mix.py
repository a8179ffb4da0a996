"""Summing the mono tracks of one mix: each track's weighted signal at the input rate, sample by
sample, into one sink (``media.audio`` places and weights each track on the container's clock)."""

from __future__ import annotations

from typing import Protocol

import numpy as np


class Sink(Protocol):
    """Where mono samples go, in order (``media.audio``'s chunker, or a :class:`Lane` of a mix)."""

    def emit(self, mono: np.ndarray) -> None: ...


# A mono track this far behind the others (s) is silence there: an empty or broken track never holds
# the rest of the film in memory.
MIX_LAG_S = 10.0


class Mix:
    """Mono tracks' weighted signals at the input rate, summed sample by sample into ``out``."""

    def __init__(self, n: int, rate: int, out: "Sink"):
        self.out, self.lag = out, int(MIX_LAG_S * rate)
        self.parts: list[list[np.ndarray]] = [[] for _ in range(n)]
        self.have = [0] * n  # samples held per track
        self.skip = [0] * n  # samples already given as silence, to drop when the track catches up

    def lane(self, k: int) -> "Lane":
        return Lane(self, k)

    def push(self, k: int, x: np.ndarray) -> None:
        cut = min(self.skip[k], x.size)
        self.skip[k] -= cut
        if x.size > cut:
            self.parts[k].append(x[cut:])
            self.have[k] += x.size - cut
        self._flush(False)

    def close(self) -> None:
        self._flush(True)

    def _flush(self, final: bool) -> None:
        lead = max(self.have)
        for k, have in enumerate(self.have):
            if lead - have > (0 if final else self.lag):
                self.parts[k].append(np.zeros(lead - have, np.float32))
                self.skip[k] += lead - have
                self.have[k] = lead
        n = min(self.have)
        if n == 0:
            return
        total = np.zeros(n)
        for k, parts in enumerate(self.parts):
            buf = np.concatenate(parts) if len(parts) > 1 else parts[0]
            total += buf[:n]
            self.parts[k] = [buf[n:]] if buf.size > n else []
            self.have[k] -= n
        self.out.emit(total.astype(np.float32))


class Lane:
    """Where one mono track of a :class:`Mix` emits its signal."""

    def __init__(self, mix: Mix, k: int):
        self.mix, self.k = mix, k

    def emit(self, mono: np.ndarray) -> None:
        self.mix.push(self.k, mono)
