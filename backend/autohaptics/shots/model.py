"""The shot list a designer sees: the analysis's boundaries, then the boundary operations of the
edit history in order (``shot_split`` at a tick, ``shot_merge`` of two adjacent shots).

A shot is ``[t0, t1)`` in ticks; its id is its first tick ``t0`` (stable under edits elsewhere
in the film, and what the operations name). Operations are pure functions over the list of shot
starts; ``strict`` (an operation being submitted) refuses a split outside a shot, an unknown
shot and a merge of shots that are not neighbours, each with one sentence; without it (replaying
stored history over boundaries a new analysis moved) such an operation changes nothing.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from autohaptics.errors import ParameterError
from autohaptics.shots.detect import KINDS, Boundaries

SPLIT = KINDS.index("dissolve") + 1  # the kind code of a designer's split
KIND_NAMES = (*KINDS, "split")
SHOT_OPS = ("shot_split", "shot_merge")


def base_starts(boundaries: Boundaries, n_ticks: int) -> dict[int, int]:
    """{first tick of each shot: kind code} from the analysis's boundaries (0 starts the film)."""
    starts = {0: KINDS.index("start")} if n_ticks > 0 else {}
    for tick, kind in zip(boundaries.tick.tolist(), boundaries.kind.tolist()):
        if 0 < tick < n_ticks:
            starts[int(tick)] = int(kind)
    return starts


def apply_shot_ops(starts: dict[int, int], ops: Sequence[dict], n_ticks: int, *, strict: bool = False
                   ) -> dict[int, int]:
    """The shot starts after the boundary operations in ``ops`` (others are passed over); a new dict."""
    out = dict(starts)
    for op in ops:
        if not isinstance(op, dict) or op.get("op") not in SHOT_OPS:
            continue
        try:
            if op["op"] == "shot_split":
                _split(out, int(op["t"]), n_ticks)
            else:
                _merge(out, [int(s) for s in op["shots"]])
        except ParameterError:
            if strict:
                raise
    return out


def shot_arrays(starts: dict[int, int], n_ticks: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(t0, t1, kind code) of each shot in order, int64 / int64 / uint8 [shape=(m,)]."""
    t0 = np.array(sorted(starts), np.int64)
    t1 = np.append(t0[1:], n_ticks).astype(np.int64)
    return t0, t1, np.array([starts[t] for t in t0.tolist()], np.uint8)


def _split(starts: dict[int, int], t: int, n_ticks: int) -> None:
    if not 0 < t < n_ticks:
        raise ParameterError(f"op 'shot_split': tick {t} is outside the film's shots (1..{n_ticks - 1} can be split)")
    if t in starts:
        raise ParameterError(f"op 'shot_split': tick {t} already starts a shot; split inside a shot")
    starts[t] = SPLIT


def _merge(starts: dict[int, int], ids: list[int]) -> None:
    unknown = [s for s in ids if s not in starts]
    if unknown:
        raise ParameterError(f"op 'shot_merge': no shot starts at tick {unknown[0]} (shot ids are their first ticks)")
    first, second = sorted(ids)
    order = sorted(starts)
    if order.index(second) != order.index(first) + 1:
        raise ParameterError(f"op 'shot_merge': shots {first} and {second} are not neighbours; "
                             "merge two adjacent shots")
    del starts[second]
