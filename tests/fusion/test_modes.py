"""The vibration track's weights smoothed over a shot (fusion/modes.py, ``smoothed_weights``): known
answers on hand-made weights, where one analysed frame's salient speck reaches an actuator that its
neighbours do not."""

from __future__ import annotations

import numpy as np
import pytest

from autohaptics.fusion.modes import smoothed_weights, vibration_track
from autohaptics.layout import ACTUATOR_IDS
from autohaptics.metrics import onsets

IDX = {a: i for i, a in enumerate(ACTUATOR_IDS)}
LEFT = np.zeros(9)
LEFT[[IDX["A1"], IDX["A3"], IDX["A5"]]] = (1.0, 0.6, 0.3)
RIGHT = np.zeros(9)
RIGHT[[IDX["A2"], IDX["A7"], IDX["A5"]]] = (1.0, 0.6, 0.3)


def flickering_shot(n: int = 30) -> np.ndarray:
    """A subject on the left in every analysed frame, and on every other frame a speck that gives
    A7 a weight of 0.1."""
    beta = np.tile(LEFT, (n, 1))
    beta[1::2, IDX["A7"]] = 0.1
    return beta


def track(beta, sigma, cut=None, have=None):
    n = beta.shape[0]
    cut = np.zeros(n, bool) if cut is None else cut
    have = np.ones(n, bool) if have is None else have
    vib, _ = vibration_track("multimodal", np.full(n, 0.8), beta=smoothed_weights(beta, have, cut, sigma),
                             have_beta=have, cut=cut)
    return vib


def test_a_frames_speck_no_longer_switches_its_actuator_on_and_off():
    beta = flickering_shot()
    thesis, smoothed = track(beta, 0.0), track(beta, 2.0)
    assert onsets(thesis[:, IDX["A7"]]).sum() == 15  # on with every speck, off between them
    assert onsets(smoothed[:, IDX["A7"]]).sum() == 1  # on through the shot, at about half the speck's weight
    assert np.allclose(smoothed[:, IDX["A7"]] / 0.8, 0.05, atol=0.02)
    for a in ("A1", "A3", "A5"):  # the subject keeps its weights
        assert np.allclose(smoothed[:, IDX[a]], thesis[:, IDX[a]], atol=1e-12)


def test_the_thesis_rule_is_sigma_zero():
    beta = flickering_shot()
    assert smoothed_weights(beta, np.ones(30, bool), np.zeros(30, bool), 0.0) is beta


def test_weights_do_not_cross_a_cut():
    beta = np.vstack([np.tile(LEFT, (10, 1)), np.tile(RIGHT, (10, 1))])
    cut = np.zeros(20, bool)
    cut[10] = True
    out = smoothed_weights(beta, np.ones(20, bool), cut, 3.0)
    assert np.allclose(out, beta, rtol=0, atol=1e-12)


def test_only_analysed_ticks_lend_their_weights():
    beta = np.tile(LEFT, (11, 1))
    beta[5] = RIGHT  # weights of a tick that was not analysed
    have = np.ones(11, bool)
    have[5] = False
    out = smoothed_weights(beta, have, np.zeros(11, bool), 2.0)
    assert np.allclose(out[have], np.tile(LEFT, (10, 1)), rtol=0, atol=1e-12)
    assert np.array_equal(out[5], RIGHT)  # its own, which the track replaces by its neighbour's
    assert np.allclose(track(beta, 2.0, have=have)[5], 0.8 * LEFT, rtol=0, atol=1e-12)


def test_ticks_without_weights_keep_none_and_the_strongest_is_one():
    rng = np.random.default_rng(3)
    beta = rng.random((40, 9)) ** 3
    beta[rng.random(40) < 0.3] = 0.0
    have = (rng.random(40) < 0.7) & (beta.max(axis=1) > 0)
    out = smoothed_weights(beta, have, rng.random(40) < 0.1, 2.0)
    assert np.array_equal(out[~have], beta[~have]) and np.allclose(out[have].max(axis=1), 1.0)
    assert np.all(np.isfinite(out)) and out.min() >= 0 and out.max() <= 1


@pytest.mark.parametrize("sigma, n", [(0.5, 300), (2.0, 300), (3.7, 300), (2.0, 3), (3.7, 1)])
def test_the_smoothed_weights_are_the_masked_mean_over_the_shot(sigma, n):
    """Against the mean written out tick by tick, clips shorter than the kernel included."""
    rng = np.random.default_rng(7)
    beta, have = rng.random((n, 9)), rng.random(n) < 0.6
    cut = rng.random(n) < 0.05
    shot, r = np.cumsum(cut), int(np.ceil(3 * sigma))
    out = smoothed_weights(beta, have, cut, sigma)
    for k in np.flatnonzero(have):
        near = [j for j in range(max(0, k - r), min(n, k + r + 1)) if have[j] and shot[j] == shot[k]]
        g = np.exp(-0.5 * ((np.array(near) - k) / sigma) ** 2)
        want = (g[:, None] * beta[near]).sum(axis=0) / g.sum()
        assert np.allclose(out[k], want / want.max(), rtol=0, atol=1e-12)
    assert np.array_equal(out[~have], beta[~have])
