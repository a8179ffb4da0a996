"""Sound scenes with known answers for the vibration rule (ALGORITHM.md section 2): what should
drive the chair (impacts, a rising engine rumble) and what should not (a steady music bed, speech,
silence). Each returns a :class:`~autohaptics.testing.scenes.Scene` without pictures (write it to a
.wav, or to a video container with a plain background) and, where it has them, the event times.

Levels are dBFS RMS (full scale = 1.0); the music bed sits about 26 dB below full scale, a film's
dialogue level, and the impacts about 18 dB above it.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from autohaptics.errors import ParameterError
from autohaptics.testing.scenes import IMPACT_LENGTH_S, Noise, Scene, Tone, impact

# a I-vi-IV-V progression in C, one chord a second, as (bass, three chord notes) in Hz
_CHORDS = ((130.81, 261.63, 329.63, 392.00), (110.00, 220.00, 261.63, 329.63),
           (87.31, 174.61, 220.00, 261.63), (98.00, 196.00, 246.94, 293.66))
IMPACT_TIMES_S = (3.0, 6.5, 9.5)


def music_bed(t0: float, t1: float, *, level_dbfs: float = -32.0) -> list[Tone]:
    """A steady chord progression with a walking bass, notes every 0.5 s: a film score's bed.

    level_dbfs : level of each note (four at a time: about 6 dB more in all).
    """
    out: list[Tone] = []
    t, k = t0, 0
    while t < t1 - 1e-9:
        end = min(t + 0.5, t1)
        chord = _CHORDS[(k // 2) % len(_CHORDS)]
        bass = chord[0] * (1.5 if k % 2 else 1.0)  # root, then fifth
        for f in (bass, *chord[1:]):
            out.append(Tone(t, end, f, level_dbfs=level_dbfs, ramp_s=0.04))
        t, k = end, k + 1
    return out


def music_with_impacts(duration_s: float = 12.0) -> Scene:
    """The music bed for ``duration_s`` with three loud impacts at :data:`IMPACT_TIMES_S`."""
    audio: list[Tone | Noise] = music_bed(0.0, duration_s)
    for i, t in enumerate(IMPACT_TIMES_S):
        audio += impact(t, seed=i + 1)
    return Scene(duration_s=duration_s, audio=tuple(audio), name="music_impacts")


def speech(duration_s: float = 12.0, *, level_dbfs: float = -24.0, seed: int = 0) -> Scene:
    """Speech-like sound: voiced syllables (a harmonic series on a 110-180 Hz voice, shaped by two
    formants) of 0.1-0.25 s, some preceded by a hissing consonant, in words of 1-4 syllables with
    pauses between words and longer ones between phrases."""
    rng = np.random.default_rng(seed)
    audio: list[Tone | Noise] = []
    t = 0.2
    while t < duration_s - 0.5:
        for _ in range(int(rng.integers(1, 5))):  # one word
            if rng.random() < 0.3:
                audio.append(Noise(t, t + 0.07, level_dbfs=level_dbfs - 10.0, seed=int(rng.integers(1 << 30))))
                t += 0.07
            length = float(rng.uniform(0.1, 0.25))
            audio += _vowel(t, t + length, f0=float(rng.uniform(110, 180)), level_dbfs=level_dbfs,
                            formants=(float(rng.uniform(300, 800)), float(rng.uniform(900, 2400))))
            t += length + 0.02
        t += float(rng.uniform(0.08, 0.25)) if rng.random() < 0.8 else float(rng.uniform(0.4, 0.8))
    return Scene(duration_s=duration_s, audio=tuple(a for a in audio if a.t1 <= duration_s), name="speech")


def _vowel(t0: float, t1: float, *, f0: float, level_dbfs: float, formants: tuple[float, float]) -> list[Tone]:
    """One voiced syllable: the harmonics of ``f0`` up to 4 kHz, each weighted by the two formants."""
    k = np.arange(1, int(4000 // f0) + 1)
    f = k * f0
    w = sum(1.0 / (1.0 + ((f - fc) / (0.15 * fc)) ** 2) for fc in formants) + 0.05
    w = w / np.sqrt(np.sum(w * w))  # the syllable's total level is level_dbfs
    return [Tone(t0, t1, float(fk), level_dbfs=level_dbfs + 20.0 * float(np.log10(wk)), ramp_s=0.02)
            for fk, wk in zip(f, w) if wk > 0.03]


def rising_rumble(duration_s: float = 10.0, *, start_s: float = 1.0, from_dbfs: float = -40.0,
                  to_dbfs: float = -8.0) -> Scene:
    """An engine rumble (35, 70 and 105 Hz with a faint noise bed) from ``start_s`` to the end,
    its level gliding from ``from_dbfs`` to ``to_dbfs``: it should vibrate ever harder."""
    audio = [Tone(start_s, duration_s, f, level_dbfs=from_dbfs - d, level_end_dbfs=to_dbfs - d, ramp_s=0.05)
             for f, d in ((35.0, 0.0), (70.0, 4.0), (105.0, 9.0))]
    audio.append(Noise(start_s, duration_s, level_dbfs=from_dbfs - 18.0, level_end_dbfs=to_dbfs - 18.0,
                       colour="pink", seed=5, ramp_s=0.05))
    return Scene(duration_s=duration_s, audio=tuple(audio), name="rumble")


def booms_and_blips(duration_s: float = 180.0, *, floor_db: float | None = None, seed: int = 0) -> Scene:
    """Booms (:func:`impact`) every 6-10 s, each followed 2-4 s later by a 0.1 s blip (a 1-3 kHz
    tone at -30 dBFS), over exact digital silence, or with ``floor_db`` over white noise at that
    level (dBFS RMS, e.g. -100, below a 16-bit LSB: a master's noise floor). Why: recursive filters
    ring down towards subnormal floats over exact silence (docs/BENCHMARKS.md, "Digital silence");
    the floor version is the same work without that. Write it with a float codec (pcm_f32le): a
    lossy or 16-bit one may round the floor to silence.
    """
    rng = np.random.default_rng(seed)
    audio: list[Tone | Noise] = [] if floor_db is None else [noise_floor(duration_s, floor_db, seed=seed)]
    t, k = 1.0, 0
    while t + IMPACT_LENGTH_S < duration_s:
        audio += impact(t, level_dbfs=float(rng.uniform(-14.0, -6.0)), seed=seed + k + 1)
        blip = t + float(rng.uniform(2.0, 4.0))
        if blip + 0.1 < duration_s:
            audio.append(Tone(blip, blip + 0.1, float(rng.uniform(1000.0, 3000.0)), level_dbfs=-30.0, ramp_s=0.01))
        t += float(rng.uniform(6.0, 10.0))
        k += 1
    name = "booms_blips" if floor_db is None else f"booms_blips_floor{floor_db:g}"
    return Scene(duration_s=duration_s, audio=tuple(audio), name=name)


def noise_floor(duration_s: float, floor_db: float, *, seed: int = 0) -> Noise:
    """Steady white noise at ``floor_db`` dBFS RMS over the whole clip: a recording's noise floor."""
    return Noise(0.0, duration_s, level_dbfs=float(floor_db), colour="white", seed=10_000 + seed, ramp_s=0.0)


def cut_in(scene: Scene, start_s: float, duration_s: float | None = None) -> Scene:
    """The sound of ``scene`` as a file that begins ``start_s`` into it (a reel or trailer cut
    mid-score): its audio events shifted back by ``start_s``, those under way at the cut starting
    abruptly at 0 s (no attack ramp), for ``duration_s`` (default: the rest). Pictures are dropped."""
    end = scene.duration_s - start_s if duration_s is None else float(duration_s)
    if not (0.0 <= start_s and 0.0 < end <= scene.duration_s - start_s + 1e-9):
        raise ParameterError(f"cannot cut {end!r} s at {start_s!r} s from a {scene.duration_s} s scene")
    audio = []
    for ev in scene.audio:
        t0, t1 = ev.t0 - start_s, min(ev.t1 - start_s, end)
        if t1 <= 0.0 or t0 >= end:
            continue
        if t0 < 0.0 and ev.level_end_dbfs is not None:  # the glide's level at the cut
            share = (start_s - ev.t0) / (ev.t1 - ev.t0)
            level = ev.level_dbfs + share * (ev.level_end_dbfs - ev.level_dbfs)
            ev = dataclasses.replace(ev, level_dbfs=level)
        audio.append(dataclasses.replace(ev, t0=0.0, t1=t1, ramp_s=0.0) if t0 < 0.0
                     else dataclasses.replace(ev, t0=t0, t1=t1))
    return Scene(duration_s=end, audio=tuple(audio), name=f"{scene.name}_from_{start_s:g}s")


def silence(duration_s: float = 5.0) -> Scene:
    """Nothing at all: the chair must stay still."""
    return Scene(duration_s=duration_s, name="silence")
