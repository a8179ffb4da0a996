"""Similar shots (autohaptics.shots.similar) on per-tick arrays with known answers: two looks
separate, a group the film does not vary adds nothing, the distance is 0..1, symmetric and 0 to
itself, saliency on a few ticks counts for little. The generated film's case runs through the
server (tests/server/test_server_shot_ops.py)."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from autohaptics.errors import ParameterError
from autohaptics.shots.similar import distances, nearest, shot_features


def tiled(lengths: list[int]) -> tuple[np.ndarray, np.ndarray]:
    t1 = np.cumsum(lengths)
    return np.concatenate([[0], t1[:-1]]), t1


def test_two_looks_separate_and_each_shot_finds_its_own_kind():
    rng = np.random.default_rng(3)
    lengths = rng.integers(5, 40, 12).tolist()
    t0, t1 = tiled(lengths)
    n = int(t1[-1])
    kind = np.repeat(np.arange(12) % 2, lengths)
    rgb = np.where(kind[:, None] == 0, [200, 40, 40], [40, 60, 200]) + rng.normal(0, 4, (n, 3))
    motion = np.where(kind == 0, 0.0, 0.3) + rng.uniform(0, 0.02, n)
    loud = np.repeat(np.where(kind == 0, 0.0, 80.0) + rng.uniform(0, 2, n), 5)
    f = shot_features(t0, t1, mean_rgb=rgb, motion=motion, loudness=loud)
    for i in range(12):
        order, d = nearest(f, i)
        assert all(j % 2 == i % 2 for j in order[:5]) and all(j % 2 != i % 2 for j in order[5:])
        assert d.max() <= 1 and d[:5].max() < 0.2 and d[5:].min() > 0.8


def test_a_group_the_film_does_not_vary_adds_nothing_and_missing_groups_are_left_out():
    t0, t1 = tiled([10, 10, 10])
    rgb = np.repeat([[10, 10, 10], [10, 10, 10], [250, 0, 0]], 10, axis=0).astype(float)
    flat = np.full(30, 0.2)
    with_flat = shot_features(t0, t1, mean_rgb=rgb, motion=flat)
    alone = shot_features(t0, t1, mean_rgb=rgb)
    assert with_flat.shape == (3, 4) and alone.shape == (3, 3)
    assert distances(with_flat, 0)[1] == 0.0 and distances(alone, 0)[2] > distances(with_flat, 0)[2] > 0
    assert shot_features(t0, t1).shape == (3, 0) and (distances(shot_features(t0, t1), 1) == 0).all()


def test_saliency_seen_on_a_few_ticks_counts_for_little():
    t0, t1 = tiled([20, 20, 20])
    beta = np.zeros((60, 9))
    beta[:20, 2] = 1.0       # shot 0: all left armrest, every tick
    beta[20:40, 6] = 1.0     # shot 1: right armrest, every tick
    beta[40:60, 6] = 1.0     # shot 2: right armrest too, but seen on 2 ticks only
    mask = np.zeros(60, bool)
    mask[:42] = True
    f = shot_features(t0, t1, beta=beta, saliency_mask=mask)
    d = distances(f, 1)
    assert d[2] < d[0] and distances(f, 0)[2] < distances(f, 0)[1]


@settings(max_examples=100, deadline=None)
@given(st.lists(st.integers(1, 30), min_size=1, max_size=15), st.integers(0, 2**31))
def test_distances_are_finite_in_range_symmetric_and_zero_to_itself(lengths, seed):
    rng = np.random.default_rng(seed)
    t0, t1 = tiled(lengths)
    n = int(t1[-1])
    f = shot_features(t0, t1, mean_rgb=rng.uniform(0, 255, (n, 3)), motion=rng.exponential(0.1, n),
                      loudness=rng.exponential(5, n * 5), beta=rng.uniform(0, 1, (n, 9)),
                      saliency_mask=rng.random(n) < 0.5)
    assert np.isfinite(f).all()
    full = np.array([distances(f, i) for i in range(len(lengths))])
    assert (full >= 0).all() and (full <= 1).all()
    np.testing.assert_allclose(full, full.T, atol=1e-12)
    assert (np.diag(full) == 0).all()
    order, d = nearest(f, 0)
    assert sorted(order.tolist()) == list(range(1, len(lengths))) and (np.diff(d) >= 0).all()


@pytest.mark.parametrize("t0, t1", [([1, 5], [5, 9]), ([0, 4], [5, 9]), ([0, 5], [5, 5]), ([], [])])
def test_shots_that_do_not_tile_are_refused(t0, t1):
    with pytest.raises(ParameterError, match="tile"):
        shot_features(np.array(t0, int), np.array(t1, int), motion=np.zeros(9))
