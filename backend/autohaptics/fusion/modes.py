"""The vibration track per generation mode, the thesis's study conditions (table 4.1).

- "multimodal": the audio intensity spread over the actuators by the saliency weights (beta);
- "audio": A1, A2 and A5 follow the audio intensity;
- "visual": the salient area's actuators at their weights, no audio;
- "random": seeded random events covering about as much of the film as the audio would.

A vibrating tick without weights of its own (saliency is computed only where the chair vibrated
when the film was analysed) borrows those of the nearest analysed tick of its shot within
``BORROW_TICKS``, else falls back to A5; such ticks are reported as estimated. By default each
analysed tick's weights are first averaged with its shot's analysed neighbours (:func:`smoothed_weights`,
applied by the derive, which keeps them per analysis).
"""

from __future__ import annotations

import numpy as np

from autohaptics.fusion.triangles import fallback_weights
from autohaptics.layout import ACTUATOR_IDS, AUDIO_MODE_ACTUATORS, CENTRE_ACTUATOR, N_ACTUATORS
from autohaptics.timebase import shot_smoothed

MODES = ("multimodal", "audio", "visual", "random")
BORROW_TICKS = 10


def vibration_track(mode: str, intensity: np.ndarray, *, beta: np.ndarray | None = None,
                    have_beta: np.ndarray | None = None, cut: np.ndarray | None = None,
                    seed: int = 0) -> tuple[np.ndarray, dict]:
    """The (n, 9) vibration of ``mode``, 0..1, and its stats.

    intensity : [shape=(n,)] audio intensity 0..1. beta, have_beta, cut : the video pass's weights
    [shape=(n, 9)] (as they are, or :func:`smoothed_weights` of them), where they were computed
    (bool [shape=(n,)]) and the shot cuts; None without a picture.
    Returns (vibration, stats); ``stats["ticks_estimated"]`` counts borrowed weights.
    """
    n = intensity.size
    vib = np.zeros((n, N_ACTUATORS))
    stats: dict = {}
    if mode == "audio":
        vib[:, [ACTUATOR_IDS.index(a) for a in AUDIO_MODE_ACTUATORS]] = intensity[:, None]
    elif mode == "multimodal":
        if beta is None:  # no picture: the no-salient-region rule puts everything on A5
            vib[:, ACTUATOR_IDS.index(CENTRE_ACTUATOR)] = intensity
            stats["fallback"] = "no video stream: all weight on A5"
        else:
            weights, estimated = weights_for(beta, have_beta, cut, intensity > 0)
            vib = intensity[:, None] * weights
            stats["ticks_estimated"] = int(estimated.sum())
    elif mode == "visual":
        if beta is not None:
            salient = have_beta & (beta.sum(axis=1) > 0)
            vib[salient] = beta[salient]
    elif mode == "random":
        vib = random_vibration(n, seed, float((intensity > 0).mean()) if intensity.any() else 0.2)
    return np.clip(vib, 0.0, 1.0), stats


def weights_for(beta: np.ndarray, have: np.ndarray, cut: np.ndarray,
                wanted: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Actuator weights per tick: the computed ones, else those of the nearest analysed tick of the
    same shot (within ``BORROW_TICKS``), else A5 only. Returns (beta (n, 9), estimated (n,) bool)."""
    n = wanted.size
    out = np.array(beta, dtype=np.float64)
    missing = wanted & ~have
    estimated = np.zeros(n, bool)
    fallback = fallback_weights()
    if missing.any():
        shot = np.cumsum(cut)
        have_idx = np.flatnonzero(have)
        for k in np.flatnonzero(missing):
            estimated[k] = True
            if have_idx.size:
                j = have_idx[np.argmin(np.abs(have_idx - k))]
                if abs(j - k) <= BORROW_TICKS and shot[j] == shot[k]:
                    out[k] = out[j]
                    continue
            out[k] = fallback
    out[~(have | missing)] = 0.0
    return out, estimated


def smoothed_weights(beta: np.ndarray, have: np.ndarray, cut: np.ndarray, sigma_ticks: float) -> np.ndarray:
    """Each analysed tick's weights (``have``) as the Gaussian-weighted mean (std ``sigma_ticks``)
    of those of the analysed ticks of its shot around it, scaled so that its strongest actuator is
    1; other ticks keep theirs (:func:`weights_for` then lends a tick without its own the nearest
    analysed tick's). beta : [shape=(n, 9)] >= 0. Why: which triangles hold salient pixels, and so
    which actuators a tick's weights reach, turns on one frame's salient specks, which an encode's
    block noise or another frame rate moves; the shot's neighbouring frames agree on where its
    subject is (docs/BENCHMARKS.md, "Vibration weights across encodes").
    Returns float64 [shape=(n, 9)] in 0..1; ``beta`` itself for sigma_ticks <= 0."""
    if sigma_ticks <= 0:
        return beta
    have = np.asarray(have, bool)
    ticks = np.flatnonzero(have)
    mean = shot_smoothed(beta, np.cumsum(cut), ticks, sigma_ticks, mask=have, mean=True)
    top = mean.max(axis=1, keepdims=True, initial=0.0)
    out = np.array(beta, dtype=np.float64)
    out[ticks] = np.where(top > 0, mean / np.where(top > 0, top, 1.0), beta[ticks])
    return out


def random_vibration(n: int, seed: int, active_fraction: float) -> np.ndarray:
    """The thesis's "random" condition: events at random times on random actuators, covering about
    ``active_fraction`` of the ticks. Events last 0.3..1.5 s with intensity 0.4..1 on 1..3 actuators."""
    rng = np.random.default_rng(seed)
    vib = np.zeros((n, N_ACTUATORS))
    target = int(round(np.clip(active_fraction, 0.0, 1.0) * n))
    active = np.zeros(n, bool)
    guard = 0
    while active.sum() < target and guard < 10 * n + 10:
        guard += 1
        length = int(rng.integers(3, 16))
        start = int(rng.integers(0, n))
        stop = min(n, start + length)
        acts = rng.choice(N_ACTUATORS, size=int(rng.integers(1, 4)), replace=False)
        vib[start:stop, acts] = np.maximum(vib[start:stop, acts], rng.uniform(0.4, 1.0))
        active[start:stop] = True
    return vib
