"""How far a feature stands above its own recent baseline: the "events" rule's measure
(ALGORITHM.md section 2, decision 2026-11; docs/GUIDE.md "Vibration").

A steady bed (music, dialogue, room tone) keeps every feature near its loud level of the last few
seconds; an impact, an explosion, a booming hit or a rising rumble lifts it above that. Per 20 ms frame:

- the feature goes to a scale on which equal ratios sound alike: loudness (sone), sharpness (acum)
  and the booming index as they are; low-frequency energy (Pa^2) to the power 0.3 (Stevens's exponent);
- its envelope is the maximum over the last ``ENVELOPE_S`` (1 s: the loud level of speech or music
  between its syllables and notes, so that they do not count as events one by one);
- the baseline is the mean envelope over ``baseline_s`` seconds ending ``GAP_S`` (0.1 s) before
  the frame. A file whose sound is under way within its first ``GAP_S`` (cut mid-score) is taken
  to have had it before it began, at its level over its opening (:func:`opening_frames`), so its
  start is no event; after an opening silence a sound is an onset however early it comes, unless
  the file's first onset has likes seconds later (:func:`resumed_onsets`: a cut in a pause of the
  dialogue), whose baseline is then the level before the file began;
- novelty = log2((value + ``FLOOR``) / (baseline + ``FLOOR``)) / ``FULL_OCTAVES`` (shares of the
  film's top), at least 0: 0 at or below the baseline, 1 at a rise of 2^0.5 (+5 phon for loudness)
  well above ``FLOOR``; less among values near it, where a codec's few-percent changes would decide.
  :func:`novelty` clips it at 1 for display; the rule compares it unclipped (a density ranks by it).

Sharpness is a sound's colour: :func:`feature_novelty` keeps its novelty where the loudness rises
too (a hiss or a consonant between louder vowels is no event), in full from ``SHARPNESS_RISE`` and
in proportion below it (a rise that the codec or the level decides switches nothing on and off).
"""

from __future__ import annotations

import numpy as np
from numpy.lib.stride_tricks import sliding_window_view

from autohaptics.quantiles import median
from autohaptics.timebase import FRAME_S

ENVELOPE_S = 1.0
GAP_S = 0.1
OPENING_S = 0.5
OPENING_RISE = 2.0  # loudness doubles at +10 phon; the loudness model's attack rises less after GAP_S
ATTACK_S = 0.2  # the loudness model reaches 0.9 of a low tone's level within it (0.16 s at 50 Hz)
FULL_OCTAVES = 0.5
EXPONENTS = {"sharpness": 1.0, "booming": 1.0, "low_energy": 0.3, "loudness": 1.0}
FLOOR = 3e-2  # of the feature's maximum over the film, added to value and baseline (module docstring)
RESUMED_S = 3.0  # the first onset's likes are looked for over this long once its baseline window is past it
RESUMED_MIN = 1  # at least this many likes
SHARPNESS_RISE = 0.1  # loudness novelty from which a sharpness rise counts in full (+0.5 phon)
SMOOTHED = ("loudness", "sharpness")  # the features whose single-frame peaks a lossy codec moves


def feature_novelty(features: dict[str, np.ndarray], *, baseline_s: float = 3.0,
                    median_n: int = 1) -> dict[str, np.ndarray]:
    """Unclipped novelty (>= 0, finite) of each of the four features, sharpness kept only where the
    loudness rises too, in full from ``SHARPNESS_RISE`` (module docstring).
    features : {name: [shape=(n,)] per 20 ms frame}.

    median_n : frames (<= 1: none) of a running median (:func:`trailing_median`) that loudness and
    sharpness go through first: a lossy codec moves their single-frame peaks (pre-echo, a transient
    spread over the next block, high bands quantised coarsely), and the 1 s maximum envelope would
    carry such a peak into the baseline for seconds. Booming and low-frequency energy come from the
    bands a codec keeps."""
    sound = features.get("loudness")
    opening = resumed = None
    if sound is not None:
        sound = np.asarray(sound, dtype=np.float64)
        opening, resumed = opening_frames(sound), resumed_onsets(sound, baseline_s=baseline_s)
    lag = (median_n - 1) // 2 if median_n > 1 else 0
    out = {f: novelty(trailing_median(np.asarray(x, dtype=np.float64), median_n) if f in SMOOTHED else x,
                      exponent=EXPONENTS[f], baseline_s=baseline_s, clip=False, opening_n=opening,
                      lag_n=lag if f in SMOOTHED else 0, resumed=resumed)
           for f, x in features.items()}
    if "sharpness" in out and "loudness" in out:
        out["sharpness"] = out["sharpness"] * np.clip(out["loudness"] / SHARPNESS_RISE, 0.0, 1.0)
    return out


def novelty(x: np.ndarray, *, exponent: float = 1.0, baseline_s: float = 3.0, clip: bool = True,
            opening_n: int | None = None, lag_n: int = 0, resumed: np.ndarray | None | str = "own") -> np.ndarray:
    """Novelty of one feature curve (module docstring).

    x : float [shape=(n,)], one value per 20 ms frame, >= 0 (non-finite values count as 0).
    baseline_s : length of the recent baseline, seconds (> 0).
    opening_n : the frames whose largest value the feature had before the file began, 0 for a
        file that opens on silence (:func:`opening_frames` of the loudness; default: of ``x``).
    lag_n : frames by which ``x`` lags the level ``opening_n`` was taken from (a trailing median's
        (n - 1) // 2): a curve under way from its first frame holds its opening value that long, so
        the level its opening check compares with spans ``lag_n`` frames more.
    resumed : the frames of the later onsets like the file's first (:func:`resumed_onsets` of the
        loudness; default: of ``x``; None: none): the history before the file is at least the
        baseline this feature reads at them.
    Returns float64 [shape=(n,)], finite, >= 0 and (with ``clip``) <= 1; all zeros for silence.
    """
    v = np.asarray(x, dtype=np.float64)
    v = np.where(np.isfinite(v), np.maximum(v, 0.0), 0.0) ** exponent
    n = v.size
    top = float(v.max()) if n else 0.0
    if top <= 0.0:
        return np.zeros(n)
    v = v / top  # the ratio below is scale-free; at 0..1 its floor cannot underflow (a denormal top)
    env_n = max(1, int(round(ENVELOPE_S / FRAME_S)))
    gap_n = int(round(GAP_S / FRAME_S))
    base_n = max(1, int(round(baseline_s / FRAME_S)))
    opening_n = opening_frames(v) if opening_n is None else min(int(opening_n), n)
    if opening_n > 0:  # a hit of this feature's own ends its opening, whatever the loudness does
        first = int(np.argmax(v[:opening_n] > FLOOR))  # its own sound begins (a codec's delay, the median's lag)
        early_n = max(first, int(lag_n)) + gap_n - first  # its first GAP_S, as the loudness's own
        opening_n = first + _before_rise(v[first:], early_n, opening_n - first)
    before = v[:opening_n].max() if opening_n > 0 else 0.0  # the level the file's sound had before it began
    if isinstance(resumed, str):
        resumed = resumed_onsets(v, baseline_s=baseline_s)
    if resumed is not None:  # what the baseline reads at the first onset's likes
        inside = trailing_max(v, env_n)
        cum = np.concatenate([[0.0], np.cumsum(inside)])
        hi = np.asarray(resumed, dtype=np.int64) - gap_n
        hi = hi[(hi >= base_n) & (hi <= n)]
        if hi.size:
            before = max(before, float(np.median((cum[hi] - cum[hi - base_n]) / base_n)))
    pre_n = env_n + gap_n + base_n if opening_n > 0 or before > 0 else 0  # history for every window before t = 0
    env = trailing_max(np.concatenate([np.full(pre_n, before), v]), env_n)
    cum = np.concatenate([[0.0], np.cumsum(env)])
    hi = np.clip(np.arange(n) + pre_n - gap_n, 0, n + pre_n)
    lo = np.clip(hi - base_n, 0, n + pre_n)
    count = hi - lo
    base = np.where(count > 0, (cum[hi] - cum[lo]) / np.maximum(count, 1), 0.0)
    out = np.maximum(np.log2((v + FLOOR) / (np.maximum(base, 0.0) + FLOOR)) / FULL_OCTAVES, 0.0)
    return np.minimum(out, 1.0) if clip else out


def opening_frames(x: np.ndarray) -> int:
    """The frames of a file's opening whose level its sound had before the file began (module
    docstring): up to ``OPENING_S`` after the sound begins (and through a climb still under way
    there), ending early where it falls silent or where a hit begins, a rise ``OPENING_RISE`` times
    above the level it had reached (:func:`_before_rise`; :func:`novelty` ends each feature's
    opening at its own such hit too); 0 where the file opens on at least ``GAP_S`` of silence (at
    most ``FLOOR`` of the film's top).

    x : [shape=(n,)] per 20 ms frame, >= 0 (non-finite values count as 0): the loudness, or any level.
    """
    v = np.where(np.isfinite(x), np.maximum(x, 0.0), 0.0)
    top = float(v.max()) if v.size else 0.0
    if top <= 0.0:
        return 0
    gap_n = int(round(GAP_S / FRAME_S))
    sounding = v > FLOOR * top
    first = int(np.argmax(sounding))
    if first >= gap_n:
        return 0
    end = min(v.size, first + int(round(OPENING_S / FRAME_S)))
    quiet = np.flatnonzero(~sounding[first:end])
    end = first + int(quiet[0]) if quiet.size else end
    return first + _before_rise(v[first:] / top, gap_n, end - first)


def resumed_onsets(x: np.ndarray, *, baseline_s: float = 3.0) -> np.ndarray | None:
    """The onsets that tell a file's first onset resumes what went on before the file began: frames
    of the later onsets like it (their level within ``OPENING_RISE`` of its own) whose whole
    baseline window lies after it, up to ``RESUMED_S`` later; None where there are fewer than
    ``RESUMED_MIN`` (a single hit, a long sound, a different sound after it).

    An onset is a frame where ``x`` rises ``OPENING_RISE`` times above the least it read over the
    ``GAP_S`` before (both with ``FLOOR`` added); its level is its largest over ``ATTACK_S`` from
    there. A file cut inside dialogue or a volley opens on a word or a shot like those that follow,
    and the baseline the rule reads at those is what it read before the file began; a boom out of
    silence, a trailer's opening hit or drums seconds apart have no such likes, or low baselines at
    them, and stay onsets. x : [shape=(n,)] per 20 ms frame, >= 0 (non-finite values count as 0).
    """
    v = np.where(np.isfinite(x), np.maximum(x, 0.0), 0.0)
    top = float(v.max()) if v.size else 0.0
    if top <= 0.0:
        return None
    v = v / top
    gap_n, attack_n = int(round(GAP_S / FRAME_S)), int(round(ATTACK_S / FRAME_S))
    base_n = max(1, int(round(baseline_s / FRAME_S)))
    if v.size <= gap_n + base_n:
        return None
    least = sliding_window_view(v[:-1], gap_n).min(axis=1)  # over frames t - gap_n .. t - 1, t >= gap_n
    rise = np.r_[np.zeros(gap_n, bool), v[gap_n:] + FLOOR > OPENING_RISE * (least + FLOOR)]
    first_sound = int(np.argmax(v > FLOOR))
    if 0 < first_sound < gap_n:  # a sound after a shorter silence rises too
        rise[first_sound] = True
    onsets = np.flatnonzero(rise & ~np.r_[False, rise[:-1]])
    if onsets.size < RESUMED_MIN + 1:
        return None
    peak = trailing_max(np.r_[v, np.zeros(attack_n)], attack_n + 1)[attack_n:] + FLOOR  # largest from each frame on
    h = int(onsets[0])
    later = onsets[(onsets >= h + gap_n + base_n) & (onsets <= h + gap_n + base_n + int(round(RESUMED_S / FRAME_S)))]
    like = later[(OPENING_RISE * peak[later] >= peak[h]) & (peak[later] <= OPENING_RISE * peak[h])]
    return like if like.size >= RESUMED_MIN else None


def _before_rise(v: np.ndarray, early_n: int, n: int) -> int:
    """How many of the first ``n`` frames of ``v`` (0..1 of the film's top) come before a hit: a
    rise above ``OPENING_RISE`` times its level (both with ``FLOOR`` added, as the novelty compares
    them). Until ``ATTACK_S`` after the first ``early_n`` frames, the level is theirs and the hit
    starts where it passes twice it; from then on the level is the one reached by ``ATTACK_S``
    before, and the hit starts where its rise begins, looked for up to ``ATTACK_S`` past frame
    ``n``: the loudness model's attack for a low sound outlasts ``GAP_S`` (a 50 Hz tone reads 0.56
    of its level over its first 0.1 s, 0.9 at 0.16 s), for the score's own level and for a hit's
    rise alike. With no hit, a climb under way at frame ``n`` (the score's swell, under twice its
    level) counts as opening too, so that its end is no event either."""
    attack_n = int(round(ATTACK_S / FRAME_S))
    early_n = max(int(early_n), 1)
    w = v[:max(n, 0) + attack_n]
    if n <= 0 or w.size == 0:
        return 0
    ref = np.maximum.accumulate(w)[np.clip(np.arange(w.size) - attack_n, early_n - 1, w.size - 1)]
    rise = np.flatnonzero(w + FLOOR > OPENING_RISE * (ref + FLOOR))
    if rise.size == 0:
        end = n
        while end < w.size and w[end] > w[end - 1]:
            end += 1
        return end
    hit = int(rise[0])
    if hit >= early_n + attack_n:
        below = np.flatnonzero(w[:hit] <= ref[hit])
        hit = int(below[-1]) + 1 if below.size else 0
    return min(n, hit)


def trailing_max(v: np.ndarray, n: int) -> np.ndarray:
    """Maximum of v[t - n + 1 .. t] at each t (the window clipped at the start), same shape and dtype.

    Numpy alone: scipy.ndimage's maximum_filter1d gives the same values but importing it costs
    about 0.35 s of CPU per process, more than the whole feature pass on a short clip.
    """
    if v.size == 0 or n <= 1:
        return v.copy()
    return sliding_window_view(np.concatenate([np.full(n - 1, v[0], v.dtype), v]), n).max(axis=1)



def trailing_median(v: np.ndarray, n: int) -> np.ndarray:
    """Median of v[t - n + 1 .. t] at each t (the window padded with the median of the first n
    values at the start), float64, same shape; no smoothing for n <= 1. Non-finite values count as
    0. A peak shorter than half the window goes, in the first frames too (a codec's start-up
    transient: padding with v[0] would hold it for (n - 1) // 2 frames more); a rise lasting
    longer passes, (n - 1) // 2 frames later."""
    x = np.where(np.isfinite(v), v, 0.0).astype(np.float64)
    if x.size == 0 or n <= 1:
        return x
    pad = np.full(n - 1, median(x[:n]))
    return median(sliding_window_view(np.concatenate([pad, x]), n), axis=1)
