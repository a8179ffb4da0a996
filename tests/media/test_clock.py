"""``media.clock.continuous_times``: packets of two streams in runs on clocks that jump (any step, back
or on, past the wrap) come out on one clock that runs on, each run as it was, and a clock that runs on
(a stream pausing the while) is left as it is."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from autohaptics.media.clock import DISCONTINUITY_S, WRAP_S, continuous_times

FRAME_S, BLOCK_S = 0.04, 0.032  # a picture's and a sound block's duration


def _run(start_s: float, length_s: float):
    """A run of interleaved picture (stream 0) and sound (stream 1) packets from ``start_s``, in the order
    a muxer writes them."""
    v = start_s + np.arange(0.0, length_s, FRAME_S)
    a = start_s + np.arange(0.0, length_s, BLOCK_S)
    t = np.concatenate([v, a])
    order = np.argsort(t, kind="stable")
    dt = np.concatenate([np.full(v.size, FRAME_S), np.full(a.size, BLOCK_S)])
    return t[order], dt[order], np.concatenate([np.zeros(v.size, np.int64), np.ones(a.size, np.int64)])[order]


@settings(max_examples=60, deadline=None)
@given(st.lists(st.tuples(st.floats(-95_000.0, 95_000.0), st.floats(1.0, 30.0)), min_size=1, max_size=5))
def test_runs_on_jumping_clocks_come_out_on_one_clock(runs):
    """Each run's clock differs from the one before by more than the threshold (else it is not a jump)."""
    parts, starts, begin = [], [], None
    for start, length in runs:
        if begin is not None and abs(start - begin) <= 2 * DISCONTINUITY_S + 30.0:
            start = begin + 3 * DISCONTINUITY_S + 30.0  # a step that is a jump
        parts.append(_run(start, length))
        starts.append(sum(p[0].size for p in parts[:-1]))
        begin = start
    t0, dt, stream = (np.concatenate([p[k] for p in parts]) for k in range(3))
    out, jumps = continuous_times(t0, dt)
    assert np.isfinite(out).all()
    assert [i for i, _ in jumps] == starts[1:]  # a new clock where each run begins, and nowhere else
    for s in (0, 1):
        steps = np.diff(out[stream == s])
        assert (steps > 0).all() and steps.max() <= 2 * max(FRAME_S, BLOCK_S) + 1e-6  # runs on
    for k, first in enumerate(starts):  # each run as it was
        last = starts[k + 1] if k + 1 < len(starts) else t0.size
        np.testing.assert_allclose(np.diff(out[first:last]), np.diff(t0[first:last]), atol=1e-6)


@settings(max_examples=30, deadline=None)
@given(st.floats(0.0, 1e5), st.floats(2.0, 40.0))
def test_a_clock_that_runs_on_is_left_as_it_is_though_a_stream_pauses(start, pause):
    """The sound stops for ``pause`` s (longer than the threshold, too) while the picture goes on."""
    t0, dt, stream = _run(start, 60.0)
    gone = (stream == 1) & (t0 > start + 10.0) & (t0 < start + 10.0 + pause)
    t0, dt, stream = t0[~gone], dt[~gone], stream[~gone]
    out, jumps = continuous_times(t0, dt)
    assert jumps == [] and np.array_equal(out, t0)


@settings(max_examples=30, deadline=None)
@given(st.floats(100.0, 1000.0), st.floats(1.0, 20.0))
def test_ffmpegs_guess_at_a_wrap_is_undone_exactly(first_s, split_s):
    """A second recording's clock behind the first's: FFmpeg reads its times under its guess at a wrap (60 s
    before the file's first time) as a whole wrap later, so the run falls back by one wrap at ``split_s``
    into it. It comes out as it was, after the first run, to the microsecond."""
    a = _run(first_s, 30.0)
    raw = _run(first_s - 90.0, 30.0)
    guessed = raw[0] + np.where(raw[0] < raw[0][0] + split_s, WRAP_S, 0.0)
    t0, dt = np.concatenate([a[0], guessed]), np.concatenate([a[1], raw[1]])
    out, jumps = continuous_times(t0, dt)
    second = out[a[0].size:]
    np.testing.assert_allclose(np.diff(second), np.diff(raw[0]), atol=1e-6)
    assert second.min() == pytest.approx((a[0] + a[1]).max(), abs=1e-6) and len(jumps) >= 2
