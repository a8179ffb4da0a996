"""``autohaptics bench audio``: compute time of the psychoacoustic audio features per second of
48 kHz audio, per parameter and per loudness method, on one core; peak memory; where the time
goes; the compiled kernels against their pure-Python and scipy reference paths; and the ISO 532-1
/ DIN 45692 conformance figures when ../shared/reference is present.

Target: loudness + sharpness + booming + low-frequency energy together <= 0.01 s of CPU per
second of audio for the default method. Why the kernels are compiled with numba (the figures of
this benchmark's "reference paths" table): docs/BENCHMARKS.md, "Why the stages are as they are".
"""

from __future__ import annotations

import argparse
import csv
import gc
import json
import os
import time
from pathlib import Path

import numpy as np
import psutil
import scipy.io.wavfile
import scipy.signal as ss

from autohaptics.intensity import kernels as K
from autohaptics.intensity import features as af
from autohaptics.intensity import booming as B
from autohaptics.intensity import filterbank as FB
from autohaptics.intensity import loudness as L
from autohaptics.intensity import zwicker as ZW
from autohaptics.intensity import low_energy as LE
from autohaptics.intensity import sharpness as S
from autohaptics.bench.common import measure, table
from autohaptics.errors import ParameterError
from autohaptics.timebase import ANALYSIS_SAMPLE_RATE as FS

CHUNK_S = 2.0  # the chunk length media.iter_audio yields
BLOCK_S = 60.0  # the generated block that is cycled to reach --seconds
TARGET_S_PER_S = 0.01


def register(sub) -> None:
    p = sub.add_parser("audio", help="audio features: CPU seconds per second of audio, memory, ISO/DIN conformance",
                       description="Time loudness, sharpness, booming and low-frequency energy (alone and together, "
                                   "per loudness method) on generated film-like 48 kHz audio, pinned to one core; "
                                   "print where the time goes and the ISO 532-1 / DIN 45692 conformance figures.")
    p.add_argument("--seconds", type=float, default=600.0, help="length of the generated audio, s (default 600)")
    p.add_argument("--seed", type=int, default=0, help="random seed of the generated audio")
    p.add_argument("--reference", metavar="DIR", default=None,
                   help="psychoacoustics reference folder (default: ../shared/reference/psychoacoustics)")
    p.add_argument("--no-conformance", action="store_true", help="skip the ISO/DIN conformance figures")
    p.add_argument("--json", metavar="OUT.json", default=None, help="also write every figure as JSON")
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    if not args.seconds > 0:
        raise ParameterError(f"--seconds must be positive, got {args.seconds}")
    saved = _affinity()
    try:
        return _run(args, _pin_one_core())
    finally:
        if saved is not None:
            os.sched_setaffinity(0, saved)


def _run(args: argparse.Namespace, core) -> int:
    figures: dict = {"seconds_of_audio": args.seconds}
    print(f"audio features benchmark: {args.seconds:g} s of generated 48 kHz audio in {CHUNK_S:g} s chunks, "
          f"pinned to CPU {core}; figures are process CPU seconds per second of audio")
    block = film_like_audio(min(BLOCK_S, args.seconds), seed=args.seed)
    chunks = _chunks(block, args.seconds)
    af.compute_audio_features([block[:FS]])  # load the compiled kernels before timing
    af.compute_audio_features([block[:FS]], params=af.AudioFeatureParams(loudness_method="iso"))

    rows, speed = [], {}
    for method in ("fast", "iso"):
        for name, fn in _parameter_runs(method, chunks).items():
            gc.collect()
            before = psutil.Process().memory_info().rss / 2**20
            m = measure(fn)
            per_s = m.cpu_s / args.seconds
            speed[f"{method}/{name}"] = {"cpu_s": m.cpu_s, "wall_s": m.wall_s, "s_per_s": per_s,
                                         "rss_before_mb": before, "peak_rss_mb": m.peak_rss_mb}
            rows.append([method, name, m.cpu_s, per_s, m.wall_s, before, m.peak_rss_mb - before])
    print(table(rows, ["method", "parameter", "cpu_s", "s_per_s_audio", "wall_s", "rss_before_MiB",
                       "peak_increase_MiB"]))
    default = speed["fast/all four"]["s_per_s"]
    print(f"default method, all four together: {default:.4f} s per s of audio "
          f"(target <= {TARGET_S_PER_S}: {'met' if default <= TARGET_S_PER_S else 'NOT met'}); "
          f"x{1.27 / default:.0f} faster than the pure-Python ISO reference, "
          f"x{0.028 / speed['fast/loudness']['s_per_s']:.1f} vs the compiled C reference (loudness alone)")
    figures["speed"] = speed

    stages = _stage_breakdown(chunks[: max(1, int(round(60.0 / CHUNK_S)))])
    print("\nwhere the time goes (fast method, ms of CPU per s of audio):")
    print(table([[k, v * 1e3] for k, v in stages.items()], ["stage", "ms_per_s"]))
    figures["stages_ms_per_s"] = {k: v * 1e3 for k, v in stages.items()}

    ref_paths = _reference_paths(block)
    print("\nreference paths (numba decision; CPU s per s of audio):")
    print(table([[k, v] for k, v in ref_paths.items()], ["path", "s_per_s_audio"]))
    figures["reference_paths"] = ref_paths

    dev = fast_vs_iso(block[: int(min(30.0, block.size / FS) * FS)])
    print("\nfast vs iso on the first 30 s of the generated audio:")
    print(table([[k, v["median"], v["p99"], v["max"]] for k, v in dev.items()], ["quantity", "median", "p99", "max"]))
    figures["fast_vs_iso"] = dev

    if not args.no_conformance:
        ref_dir = Path(args.reference) if args.reference else _default_reference_dir()
        if ref_dir is None or not (ref_dir / "iso532-1").is_dir():
            print(f"\nconformance: reference data not found ({ref_dir}); pass --reference DIR")
        else:
            figures["conformance"] = _conformance(ref_dir)
    if args.json:
        Path(args.json).write_text(json.dumps(figures, indent=1))
        print(f"\nfigures written to {args.json}")
    return 0


# ------------------------------------------------------------------ test signal
def film_like_audio(seconds: float, *, seed: int = 0) -> np.ndarray:
    """Deterministic film-like mono audio (float32, digital full scale, 48 kHz): scenes of 1-8 s
    of speech-like modulated noise, music-like harmonic chords, explosions with low rumble,
    room tone, and pink noise, at -45 .. -12 dBFS."""
    rng = np.random.default_rng(seed)
    n = int(round(seconds * FS))
    out = np.zeros(n, np.float32)
    a = 0
    while a < n:
        m = min(n - a, int(rng.uniform(1.0, 8.0) * FS))
        t = np.arange(m) / FS
        kind = rng.integers(5)
        if kind == 0:  # speech-like: band-limited noise, 4 Hz syllables
            x = ss.sosfilt(ss.butter(4, [200, 4000], btype="band", output="sos", fs=FS), rng.standard_normal(m))
            x *= np.clip(np.sin(2 * np.pi * rng.uniform(3, 5) * t + rng.uniform(0, 6)), 0, None) ** 2
        elif kind == 1:  # music-like: a chord of harmonic tones, changing every 0.5 s
            x = np.zeros(m)
            for start in range(0, m, FS // 2):
                seg = slice(start, min(m, start + FS // 2))
                for f0 in 110.0 * 2 ** (rng.integers(0, 24, 3) / 12):
                    for h in range(1, 6):
                        x[seg] += np.sin(2 * np.pi * f0 * h * t[seg] + rng.uniform(0, 6)) / h
        elif kind == 2:  # explosion: broadband burst with a decaying envelope and rumble
            x = rng.standard_normal(m) * np.exp(-t / rng.uniform(0.2, 1.0))
            x += 3 * np.sin(2 * np.pi * rng.uniform(30, 60) * t) * np.exp(-t / 1.5)
        elif kind == 3:  # room tone
            x = 0.01 * rng.standard_normal(m)
        else:  # pink-ish noise
            x = ss.lfilter([0.049922035, -0.095993537, 0.050612699, -0.004408786],
                           [1, -2.494956002, 2.017265875, -0.522189400], rng.standard_normal(m))
        rms = float(np.sqrt(np.mean(x ** 2))) or 1.0
        out[a:a + m] = (x / rms * 10 ** (rng.uniform(-45, -12) / 20)).astype(np.float32)
        a += m
    return np.clip(out, -1.0, 1.0)


def _chunks(block: np.ndarray, seconds: float) -> list[np.ndarray]:
    step = int(CHUNK_S * FS)
    total = int(round(seconds * FS))
    out, done = [], 0
    while done < total:
        a = done % block.size
        n = min(step, total - done, block.size - a)
        out.append(block[a:a + n])
        done += n
    return out


# ------------------------------------------------------------------ timed runs
def _parameter_runs(method: str, chunks: list[np.ndarray]) -> dict:
    params = af.AudioFeatureParams(loudness_method=method)
    lp = params.loudness_params()
    pa = params.pa_per_unit

    def loudness_only():
        state = L.init_state(params=lp)
        for c in chunks:
            _, state = L.loudness_update(c.astype(np.float64) * pa, state, params=lp)

    frame_specs = _frame_patterns(chunks, params) if method == "fast" else None

    def sharpness_only():
        for spec in frame_specs:
            S.sharpness(specific=spec, params=params.sharpness_params())

    def booming_only():
        for spec in frame_specs:
            B.booming(specific=spec, params=params.booming_params())

    def low_energy_only():
        state = LE.init_state(params=params.low_energy_params())
        for c in chunks:
            _, state = LE.low_energy_update(c.astype(np.float64) * pa, state, params=params.low_energy_params())

    def all_four():
        af.compute_audio_features(chunks, params=params)

    runs = {"loudness": loudness_only}
    if frame_specs is not None:
        runs.update({"sharpness (from N'(z))": sharpness_only, "booming (from N'(z))": booming_only,
                     "low_energy": low_energy_only})
    runs["all four"] = all_four
    return runs


def _frame_patterns(chunks: list[np.ndarray], params: af.AudioFeatureParams) -> list[np.ndarray]:
    """The frame-mean N'(z) arrays the runner hands to sharpness and booming, chunk by chunk."""
    lp = params.loudness_params()
    state = L.init_state(params=lp)
    out, pending = [], np.zeros((0, L.Z_BARK.size))
    for c in chunks:
        r, state = L.loudness_update(c.astype(np.float64) * params.pa_per_unit, state, params=lp)
        pending = np.concatenate([pending, r.specific])
        k = pending.shape[0] // af.STEPS_PER_FRAME
        out.append(pending[: k * af.STEPS_PER_FRAME].reshape(k, af.STEPS_PER_FRAME, -1).mean(axis=1))
        pending = pending[k * af.STEPS_PER_FRAME:]
    return out


def _stage_breakdown(chunks: list[np.ndarray]) -> dict[str, float]:
    """CPU seconds per second of audio of each step of the default pipeline."""
    params = af.AudioFeatureParams()
    lp = params.loudness_params()
    plan = FB.plan(lp.method)
    state = L.init_state(params=lp)
    le_state = LE.init_state(params=params.low_energy_params())
    acc = dict.fromkeys(["calibrate", "filter bank", "core loudness", "decay", "slopes", "temporal weighting",
                         "low energy", "frames + sharpness + booming"], 0.0)
    seconds = sum(c.size for c in chunks) / FS
    for c in chunks:
        t0 = time.process_time()
        p = c.astype(np.float64) * params.pa_per_unit
        t1 = time.process_time()
        k0 = -(-state.n_in // 24)
        ms, bank, smooth, stages = FB.filter_bank(p, state.n_in, state.bank, state.smooth, state.stages, plan)
        t2 = time.process_time()
        core = ZW.core_loudness(ms, diffuse=False)
        t3 = time.process_time()
        decayed, decay = ZW.nonlinear_decay(core, state.decay, plan, started=k0 > 0)
        t4 = time.process_time()
        rows = ZW.output_rows(k0, core.shape[1])
        total, spec = ZW.slopes(decayed, rows)
        t5 = time.process_time()
        weighted, weighting = ZW.temporal_weighting(total, state.weighting, started=k0 > 0)
        t6 = time.process_time()
        _, le_state = LE.low_energy_update(p, le_state, params=params.low_energy_params())
        t7 = time.process_time()
        k = spec.shape[0] // af.STEPS_PER_FRAME
        af.frame_values(weighted[rows >= 0][: k * 10].reshape(k, 10), spec[: k * 10].reshape(k, 10, -1),
                   np.zeros(k), 0, 0, params)
        t8 = time.process_time()
        state = L.LoudnessState(method=state.method, field=state.field, n_in=state.n_in + p.size, bank=bank,
                                smooth=smooth, stages=stages, decay=decay, weighting=weighting)
        for key, dt in zip(acc, (t1 - t0, t2 - t1, t3 - t2, t4 - t3, t5 - t4, t6 - t5, t7 - t6, t8 - t7)):
            acc[key] += dt
    return {k: v / seconds for k, v in acc.items()}


def _reference_paths(block: np.ndarray) -> dict[str, float]:
    """Compiled kernels vs numpy/scipy or pure-Python references of the same steps."""
    out = {}
    p = block[: 10 * FS].astype(np.float64) * 3.5566
    sos, gain = FB.iso_sos()
    bands = np.arange(28)
    a = FB.smoothing_pole(bands, FS)
    t0 = time.process_time()
    for b in bands:
        y = ss.sosfilt(sos[b], p) * gain[b]
        y = y * y
        for _ in range(3):
            y = ss.lfilter([1 - a[b]], [1, -a[b]], y)
        _ = y[::24]
    out["ISO filter bank, scipy sosfilt + lfilter"] = (time.process_time() - t0) / 10.0
    state = L.init_state(params=L.LoudnessParams(method="iso"))
    t0 = time.process_time()
    FB.filter_bank(p, state.n_in, state.bank, state.smooth, state.stages, FB.plan("iso"))
    out["ISO filter bank, compiled kernel"] = (time.process_time() - t0) / 10.0
    state = L.init_state(params=L.LoudnessParams(method="fast"))
    t0 = time.process_time()
    FB.filter_bank(p, state.n_in, state.bank, state.smooth, state.stages, FB.plan("fast"))
    out["fast multirate filter bank, compiled kernel"] = (time.process_time() - t0) / 10.0

    short = p[: FS // 4]  # 0.25 s: the pure-Python steps are slow
    st = L.init_state(params=L.LoudnessParams(method="iso"))
    ms, *_ = FB.filter_bank(short, st.n_in, st.bank, st.smooth, st.stages, FB.plan("iso"))
    core = ZW.core_loudness(ms, diffuse=False)
    plan = FB.plan("iso")
    for label, fn in (("compiled", K.nonlinear_decay), ("pure Python", K.nonlinear_decay.py_func)):
        z = np.zeros(core.shape[0])
        t0 = time.process_time()
        fn(core, plan.nl_coef, plan.nl_iterations, 1e-5, z.copy(), z.copy(), z.copy(), np.zeros(1, np.int64),
           np.empty_like(core))
        out[f"decay network (24 sub-steps), {label}"] = (time.process_time() - t0) / 0.25
    rows = ZW.output_rows(0, core.shape[1])
    for label, fn in (("compiled", K.slopes), ("pure Python", K.slopes.py_func)):
        t0 = time.process_time()
        fn(core, ZW.ZUP, ZW.RNS, ZW.USL, rows, np.empty(core.shape[1]), np.empty((int((rows >= 0).sum()), 240)))
        out[f"slopes, {label}"] = (time.process_time() - t0) / 0.25
    return out


def fast_vs_iso(x: np.ndarray) -> dict[str, dict[str, float]]:
    """Deviation of the fast method from "iso" on digital audio ``x``.

    N(t) on the 2 ms grid: distance to the fast values within +-2 ms (the standard's time
    tolerance), relative to max(N, 0.1 sone), as ISO 532-1 counts it. The four 20 ms features:
    |fast - iso| divided by the clip's maximum of the iso feature, i.e. the error the intensity
    rule sees after its max-normalisation (a frame near the 0.1 sone sharpness floor can flip
    between 0 and its value; that shows in the max, not in the percentiles).
    """
    res = {m: af.compute_audio_features([x], params=af.AudioFeatureParams(loudness_method=m), step_ms=2)
           for m in L.LOUDNESS_METHODS}
    out = {}
    ref, fast = res["iso"].loudness_iso, res["fast"].loudness_iso
    pad = np.pad(fast, 1, mode="edge")
    win = np.stack([pad[:-2], pad[1:-1], pad[2:]])
    dist = np.maximum(0.0, np.maximum(win.min(axis=0) - ref, ref - win.max(axis=0))) / np.maximum(ref, 0.1)
    out["N(t) 2 ms, +-2 ms, rel."] = _stats(dist)
    for name in af.FEATURE_NAMES:
        a, b = getattr(res["iso"], name), getattr(res["fast"], name)
        out[f"{name} 20 ms / clip max"] = _stats(np.abs(b - a) / max(float(a.max()), 1e-300))
    return out


def _stats(rel: np.ndarray) -> dict[str, float]:
    return {"median": float(np.median(rel)), "p99": float(np.percentile(rel, 99)), "max": float(rel.max())}


# ------------------------------------------------------------------ conformance
def _conformance(ref_dir: Path) -> dict:
    iso_dir = ref_dir / "iso532-1"
    with open(iso_dir / "reference_summary.csv", newline="") as fh:
        summary = {int(r["signal"]): r for r in csv.DictReader(fh)}
    figures: dict = {"iso532_1": {}, "din45692": {}}
    rows = []
    for method in L.LOUDNESS_METHODS:
        in5 = in10 = total = 0
        worst_nmax = 0.0
        per_signal_min5 = 1.0
        for n in range(6, 26):
            p = _wav(iso_dir / summary[n]["file"], 2.0 * np.sqrt(2.0))
            r = L.loudness_zwtv(p, params=L.LoudnessParams(method=method, field="diffuse" if n == 15 else "free"))
            ref = np.loadtxt(iso_dir / "reference" / "csv_from_sqat_mat" / f"tv_signal_{n:02d}_loudness.csv",
                             delimiter=",", skiprows=1)
            k = min(ref.shape[0], r.loudness.size)
            pad = np.pad(r.loudness[:k], 1, mode="edge")
            cand = np.stack([pad[:-2], pad[1:-1], pad[2:]])
            ok5 = ((cand >= ref[:k, 2]) & (cand <= ref[:k, 3])).any(axis=0)
            ok10 = ((cand >= ref[:k, 4]) & (cand <= ref[:k, 5])).any(axis=0)
            in5, in10, total = in5 + int(ok5.sum()), in10 + int(ok10.sum()), total + k
            per_signal_min5 = min(per_signal_min5, float(ok5.mean()))
            worst_nmax = max(worst_nmax, abs(r.loudness.max() / float(summary[n]["Nmax_ref_sone"]) - 1))
        stat = []
        for n in (2, 3, 4, 5):
            p = _wav(iso_dir / summary[n]["file"], 2.0 * np.sqrt(2.0))
            r = L.loudness_zwtv(p, params=L.LoudnessParams(method=method))
            stat.append(float(np.median(r.loudness[r.t_s >= 1.0])) / float(summary[n]["N_ref_sone"]) - 1)
        figures["iso532_1"][method] = {"share_in_5pct": in5 / total, "share_in_10pct": in10 / total,
                                       "worst_signal_share_in_5pct": per_signal_min5, "samples": total,
                                       "worst_Nmax_dev": worst_nmax, "stationary_2_5_steady_dev": stat}
        rows.append([method, "ISO 6-25 N(t)", f"{in5 / total:.2%} in 5 % band, {in10 / total:.2%} in 10 % band "
                     f"({total} samples; worst signal {per_signal_min5:.2%}), Nmax within {worst_nmax:.2%}"])
        rows.append([method, "ISO 2-5 steady", " ".join(f"{d:+.2%}" for d in stat)])
    dev = []
    for n in (2, 3, 4, 5):
        total, _ = L.loudness_stationary(_wav(iso_dir / summary[n]["file"], 2.0 * np.sqrt(2.0)), skip_s=0.5)
        dev.append(total / float(summary[n]["N_ref_sone"]) - 1)
    figures["iso532_1"]["stationary_method_2_5_dev"] = dev
    rows.append(["stationary", "ISO 2-5", " ".join(f"{d:+.2%}" for d in dev)])

    din_dir = ref_dir / "din45692"
    with open(din_dir / "reference_values.csv", newline="") as fh:
        din = list(csv.DictReader(fh))
    results: dict[str, list] = {"stationary": [], "fast": [], "iso": []}
    for row in din:
        p = _wav(din_dir / row["signal_file"], 0.6334)
        ref = float(row["S_ref_acum"])
        tol = max(0.05 * ref, 0.05)
        _, spec = L.loudness_stationary(p, skip_s=0.5)
        results["stationary"].append((float(S.sharpness(specific=spec)), ref, tol))
        for method in L.LOUDNESS_METHODS:
            prm = af.AudioFeatureParams(loudness_method=method)
            f = af.compute_audio_features([(p / prm.pa_per_unit).astype(np.float32)], params=prm)
            results[method].append((float(np.median(f.sharpness[f.t_s >= 0.5])), ref, tol))
    for name, vals in results.items():
        passed = sum(abs(v - r) <= t for v, r, t in vals)
        worst = max(abs(v - r) / t for v, r, t in vals)
        strict = sum(abs(v - r) <= 0.05 + 1e-12 for v, r, t in vals)
        figures["din45692"][name] = {"passed": passed, "of": len(vals), "worst_error_over_tolerance": worst,
                                     "within_0_05_acum": strict}
        rows.append([name, "DIN 45692 (41)", f"{passed}/{len(vals)} within max(5 %, 0.05 acum), worst at "
                     f"{worst:.0%} of the tolerance; {strict}/{len(vals)} within 0.05 acum"])
    print("\nconformance (ISO 532-1: 2 ms samples with +-2 ms time tolerance; DIN 45692: p = x * 0.6334 Pa):")
    print(table(rows, ["method", "check", "result"]))
    return figures


def _wav(path: Path, cal: float) -> np.ndarray:
    sr, x = scipy.io.wavfile.read(path)
    if sr != FS:
        raise ParameterError(f"{path}: expected 48 kHz, got {sr} Hz")
    return x.astype(np.float64) / 32767.0 * cal


def _default_reference_dir() -> Path | None:
    env = os.environ.get("AUTOHAPTICS_SHARED")
    root = Path(env) if env else Path(__file__).resolve().parents[3].parent / "shared"
    d = root / "reference" / "psychoacoustics"
    return d if d.is_dir() else None


def _affinity() -> set | None:
    try:
        return os.sched_getaffinity(0)
    except (AttributeError, OSError):
        return None


def _pin_one_core() -> int | str:
    """Pin this process to one CPU so every figure is single-core compute (run() restores it)."""
    try:
        cpus = sorted(os.sched_getaffinity(0))
        os.sched_setaffinity(0, {cpus[-1]})
        return cpus[-1]
    except (AttributeError, OSError):
        return "(not pinned: no sched_setaffinity)"
