"""The four psychoacoustic audio features on the 20 ms frame grid, streaming (ALGORITHM.md
section 2): loudness (sone), sharpness (acum), booming index, low-frequency energy (Pa^2).

Recipe per chunk (float32 mono 48 kHz, digital full scale, as :func:`autohaptics.media.iter_audio`
yields): calibrate (``pa_per_unit``: sample -> Pa) -> :mod:`autohaptics.intensity.loudness` (N(t) and
N'(z, t) every 2 ms) and :mod:`autohaptics.intensity.low_energy` -> ``frame_values``: the ten 2 ms values of each
20 ms frame become one frame value -> :mod:`autohaptics.intensity.sharpness`, :mod:`autohaptics.intensity.booming`.

How a 20 ms frame value is formed (frame f covers [0.02 f, 0.02 (f + 1)) s, i.e. input samples
960 f .. 960 f + 959, and holds the 2 ms ISO samples k = 10 f .. 10 f + 9 at t = 0.002 k):

- loudness: the MAX of the frame's ten N(t) values (``frame_loudness="max"``, default; ISO's
  N(t) is already temporally integrated with 3.5 ms and 70 ms, and a peak reading keeps a 20 ms
  impact at its true loudness, in line with the tick taking the max of its frames) or their
  MEAN (``frame_loudness="mean"``).
- sharpness and booming: computed from the frame's MEAN specific loudness N'(z) (the mean of
  its ten 2 ms patterns); their loudness denominator is the area of that same mean pattern.
- low_energy: the mean square of the low-passed pressure over the frame's 960 samples.
- The last frame may be partial (n_samples not a multiple of 960): it uses the 2 ms values and
  samples it has (at least one). n_frames = ceil(n_samples / 960); 1 sample gives 1 frame.

Streaming: :func:`init_state` -> :func:`process_chunk` per chunk (returns the frames completed so
far) -> :func:`finish` (the trailing partial frame). :func:`compute_audio_features` runs that
loop over an iterable of chunks. Chunked processing equals whole processing exactly.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable
from dataclasses import dataclass
from typing import ClassVar

import numpy as np

from autohaptics.intensity import booming as _booming
from autohaptics.intensity import loudness as _loudness
from autohaptics.intensity import low_energy as _low_energy
from autohaptics.intensity import sharpness as _sharpness
from autohaptics.errors import ParameterError
from autohaptics.records import ANALYSIS, Record, param
from autohaptics.progress import CancelToken, check_cancel
from autohaptics.timebase import ANALYSIS_SAMPLE_RATE, FRAME_S, SAMPLES_PER_FRAME

FRAME_LOUDNESS = ("max", "mean")
STEPS_MS = (2, 20)
STEPS_PER_FRAME = SAMPLES_PER_FRAME // _loudness.SAMPLES_PER_STEP  # 10 ISO samples per frame
FEATURE_NAMES = ("loudness", "sharpness", "booming", "low_energy")
_N_BARK = _loudness.Z_BARK.shape[0]


@dataclass(frozen=True)
class AudioFeatureParams(Record):
    """Everything that changes the audio features (JSON-serialisable via dataclasses.asdict).

    pa_per_unit : float, Pa per digital unit (default 3.5566: 0 dBFS rms = 105 dB SPL, i.e. the
        cinema calibration pink noise at -20 dBFS rms = 85 dB SPL).
    field : "free" (default) or "diffuse"; the sound field of ISO 532-1.
    loudness_method : "fast" (default; multirate filter bank) or "iso" (the standard's filters at
        48 kHz; the reference preset). See :mod:`autohaptics.intensity.loudness`.
    booming_variant : "hatano" (default, linear Hatano-type index) or "paper" (thesis eq. 3.3).
    low_energy_cutoff_hz : float, Hz; low-pass corner of the low-frequency energy (default 215).
    sharpness_min_loudness_sone : float, sone; sharpness is 0 below this loudness (default 0.1).
    booming_min_loudness_sone : float, sone; booming is 0 below this loudness (default 0.1).
    booming_lf_cutoff_hz : float, Hz; upper frequency of the booming index's N_LF (default 280).
    low_energy_order : int; Butterworth order of the low-energy low-pass (default 4).
    frame_loudness : "max" (default) or "mean" of the ten 2 ms N(t) values of a frame.
    """

    STAGE: ClassVar[str] = ANALYSIS
    GROUP: ClassVar[str] = "audio"

    pa_per_unit: float = param(3.5566, gt=0.0, unit="Pa")
    field: str = "free"
    loudness_method: str = "fast"
    booming_variant: str = "hatano"
    low_energy_cutoff_hz: float = 215.0
    sharpness_min_loudness_sone: float = 0.1
    booming_min_loudness_sone: float = 0.1
    booming_lf_cutoff_hz: float = 280.0
    low_energy_order: int = 4
    frame_loudness: str = param("max", choices=FRAME_LOUDNESS)

    def check(self) -> None:
        self.loudness_params()
        self.sharpness_params()
        self.booming_params()
        self.low_energy_params()

    def loudness_params(self) -> _loudness.LoudnessParams:
        return _loudness.LoudnessParams(field=self.field, method=self.loudness_method)

    def sharpness_params(self) -> _sharpness.SharpnessParams:
        return _sharpness.SharpnessParams(min_loudness_sone=self.sharpness_min_loudness_sone)

    def booming_params(self) -> _booming.BoomingParams:
        return _booming.BoomingParams(variant=self.booming_variant, lf_cutoff_hz=self.booming_lf_cutoff_hz,
                                      min_loudness_sone=self.booming_min_loudness_sone)

    def low_energy_params(self) -> _low_energy.LowEnergyParams:
        return _low_energy.LowEnergyParams(cutoff_hz=self.low_energy_cutoff_hz, order=self.low_energy_order)


@dataclass
class AudioFeatures:
    """Per-frame features on the 20 ms grid (all float64 [shape=(n_frames,)]).

    t_s : frame start times, s (0.02 f).
    loudness : sone; sharpness : acum; booming : sone ("hatano") or dimensionless ("paper");
    low_energy : Pa^2 (mean square below the cutoff).
    n_samples : input samples (48 kHz) these frames cover; for a partial result from
        :func:`process_chunk`, the samples consumed so far.
    t_iso_s, loudness_iso : only with ``step_ms=2``: N(t) on the ISO 2 ms grid, s and sone
        [shape=(ceil(n_samples / 96),)]; otherwise None.
    """

    t_s: np.ndarray
    loudness: np.ndarray
    sharpness: np.ndarray
    booming: np.ndarray
    low_energy: np.ndarray
    n_samples: int
    t_iso_s: np.ndarray | None = None
    loudness_iso: np.ndarray | None = None

    @property
    def n_frames(self) -> int:
        return int(self.t_s.shape[0])


@dataclass(frozen=True)
class AudioFeatureState:
    """Streaming state (never mutated): sub-stage states and the 2 ms values of the frame in
    progress. n_samples : samples consumed; frames_out : frames already returned."""

    n_samples: int
    frames_out: int
    step_ms: int
    loudness: _loudness.LoudnessState
    low_energy: _low_energy.LowEnergyState
    pending_n: np.ndarray  # [shape=(k,)], sone
    pending_spec: np.ndarray  # [shape=(k, 240)], sone/Bark


# ------------------------------------------------------------------ streaming API
def init_state(params: AudioFeatureParams = AudioFeatureParams(), *, step_ms: int = 20) -> AudioFeatureState:
    """A fresh state (silence before t = 0). ``step_ms=2`` also returns N(t) on the ISO grid."""
    if step_ms not in STEPS_MS:
        raise ParameterError(f"step_ms must be one of {STEPS_MS}, got {step_ms!r}")
    return AudioFeatureState(
        n_samples=0, frames_out=0, step_ms=int(step_ms),
        loudness=_loudness.init_state(params=params.loudness_params()),
        low_energy=_low_energy.init_state(params=params.low_energy_params()),
        pending_n=np.zeros(0), pending_spec=np.zeros((0, _loudness.Z_BARK.shape[0])),
    )


def process_chunk(x: np.ndarray, state: AudioFeatureState, *,
                  params: AudioFeatureParams = AudioFeatureParams()) -> tuple[AudioFeatures, AudioFeatureState]:
    """Feed one chunk; return the frames it completed and the new state.

    x : np.ndarray [shape=(n,)], mono 48 kHz samples in digital full scale (float32 usually).
    Raises ParameterError for a non-1-D chunk or non-finite samples (naming their count).
    """
    p = _calibrate(x, params)
    lres, l_state = _loudness.loudness_update(p, state.loudness, params=params.loudness_params())
    le, le_state = _low_energy.low_energy_update(p, state.low_energy, params=params.low_energy_params())
    n_samples = state.n_samples + p.shape[0]
    pend_n = np.concatenate([state.pending_n, lres.loudness])
    pend_spec = np.concatenate([state.pending_spec, lres.specific]) if lres.specific.size else state.pending_spec
    k = n_samples // SAMPLES_PER_FRAME - state.frames_out
    used = k * STEPS_PER_FRAME
    out = frame_values(pend_n[:used].reshape(k, STEPS_PER_FRAME), pend_spec[:used].reshape(k, STEPS_PER_FRAME, _N_BARK),
                  le, state.frames_out, n_samples, params)
    if state.step_ms == 2:
        out.t_iso_s, out.loudness_iso = lres.t_s, lres.loudness
    new = AudioFeatureState(n_samples=n_samples, frames_out=state.frames_out + k, step_ms=state.step_ms,
                            loudness=l_state, low_energy=le_state,
                            pending_n=pend_n[used:].copy(), pending_spec=pend_spec[used:].copy())
    return out, new


def finish(state: AudioFeatureState, *, params: AudioFeatureParams = AudioFeatureParams()) -> AudioFeatures:
    """The trailing partial frame (0 or 1 frame). Raises ParameterError if no sample was fed:
    an empty track has no frames to give (an empty clip is an error, never 0 frames)."""
    if state.n_samples == 0:
        raise ParameterError("no audio samples: an empty track has no audio features")
    le = _low_energy.low_energy_finish(state.low_energy)
    k = le.shape[0]
    j = state.pending_n.shape[0] if k else 0
    out = frame_values(state.pending_n[None, :j] if k else np.zeros((0, 1)),
                  state.pending_spec[None, :j] if k else np.zeros((0, 1, state.pending_spec.shape[1])),
                  le, state.frames_out, state.n_samples, params)
    if state.step_ms == 2:
        out.t_iso_s, out.loudness_iso = np.zeros(0), np.zeros(0)
    return out


def compute_audio_features(chunks: Iterable[np.ndarray], *, params: AudioFeatureParams = AudioFeatureParams(),
                           progress: Callable[[float], None] | None = None, cancel: CancelToken | None = None,
                           step_ms: int = 20) -> AudioFeatures:
    """Run the streaming features over ``chunks`` (e.g. ``media.iter_audio(path)``).

    progress : called after each chunk with the seconds of audio processed so far.
    cancel : a token with ``is_set()``; checked before each chunk (raises CancelledError).
    step_ms : 20 (default) or 2 (also N(t) on the ISO 2 ms grid in ``loudness_iso``).
    Returns :class:`AudioFeatures` with ceil(n_samples / 960) frames. Raises ParameterError for
    an empty input or non-finite samples.
    """
    state = init_state(params, step_ms=step_ms)
    parts = []
    for chunk in chunks:
        check_cancel(cancel)
        part, state = process_chunk(chunk, state, params=params)
        parts.append(part)
        if progress is not None:
            progress(state.n_samples / ANALYSIS_SAMPLE_RATE)
    check_cancel(cancel)
    parts.append(finish(state, params=params))
    return concatenate(parts)


def concatenate(parts: list[AudioFeatures]) -> AudioFeatures:
    """Join consecutive partial results (from process_chunk / finish) into one."""
    if not parts:
        raise ParameterError("nothing to concatenate: no partial audio features")
    cat = lambda name: np.concatenate([getattr(p, name) for p in parts])  # noqa: E731
    iso = all(p.loudness_iso is not None for p in parts)
    return AudioFeatures(t_s=cat("t_s"), loudness=cat("loudness"), sharpness=cat("sharpness"),
                         booming=cat("booming"), low_energy=cat("low_energy"), n_samples=parts[-1].n_samples,
                         t_iso_s=cat("t_iso_s") if iso else None, loudness_iso=cat("loudness_iso") if iso else None)


# ------------------------------------------------------------------ private steps
def _calibrate(x, params: AudioFeatureParams) -> np.ndarray:
    """Digital full scale -> Pa, float64 [shape=(n,)]."""
    x = np.asarray(x)
    if x.ndim != 1 or x.dtype.kind not in "fiu":
        raise ParameterError(f"an audio chunk must be a real 1-D array [shape=(n,)], got {x.dtype} {x.shape}")
    bad = ~np.isfinite(x)
    if bad.any():
        raise ParameterError(f"audio chunk holds {int(bad.sum())} non-finite sample(s) (NaN or inf) "
                             f"among {x.shape[0]}")
    return x.astype(np.float64) * float(params.pa_per_unit)


def frame_values(n_steps: np.ndarray, spec_steps: np.ndarray, low_energy: np.ndarray, first_frame: int,
                 n_samples: int, params: AudioFeatureParams) -> AudioFeatures:
    """Frame values from the 2 ms values of k frames.

    n_steps : [shape=(k, j)] N(t), sone; spec_steps : [shape=(k, j, 240)] N'(z, t), sone/Bark;
    low_energy : [shape=(k,)] Pa^2.
    """
    k = n_steps.shape[0]
    if params.frame_loudness == "max":
        loud = n_steps.max(axis=1) if k else np.zeros(0)
    else:
        loud = n_steps.mean(axis=1) if k else np.zeros(0)
    spec = np.zeros((k, spec_steps.shape[-1]))
    for i in range(spec_steps.shape[1]):  # sequential sum: the same bits whatever k (chunked == whole)
        spec += spec_steps[:, i]
    spec /= max(1, spec_steps.shape[1])
    return AudioFeatures(
        t_s=np.arange(first_frame, first_frame + k, dtype=np.float64) * FRAME_S,
        loudness=np.maximum(loud, 0.0),
        sharpness=_sharpness.sharpness(specific=spec, params=params.sharpness_params()),
        booming=_booming.booming(specific=spec, params=params.booming_params()),
        low_energy=low_energy,
        n_samples=n_samples,
    )
