"""The streaming audio-feature runner: the interface the pipeline calls, frame rules, known
answers through the whole chain, streaming equality, progress, cancellation, errors."""

from __future__ import annotations

import dataclasses
import json
import threading

import numpy as np
import pytest

from autohaptics.intensity import features as af
from autohaptics.intensity import loudness as L
from autohaptics.errors import CancelledError, ParameterError
from autohaptics.timebase import FRAME_S, frame_times_s

FS = 48_000
PA = af.AudioFeatureParams().pa_per_unit


def tone(f_hz: float, db_spl: float, dur_s: float = 1.0) -> np.ndarray:
    """Digital samples (film calibration) of a tone at ``db_spl``."""
    t = np.arange(int(round(dur_s * FS))) / FS
    return (np.sqrt(2.0) * 2e-5 * 10 ** (db_spl / 20) / PA * np.sin(2 * np.pi * f_hz * t)).astype(np.float32)


def steady(x: np.ndarray) -> np.ndarray:
    return np.median(x[25:])


def test_params_defaults_and_json():
    p = af.AudioFeatureParams()
    assert (p.pa_per_unit, p.field, p.loudness_method, p.booming_variant) == (3.5566, "free", "fast", "hatano")
    assert (p.low_energy_cutoff_hz, p.sharpness_min_loudness_sone) == (215.0, 0.1)
    d = dataclasses.asdict(p)
    assert af.AudioFeatureParams(**json.loads(json.dumps(d))) == p


@pytest.mark.parametrize("kwargs, match", [
    ({"pa_per_unit": 0.0}, "pa_per_unit"), ({"pa_per_unit": float("nan")}, "pa_per_unit"),
    ({"field": "near"}, "field"), ({"loudness_method": "x"}, "method"), ({"booming_variant": "x"}, "variant"),
    ({"low_energy_cutoff_hz": -1.0}, "cutoff"), ({"frame_loudness": "median"}, "frame_loudness"),
    ({"sharpness_min_loudness_sone": -0.1}, "min_loudness"),
])
def test_params_are_validated(kwargs, match):
    with pytest.raises(ParameterError, match=match):
        af.AudioFeatureParams(**kwargs)


@pytest.mark.parametrize("n, frames", [(1, 1), (959, 1), (960, 1), (961, 2), (48_000, 50), (48_001, 51)])
def test_frame_count_and_grid(n, frames):
    f = af.compute_audio_features([np.full(n, 0.01, np.float32)])
    assert f.n_frames == frames and f.n_samples == n
    np.testing.assert_array_equal(f.t_s, frame_times_s(frames))
    for name in af.FEATURE_NAMES:
        x = getattr(f, name)
        assert x.dtype == np.float64 and x.shape == (frames,)
        assert np.isfinite(x).all() and (x >= 0).all()
    assert f.loudness_iso is None


def test_known_answers_through_the_chain():
    n1k40 = af.compute_audio_features([tone(1000, 40)])
    n1k50 = af.compute_audio_features([tone(1000, 50)])
    assert steady(n1k40.loudness) == pytest.approx(1.0, rel=0.1)
    assert steady(n1k50.loudness) / steady(n1k40.loudness) == pytest.approx(2.0, rel=0.1)
    low = af.compute_audio_features([tone(60, 80)])
    high = af.compute_audio_features([tone(4000, 70)])
    assert steady(low.booming) > 1.0 and steady(high.booming) < 0.01
    assert steady(low.sharpness) < 0.5 and steady(high.sharpness) > 2.5
    e100 = af.compute_audio_features([tone(100, 70)]).low_energy
    e2k = af.compute_audio_features([tone(2000, 70)]).low_energy
    assert steady(e100) > 1e5 * steady(e2k)
    assert steady(e100) == pytest.approx((2e-5 * 10 ** 3.5) ** 2, rel=0.05)  # 70 dB SPL in Pa^2


def test_silence_gives_exact_zeros():
    f = af.compute_audio_features([np.zeros(10_000, np.float32)])
    for name in af.FEATURE_NAMES:
        assert np.all(getattr(f, name) == 0.0)


def test_frame_loudness_max_versus_mean_and_iso_grid():
    x = np.concatenate([np.zeros(FS // 2, np.float32), tone(1000, 80, 0.005), np.zeros(FS // 2, np.float32)])
    peak = af.compute_audio_features([x], step_ms=2)
    mean = af.compute_audio_features([x], params=af.AudioFeatureParams(frame_loudness="mean"))
    assert (peak.loudness >= mean.loudness - 1e-12).all() and peak.loudness.max() > mean.loudness.max()
    assert peak.loudness_iso.shape == (L.n_steps(x.size),)
    np.testing.assert_allclose(peak.t_iso_s, np.arange(peak.loudness_iso.size) * 0.002)
    frames = peak.loudness_iso[: 10 * (peak.loudness_iso.size // 10)].reshape(-1, 10)
    np.testing.assert_array_equal(peak.loudness[: frames.shape[0]], frames.max(axis=1))


def test_streaming_api_equals_the_runner():
    rng = np.random.default_rng(5)
    x = (rng.standard_normal(2 * FS + 333) * 0.05).astype(np.float32)
    whole = af.compute_audio_features([x], step_ms=2)
    params = af.AudioFeatureParams()
    state = af.init_state(params, step_ms=2)
    parts, i = [], 0
    for n in [0, 1, 95, 865, 959, 960, 961, 12345] + [20_000] * 10:
        part, state = af.process_chunk(x[i:i + n], state, params=params)
        parts.append(part)
        i += n
        if i >= x.size:
            break
    parts.append(af.finish(state, params=params))
    joined = af.concatenate(parts)
    for name in af.FEATURE_NAMES + ("t_s", "loudness_iso", "t_iso_s"):
        np.testing.assert_array_equal(getattr(joined, name), getattr(whole, name))
    assert joined.n_samples == whole.n_samples == x.size


def test_process_chunk_returns_only_complete_frames():
    params = af.AudioFeatureParams()
    state = af.init_state(params)
    part, state = af.process_chunk(np.zeros(1919, np.float32), state, params=params)
    assert part.n_frames == 1 and state.frames_out == 1
    part, state = af.process_chunk(np.zeros(1, np.float32), state, params=params)
    assert part.n_frames == 1 and part.t_s[0] == pytest.approx(FRAME_S)
    tail = af.finish(state, params=params)
    assert tail.n_frames == 0 and tail.n_samples == 1920


def test_progress_reports_seconds_and_cancel_stops():
    seen = []
    chunks = [np.zeros(FS // 2, np.float32) for _ in range(4)]
    af.compute_audio_features(iter(chunks), progress=seen.append)
    assert seen == pytest.approx([0.5, 1.0, 1.5, 2.0])
    token = threading.Event()

    def gen():
        yield chunks[0]
        token.set()
        yield chunks[1]

    with pytest.raises(CancelledError):
        af.compute_audio_features(gen(), cancel=token)


def test_errors():
    x = np.zeros(2000, np.float32)
    x[[3, 70, 900]] = [np.nan, np.inf, -np.inf]
    with pytest.raises(ParameterError, match="3 non-finite"):
        af.compute_audio_features([x])
    with pytest.raises(ParameterError, match="1-D"):
        af.compute_audio_features([np.zeros((2, 100), np.float32)])
    with pytest.raises(ParameterError, match="no audio samples"):
        af.compute_audio_features([])
    with pytest.raises(ParameterError, match="no audio samples"):
        af.compute_audio_features([np.zeros(0, np.float32)])
    with pytest.raises(ParameterError, match="step_ms"):
        af.init_state(step_ms=5)


def test_iso_method_and_diffuse_field_run():
    p = af.AudioFeatureParams(loudness_method="iso", field="diffuse", booming_variant="paper")
    f = af.compute_audio_features([tone(500, 60, 1.0)], params=p)
    assert f.n_frames == 50 and steady(f.loudness) > 1.0 and 1.5 < steady(f.booming) < 2.05


def test_features_command_writes_json(tmp_path):
    import scipy.io.wavfile

    from autohaptics.cli.main import main

    wav = tmp_path / "tone.wav"
    x = np.concatenate([tone(60, 80, 0.5), tone(4000, 70, 0.5)])
    scipy.io.wavfile.write(wav, FS, (x * 32767).astype(np.int16))
    out = tmp_path / "features.json"
    assert main(["features", str(wav), "-o", str(out), "--step-ms", "2", "--method", "iso"]) == 0
    doc = json.loads(out.read_text())
    assert doc["params"]["loudness_method"] == "iso" and doc["params"]["pa_per_unit"] == PA
    frames = doc["frames"]
    assert frames["n"] == 50 and len(frames["t_s"]) == 50 and frames["step_s"] == FRAME_S
    for name in af.FEATURE_NAMES:
        assert len(frames[name]) == 50 and min(frames[name]) >= 0
    assert doc["units"]["loudness"] == "sone" and doc["units"]["low_energy"] == "Pa^2"
    assert np.median(frames["booming"][5:25]) > 1.0 > np.median(frames["booming"][30:])
    assert np.median(frames["sharpness"][30:]) > 2.5
    assert doc["loudness_iso"]["n"] == 500 and doc["loudness_iso"]["step_s"] == 0.002
    assert main(["features", str(tmp_path / "missing.wav"), "-o", str(out)]) == 2


def test_bench_audio_prints_figures(capsys):
    from autohaptics.cli.main import main

    assert main(["bench", "audio", "--seconds", "2", "--no-conformance"]) == 0
    text = capsys.readouterr().out
    assert "all four" in text and "s_per_s_audio" in text and "where the time goes" in text
