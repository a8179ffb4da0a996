"""Exact digital silence after loud sound: no recursive state and no output of the audio stages
holds a subnormal double (0 < |x| < 2.2e-308, the values Intel CPUs compute ~100x slower), counted
in every state and intermediate, through the stage functions, the public feature pass and the
kernels' plain Python source; the states end exactly at 0 (flushed below kernels.FLUSH_FLOOR)."""

from __future__ import annotations

import numpy as np
import pytest

from autohaptics.intensity import features as F
from autohaptics.intensity import filterbank as fb
from autohaptics.intensity import kernels
from autohaptics.intensity import loudness as L
from autohaptics.intensity import low_energy as LE
from autohaptics.intensity import zwicker as zw
from autohaptics.testing import render_audio
from autohaptics.testing.sounds import impact
from autohaptics.testing.scenes import Scene

FS = L.SAMPLE_RATE_HZ
TINY = np.finfo(np.float64).tiny
BOOM_S = 1.0
SILENCE_S = 60.0  # long enough for every state to ring down past 1e-308 without the flush (~53 s the slowest)


def subnormals(*arrays) -> int:
    """How many values of ``arrays`` (nested tuples allowed) are subnormal doubles."""
    n = 0
    for a in arrays:
        if isinstance(a, (tuple, list)):
            n += subnormals(*a)
        else:
            a = np.asarray(a, dtype=np.float64)
            n += int(np.count_nonzero((a != 0.0) & (np.abs(a) < TINY)))
    return n


def boom_then_silence() -> np.ndarray:
    """A loud impact (45 Hz thump and pink crack, Pa at 48 kHz) then ``SILENCE_S`` of exact zeros."""
    scene = Scene(duration_s=BOOM_S, audio=tuple(impact(0.1, level_dbfs=-6.0)))
    boom = render_audio(scene, sample_rate=FS, channels=1)[0].astype(np.float64) * 3.5566
    assert np.abs(boom).max() > 1.0
    return np.concatenate([boom, np.zeros(int(SILENCE_S * FS))])


def seconds(x: np.ndarray, step_s: float = 1.0):
    n = int(step_s * FS)
    return [x[i:i + n] for i in range(0, x.shape[0], n)]


@pytest.mark.parametrize("method", L.LOUDNESS_METHODS)
def test_no_subnormal_in_any_loudness_state_or_intermediate(method):
    """Each second of silence, through the stages of ISO 532-1 as loudness_update composes them."""
    params = L.LoudnessParams(method=method)
    plan = fb.plan(method)
    state = L.init_state(params=params)
    counts = []
    for chunk in seconds(boom_then_silence()):
        k_start = fb.ceil_div(state.n_in, fb.LEVEL_STEP)
        ms, bank, smooth, stages = fb.filter_bank(chunk, state.n_in, state.bank, state.smooth, state.stages, plan)
        core = zw.core_loudness(ms, diffuse=False)
        decayed, decay = zw.nonlinear_decay(core, state.decay, plan, started=k_start > 0)
        total, specific = zw.slopes(decayed, zw.output_rows(k_start, core.shape[1]))
        weighted, weighting = zw.temporal_weighting(total, state.weighting, started=k_start > 0)
        counts.append(subnormals(ms, bank, smooth, stages, core, decayed, decay, total, specific, weighted, weighting))
        _, state = L.loudness_update(chunk, state, params=params)
    assert counts == [0] * len(counts)
    held = np.concatenate([np.ravel(a) for a in (*state.bank, *state.smooth, *state.stages, state.decay,
                                                 state.weighting)])
    # what still rings (the 2 kHz bands' slow poles; the smoothers hold their squares) is far from 1e-308
    assert np.abs(held[held != 0.0]).min(initial=1.0) > 1e100 * TINY
    assert np.count_nonzero(state.bank[0]) == 0  # 48 kHz band filters: flushed to exactly 0, and kept there
    assert np.count_nonzero(state.decay) == 0 and np.count_nonzero(state.weighting) == 0


def test_no_subnormal_through_the_public_feature_pass():
    """The same boom then silence through autohaptics.intensity.features, chunk by chunk."""
    x = (boom_then_silence() / 3.5566).astype(np.float32)
    state = F.init_state(step_ms=2)
    counts = []
    outputs = []
    for chunk in seconds(x):
        part, state = F.process_chunk(chunk, state)
        outputs.append(part)
        s = state.loudness
        counts.append(subnormals(s.bank, s.smooth, s.stages, s.decay, s.weighting, state.low_energy.zi,
                                 state.low_energy.tail, state.pending_n, state.pending_spec,
                                 part.loudness, part.sharpness, part.booming, part.low_energy, part.loudness_iso))
    assert counts == [0] * len(counts)
    assert sum(p.n_frames for p in outputs) == int((BOOM_S + SILENCE_S) / 0.02)
    assert max(float(p.loudness.max(initial=0.0)) for p in outputs[:1]) > 10.0  # the boom is loud
    assert np.count_nonzero(state.low_energy.zi) == 0


def test_low_energy_state_and_frames_hold_no_subnormal():
    frames, state = LE.low_energy_update(boom_then_silence(), LE.init_state())
    assert subnormals(frames, state.zi, state.tail) == 0
    assert frames.max() > 0 and np.count_nonzero(state.zi) == 0


def test_stationary_loudness_of_a_signal_ending_in_silence_is_unchanged_by_the_flush():
    """bank_mean_square flushes as well; ISO's stationary loudness of a tone is unaffected."""
    t = np.arange(FS) / FS
    tone = np.sqrt(2) * 2e-5 * 10 ** (60 / 20) * np.sin(2 * np.pi * 1000 * t)
    n_tone, _ = L.loudness_stationary(tone, skip_s=0.2)
    n_tail, _ = L.loudness_stationary(np.concatenate([tone, np.zeros(20 * FS)]), skip_s=0.2)
    assert n_tone == pytest.approx(4.0, rel=0.05)  # 60 dB at 1 kHz: 4 sone
    assert n_tail < n_tone


# ------------------------------------------------------------------ the plain Python source
# A band-pass section pair with poles at radius 0.5: a loud impulse rings down past 1e-308 in ~1000
# samples, so a few thousand samples of Python show whether the source flushes.
_SOS = np.array([[1.0, 0.0, -1.0, 1.0, 0.0, 0.25], [1.0, 0.0, -1.0, 1.0, -0.5, 0.25]])


def _impulse(n: int = 4000) -> np.ndarray:
    x = np.zeros(n)
    x[0] = 1.0e3
    return x


def test_python_bank_square_smooth_flushes():
    sos = np.stack([_SOS[0], _SOS[1], _SOS[0]])[None]
    zi_sos, zi_smooth = np.zeros((1, 3, 2)), np.zeros((1, 3))
    out = np.empty((1, fb.ceil_div(4000, 24)))
    kernels.bank_square_smooth.py_func(_impulse(), sos, np.ones(1), np.array([0.5]), zi_sos, zi_smooth, 0, 24, out)
    assert out[0, 0] > 0 and subnormals(out, zi_sos, zi_smooth) == 0
    assert np.count_nonzero(zi_sos) == 0 and np.count_nonzero(zi_smooth) == 0


def test_python_sos_decimate_flushes():
    zi = np.zeros((2, 2))
    out = np.empty(4000)
    kernels.sos_decimate.py_func(_impulse(), _SOS, zi, 0, 1, out)
    assert out[0] > 0 and subnormals(out, zi) == 0 and np.count_nonzero(zi) == 0


def test_python_first_order_flushes():
    zi = np.zeros(1)
    out = np.empty(4000)
    kernels.first_order.py_func(_impulse(), 0.5, 0.0, 0.5, zi, out)
    assert out[0] > 0 and subnormals(out, zi) == 0 and zi[0] == 0.0


def test_python_nonlinear_decay_flushes():
    """ISO's decay network after 10 sone, 2 sub-steps per 0.5 ms, then 25 s of zeros: its slowest
    time constant (75 ms) takes ~17 s from 10 sone to the floor, ~53 s to 1e-308."""
    plan = fb.plan("fast")
    core = np.zeros((1, 50_000))
    core[0, :10] = 10.0
    uo, u2, prev, started = np.zeros(1), np.zeros(1), np.zeros(1), np.zeros(1, dtype=np.int64)
    out = np.empty_like(core)
    kernels.nonlinear_decay.py_func(core, plan.nl_coef, plan.nl_iterations, 1e-4, uo, u2, prev, started, out)
    assert out[0, 0] == 10.0 and subnormals(out, uo, u2) == 0
    assert uo[0] == 0.0 and u2[0] == 0.0


def test_flush_floor_is_far_below_the_threshold_in_quiet_and_its_square_is_normal():
    assert kernels.FLUSH_FLOOR ** 2 > 1e100 * TINY  # a squared state above the floor stays normal
    assert kernels.FLUSH_FLOOR < 1e-60 * 2e-5  # 2e-5 Pa: 0 dB SPL


# ------------------------------------------------------------------ decoded from files
# Every decode path (codec, rate through the resampler, layout) into the public feature pass: a
# codec's tail after a boom (Opus leaves float32 subnormal samples), a glide into the float32
# subnormals, a float64 fade into the float64 subnormals (f64 PCM, downmixed in float64).
def _write_f64_wav(path, x: np.ndarray, rate: int) -> None:
    """Mono float64 samples ``x`` (digital full scale) as a pcm_f64le .wav, written by PyAV."""
    import av

    with av.open(str(path), "w", format="wav") as out:
        stream = out.add_stream("pcm_f64le", rate=rate, layout="mono")
        for i in range(0, x.size, 4096):
            frame = av.AudioFrame.from_ndarray(np.ascontiguousarray(x[None, i:i + 4096]), format="dbl", layout="mono")
            frame.sample_rate = rate
            for packet in stream.encode(frame):
                out.mux(packet)
        for packet in stream.encode(None):
            out.mux(packet)


def _decoded_case(tmp_path, case: str):
    """(the file, whether its decoded float32 samples hold subnormals) for one decode path."""
    from autohaptics.testing import Tone, write_scene

    boom = Scene(duration_s=8.0, audio=tuple(impact(0.1, level_dbfs=-6.0)))
    if case == "opus_48k_stereo_boom":  # the decoder's tail after the boom: float32 subnormal samples
        return write_scene(tmp_path / "boom.webm", boom, video=False, channels=2), True
    if case == "aac_44k1_5.1_boom":
        return write_scene(tmp_path / "boom.m4a", boom, video=False, sample_rate=44100, channels=6), False
    if case == "f32_22k05_7.1_glide":  # -6 dBFS to -1000 dB by 6 s: float32 subnormal from ~4.6 s, 0 after ~5.4 s
        glide = Scene(duration_s=8.0, audio=(Tone(0.1, 6.0, 440.0, level_dbfs=-6.0, level_end_dbfs=-1000.0),))
        return write_scene(tmp_path / "glide.wav", glide, video=False, audio_codec="pcm_f32le", sample_rate=22050,
                           channels=8), True
    rate = 96000  # "f64_96k_mono_fade": noise x exp(-t / 12 ms): 1e-308 at 8.5 s, 0 after ~9 s
    t = np.arange(10 * rate) / rate
    x = np.random.default_rng(0).standard_normal(t.size) * 0.1 * np.exp(-t / 0.012)
    assert np.count_nonzero((x != 0) & (np.abs(x) < TINY)) > 10_000  # the file holds float64 subnormals
    _write_f64_wav(tmp_path / "fade.wav", x, rate)
    return tmp_path / "fade.wav", True


@pytest.mark.parametrize("case", ["opus_48k_stereo_boom", "aac_44k1_5.1_boom", "f32_22k05_7.1_glide",
                                  "f64_96k_mono_fade"])
def test_no_subnormal_state_from_any_decode_path(tmp_path, case):
    from autohaptics.media import iter_audio

    path, tiny_samples = _decoded_case(tmp_path, case)
    state = F.init_state()
    counts, in_samples = [], 0
    for chunk in iter_audio(path, chunk_s=1.0):
        assert chunk.dtype == np.float32 and np.isfinite(chunk).all()
        in_samples += int(np.count_nonzero((chunk != 0) & (np.abs(chunk) < np.finfo(np.float32).tiny)))
        part, state = F.process_chunk(chunk, state)
        s = state.loudness
        counts.append(subnormals(s.bank, s.smooth, s.stages, s.decay, s.weighting, state.low_energy.zi,
                                 state.pending_spec, part.loudness, part.sharpness, part.booming, part.low_energy))
    assert counts == [0] * len(counts)
    assert (in_samples > 0) == tiny_samples  # the decoded samples reached the float32 subnormals
    assert np.count_nonzero(state.loudness.bank[0]) == 0 and np.count_nonzero(state.low_energy.zi) == 0
