"""``autohaptics bench accuracy VIDEO...``: run time against error, per configuration.

For each clip, every configuration (``reference``, ``balanced``, ``fast``, ``balanced`` without
skipping, and any ``--config``) runs ``generate`` in a FRESH process, so its peak memory is its
own; the bare decode of the same file (:func:`autohaptics.media.decode_all`) also runs in its own
process in the same run. Wall time is the ``generate`` call itself (after imports and a warm-up of
the compiled audio kernels, which a long film pays once); peak RSS is the whole process's
(``ru_maxrss`` from ``wait4``). Each timeline is compared with the reference one
(:mod:`autohaptics.metrics`).

Outputs (in ``--out``): ``accuracy.json`` (every figure), ``accuracy_<clip>.png`` (x = wall time /
decode time, y = vibration MAE, temperature MAE, 1 - fan IoU; one point per configuration, the
Pareto front drawn), and the timelines. Printed: the table, the per-stage seconds (where the time
goes) and the skipping audit (share of ticks computed vs skipped per stage, and what skipping
costs in error: ``balanced`` vs ``balanced`` with ``video.skip=false``, both against the reference
and against each other).

Targets (checked here, never by timed assertions): balanced <= 1.25 x decode on a 1080p clip with
vibration MAE <= 0.02, onset F1 >= 0.97, temperature MAE <= 0.3 C and fan IoU >= 0.9 against
the reference; fast at least 2 x cheaper than balanced in analysis cost (wall - decode).
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
import time
from dataclasses import dataclass
from fractions import Fraction
from pathlib import Path

from autohaptics.bench.common import table
from autohaptics.errors import ParameterError

REFERENCE = "reference"
DEFAULT_CONFIGS = ("reference", "balanced", "fast")
NOSKIP = "balanced-noskip"
TARGETS = {"x_decode": 1.25, "vibration_mae": 0.02, "onset_f1": 0.97, "temperature_mae_c": 0.3, "fan_iou": 0.9,
           "fast_speedup": 2.0}  # fast >= 2 x faster than balanced: wall time, stage seconds, wall - decode
SKIP_STAGES = ("saliency", "flow", "depth")


# ------------------------------------------------------------------ configurations
@dataclass(frozen=True)
class Config:
    """One benchmarked configuration: a preset plus dotted overrides."""

    name: str
    preset: str
    overrides: tuple[tuple[str, str], ...] = ()

    def cli_args(self) -> list[str]:
        out = ["--preset", self.preset]
        for k, v in self.overrides:
            out += ["--set", f"{k}={v}"]
        return out


def parse_config(text: str) -> Config:
    """``NAME:k=v,k=v`` -> Config. ``preset=NAME`` picks the base preset (default balanced); a piece
    without ``=`` continues the previous value (``tracks=vibration,fans``). Validated here."""
    from autohaptics.params import resolve_params

    name, sep, rest = text.partition(":")
    name = name.strip()
    if not name or not sep and "=" in name:
        raise ParameterError(f"--config expects NAME:k=v,k=v, got {text!r}")
    pairs: list[list[str]] = []
    for piece in (p for p in rest.split(",") if p.strip()):
        if "=" in piece:
            k, v = piece.split("=", 1)
            pairs.append([k.strip(), v.strip()])
        elif pairs:
            pairs[-1][1] += "," + piece.strip()
        else:
            raise ParameterError(f"--config {name}: expected k=v, got {piece!r}")
    preset = "balanced"
    overrides = []
    for k, v in pairs:
        if k == "preset":
            preset = v
        else:
            overrides.append((k, v))
    resolve_params(preset, dict(overrides))  # raises ParameterError naming a bad key or value
    return Config(name, preset, tuple(overrides))


def default_configs(skip_audit: bool = True) -> list[Config]:
    configs = [Config(name, name) for name in DEFAULT_CONFIGS]
    if skip_audit:
        configs.append(Config(NOSKIP, "balanced", (("video.skip", "false"),)))
    return configs


# ------------------------------------------------------------------ child processes
@dataclass
class ChildResult:
    returncode: int
    wall_s: float
    peak_rss_mb: float  # the child's own peak resident set size (ru_maxrss via wait4), MiB
    stdout: str
    stderr: str


# A launcher of a few MB runs the measured command: a process's ru_maxrss starts at the RSS of the
# process it was forked from (Linux copies the page tables and keeps the high-water mark across
# exec), so a command started straight from this process would report at least this process's size.
_LAUNCHER = r"""
import json, os, sys, time
out, cmd = sys.argv[1], sys.argv[2:]
t0 = time.perf_counter()
pid = os.fork()
if pid == 0:
    try:
        os.execvp(cmd[0], cmd)
    finally:
        os._exit(127)
_, status, usage = os.wait4(pid, 0)
with open(out, "w") as fh:
    json.dump({"status": status, "maxrss_kb": usage.ru_maxrss, "wall_s": time.perf_counter() - t0}, fh)
"""


def run_child(cmd: list[str], *, timeout_s: float | None = None, env: dict | None = None) -> ChildResult:
    """Run ``cmd`` in a fresh process: its exit code, wall time and its own peak RSS (``ru_maxrss``
    from ``wait4``, through a small launcher, so neither this process's size nor another child's
    counts). A run past ``timeout_s`` is killed with its launcher (returncode -9)."""
    with tempfile.TemporaryFile("w+") as out, tempfile.TemporaryFile("w+") as err, \
            tempfile.NamedTemporaryFile("r", suffix=".json") as res:
        proc = subprocess.Popen([sys.executable, "-I", "-S", "-c", _LAUNCHER, res.name, *cmd], stdout=out,
                                stderr=err, text=True, env=env, start_new_session=True)
        try:
            proc.wait(timeout=timeout_s)
        except subprocess.TimeoutExpired:
            os.killpg(proc.pid, 9)
            proc.wait()
            out.seek(0)
            err.seek(0)
            return ChildResult(-9, float(timeout_s or 0.0), 0.0, out.read(), err.read())
        out.seek(0)
        err.seek(0)
        doc = json.loads(res.read() or "{}")
        if "status" not in doc:
            raise ParameterError(f"the measuring launcher failed (exit {proc.returncode}): {err.read()[-500:]}")
        return ChildResult(os.waitstatus_to_exitcode(doc["status"]), doc["wall_s"], doc["maxrss_kb"] / 1024.0,
                           out.read(), err.read())


def _worker_cmd(*args: str) -> list[str]:
    return [sys.executable, "-m", "autohaptics.bench.accuracy", *args]


_CHILD_ENV: dict | None = None  # set by snapshot_source(): children import that copy of the package


def snapshot_source(dest: Path) -> Path:
    """Copy the ``autohaptics`` package to ``dest`` and make every measured child import that copy:
    a long run then measures one version of the code even when the working tree changes under it."""
    import shutil

    global _CHILD_ENV
    src = Path(__file__).resolve().parents[1]
    if dest.exists():
        shutil.rmtree(dest)
    shutil.copytree(src, dest / "autohaptics", ignore=shutil.ignore_patterns("*.pyc"))
    env = dict(os.environ)
    env["PYTHONPATH"] = os.pathsep.join([str(dest)] + ([env["PYTHONPATH"]] if env.get("PYTHONPATH") else []))
    _CHILD_ENV = env
    return dest


def _child_json(cmd: list[str], result: Path) -> dict:
    r = run_child(cmd, env=_CHILD_ENV)
    if r.returncode != 0:
        last = (r.stderr.strip().splitlines() or ["(no message)"])[-1]
        raise ParameterError(f"benchmark run failed (exit {r.returncode}): {' '.join(cmd[3:])}: {last}")
    doc = json.loads(result.read_text())
    doc["process_wall_s"] = r.wall_s
    doc["peak_rss_mb"] = r.peak_rss_mb
    return doc


def measure_decode(video: Path, work: Path) -> dict:
    """Bare decode of ``video`` in a fresh process: {"wall_s", "cpu_s", "peak_rss_mb", counts}."""
    res = work / "decode.result.json"
    return _child_json(_worker_cmd("_decode", str(video), str(res)), res)


def measure_generate(video: Path, config: Config, work: Path) -> dict:
    """``generate`` of ``video`` with ``config`` in a fresh process; writes ``<name>.json`` (the timeline)."""
    res = work / f"{config.name}.result.json"
    tl = work / f"{config.name}.json"
    return _child_json(_worker_cmd("_generate", str(video), str(tl), str(res), *config.cli_args()), res)


# ------------------------------------------------------------------ workers (in the child)
def _worker_decode(argv: list[str]) -> None:
    from autohaptics import media

    video, result = argv
    cpu0, t0 = time.process_time(), time.perf_counter()
    counts = media.decode_all(video)
    wall, cpu = time.perf_counter() - t0, time.process_time() - cpu0
    Path(result).write_text(json.dumps({"wall_s": wall, "cpu_s": cpu, **counts}))


def _worker_generate(argv: list[str]) -> None:
    import numpy as np

    from autohaptics.intensity import features as af
    from autohaptics.cli.generate import add_generation_options, params_from_args
    from autohaptics.pipeline import generate

    p = argparse.ArgumentParser()
    p.add_argument("video")
    p.add_argument("timeline")
    p.add_argument("result")
    add_generation_options(p)
    args = p.parse_args(argv)
    params, preset = params_from_args(args)
    # load the compiled audio kernels for this method (a one-off cost a long film pays once)
    af.compute_audio_features([np.zeros(9600, np.float32)], params=params.audio)
    cpu0, t0 = time.process_time(), time.perf_counter()
    tl = generate(args.video, params, preset=preset)
    wall, cpu = time.perf_counter() - t0, time.process_time() - cpu0
    tl.save(args.timeline)
    Path(args.result).write_text(json.dumps({"wall_s": wall, "cpu_s": cpu, "stats": tl.stats,
                                             "n_ticks": tl.n_ticks, "duration_s": tl.source.get("duration_s")}))


# ------------------------------------------------------------------ one clip
def bench_clip(video: Path, configs: list[Config], out: Path, *, repeat: int = 1,
               log=print) -> dict:
    """Every figure for one clip (module docstring); timelines and results go to ``out/<clip stem>/``."""
    from autohaptics import media
    from autohaptics.metrics import compare_timelines, headline
    from autohaptics.timeline import Timeline

    info = media.probe(video)
    work = out / video.stem
    work.mkdir(parents=True, exist_ok=True)
    video.read_bytes()  # warm the page cache: no run pays the first read from disk
    log(f"\n== {video.name}: {info.duration_s:.2f} s, "
        + (f"{info.video.width}x{info.video.height} @ {info.video.fps:.3g} fps {info.video.codec}"
           if info.video else "no video")
        + (f", audio {info.audio.codec} {info.audio.sample_rate} Hz {info.audio.channels} ch" if info.audio else ""))

    decodes = []
    runs: dict[str, list[dict]] = {c.name: [] for c in configs}
    for i in range(repeat):  # alternate, so machine noise hits every configuration alike
        decodes.append(measure_decode(video, work))
        log(f"  decode: {decodes[-1]['wall_s']:.2f} s")
        for c in configs:
            if c.name == REFERENCE and runs[c.name]:
                continue  # the yardstick runs once: its timeline is what matters, not its speed
            runs[c.name].append(measure_generate(video, c, work))
            log(f"  {c.name}: {runs[c.name][-1]['wall_s']:.2f} s")
    decode_s = statistics.median(d["wall_s"] for d in decodes)
    result = {"clip": str(video), "duration_s": info.duration_s,
              "video": None if info.video is None else {"width": info.video.width, "height": info.video.height,
                                                        "fps": info.video.fps, "codec": info.video.codec},
              "audio": None if info.audio is None else {"codec": info.audio.codec, "channels": info.audio.channels,
                                                        "sample_rate": info.audio.sample_rate},
              "repeat": repeat, "load_average": os.getloadavg(),
              "decode": {"wall_s": decode_s, "runs_s": [d["wall_s"] for d in decodes],
                         "cpu_s": statistics.median(d["cpu_s"] for d in decodes),
                         "peak_rss_mb": max(d["peak_rss_mb"] for d in decodes),
                         "video_frames": decodes[0]["video_frames"], "audio_samples": decodes[0]["audio_samples"]},
              "configs": {}}
    timelines = {c.name: Timeline.load(work / f"{c.name}.json") for c in configs}
    ref = timelines.get(REFERENCE)
    for c in configs:
        rs = runs[c.name]
        wall = statistics.median(r["wall_s"] for r in rs)
        entry = {"preset": c.preset, "overrides": dict(c.overrides), "wall_s": wall, "runs_s": [r["wall_s"] for r in rs],
                 "cpu_s": statistics.median(r["cpu_s"] for r in rs), "peak_rss_mb": max(r["peak_rss_mb"] for r in rs),
                 "x_decode": wall / decode_s if decode_s > 0 else float("nan"),
                 "analysis_s": wall - decode_s, "stages": _median_stages([stage_seconds(r["stats"]) for r in rs]),
                 "analysis_stage_s": statistics.median(analysis_stage_seconds(r["stats"]) for r in rs),
                 "skipping": skip_shares(rs[0]["stats"]), "timeline": str(work / f"{c.name}.json"),
                 "stats": rs[0]["stats"]}
        if ref is not None:
            report = compare_timelines(ref, timelines[c.name])
            entry["error"] = headline(report)
            entry["error_report"] = _trim(report)
        entry["x_decode_cpu"] = entry["cpu_s"] / result["decode"]["cpu_s"] if result["decode"]["cpu_s"] > 0 else 0.0
        result["configs"][c.name] = entry
    if NOSKIP in timelines and "balanced" in timelines:
        result["skip_cost"] = {
            "balanced_vs_noskip": headline(compare_timelines(timelines[NOSKIP], timelines["balanced"])),
        }
    return result


def _video_stages(stats: dict) -> dict[str, dict]:
    """The per-stage blocks of stats["video"] (every dict with "seconds"), in the pipeline's order."""
    video = stats.get("video") or {}
    return {k: v for k, v in video.items() if isinstance(v, dict) and "seconds" in v}


def stage_seconds(stats: dict) -> dict:
    """Seconds per stage from a timeline's stats: audio, each video stage, the video pass, derive, total."""
    out = {"hash": _sec(stats.get("hash")), "audio": _sec(stats.get("audio"))}
    for name, block in _video_stages(stats).items():
        out[f"video.{name}"] = _sec(block)
    out["video"] = _sec(stats.get("video"))
    out["derive"] = _sec(stats.get("derive"))
    out["total"] = float(stats.get("total_seconds") or 0.0)
    return out


def _median_stages(runs: list[dict]) -> dict:
    keys = list(dict.fromkeys(k for r in runs for k in r))
    return {k: statistics.median(r.get(k, 0.0) for r in runs) for k in keys}


def analysis_stage_seconds(stats: dict) -> float:
    """Seconds spent analysing, not decoding: the audio pass (its decoding is a small part) plus
    every video stage but decoding ("decode", "decode_wait"). Measured inside one run, so less
    exposed to the machine's load than wall time minus a separately measured decode."""
    return _sec(stats.get("audio")) + sum(_sec(b) for n, b in _video_stages(stats).items()
                                          if not n.startswith("decode"))


def skip_shares(stats: dict) -> dict:
    """{stage: {"computed", "skipped", "held", "share_computed"}} from stats["video"], plus static ticks
    and cuts ("held": ticks without a frame of their own that took the values of the analysed tick
    before them, where that tick computed the stage; the others count as skipped)."""
    video = stats.get("video") or {}
    out = {}
    for name in SKIP_STAGES:
        s = video.get(name) or {}
        if "ticks_computed" in s:
            done, skipped, held = int(s["ticks_computed"]), int(s["ticks_skipped"]), int(s.get("ticks_held", 0))
            out[name] = {"computed": done, "skipped": skipped, "held": held,
                         "share_computed": done / (done + skipped + held) if done + skipped + held else 0.0,
                         "seconds": float(s.get("seconds", 0.0)), "calls": int(s.get("computed", 0))}
    if "static" in video:
        out["static_ticks"] = int(video["static"].get("ticks_static", 0))
    if "cuts" in video:
        out["cuts"] = int(video["cuts"].get("cuts", 0))
    frames = video.get("frames") or {}
    if frames:
        out["ticks"] = int(frames.get("ticks", 0))
    return out


def _sec(block) -> float:
    return float(block.get("seconds", 0.0)) if isinstance(block, dict) else 0.0


def _trim(report: dict) -> dict:
    """The comparison report without the per-actuator onset lists (kept short in the JSON)."""
    r = json.loads(json.dumps(report))
    r["vibration"]["onsets"].pop("per_actuator", None)
    return r


# ------------------------------------------------------------------ reporting
def pareto_front(points: list[tuple[float, float]]) -> list[int]:
    """Indices of the points no other point beats on both axes (lower is better), sorted by x."""
    idx = []
    for i, (x, y) in enumerate(points):
        if not any((x2 <= x and y2 <= y) and (x2 < x or y2 < y) for j, (x2, y2) in enumerate(points) if j != i):
            idx.append(i)
    return sorted(idx, key=lambda i: points[i])


def print_tables(res: dict, log=print) -> None:
    d = res["decode"]
    log(f"\nbare decode: {d['wall_s']:.2f} s wall ({d['video_frames']} frames, {d['audio_samples']} samples), "
        f"peak RSS {d['peak_rss_mb']:.0f} MiB")
    rows = []
    for name, c in res["configs"].items():
        e = c.get("error") or {}
        rows.append([name, c["wall_s"], c["x_decode"], c["x_decode_cpu"], c["analysis_stage_s"], c["peak_rss_mb"],
                     e.get("vibration_mae", ""), e.get("chair_mae", ""), e.get("onset_f1", ""),
                     e.get("onset_precision", ""), e.get("onset_recall", ""), e.get("chair_onset_f1", ""),
                     e.get("temperature_mae_c", ""), e.get("fan_iou", ""), e.get("fan_ticks_f1", ""),
                     e.get("fan_iou_both_on", "")])
    log(table(rows, ["config", "wall_s", "x_decode", "x_decode_cpu", "analysis_s", "peak_MiB", "vib_MAE",
                     "chair_MAE", "onset_F1", "onset_P", "onset_R", "chair_F1", "temp_MAE_C", "fan_IoU",
                     "fan_ticks_F1", "fan_IoU_both"]))
    log("(x_decode: wall / bare decode wall; x_decode_cpu: the same in CPU seconds; analysis_s: audio pass + "
        "video stages except decode, from the stats; chair_*: the strongest actuator per tick; fan_ticks_F1: "
        "agreement on which ticks blow; fan_IoU_both: cell IoU where both blow)")
    log("\nwhere the time goes (seconds per stage, from the timelines' stats):")
    names = list(res["configs"])
    keys = list(dict.fromkeys(k for n in names for k in res["configs"][n]["stages"]))
    log(table([[k] + [res["configs"][n]["stages"].get(k, 0.0) for n in names] for k in keys], ["stage"] + names))
    audited = [n for n in ("balanced", NOSKIP) if n in res["configs"]]
    if audited:
        log("\nskipping audit (ticks computed / skipped per stage):")
        rows = []
        for stage in SKIP_STAGES:
            row = [stage]
            for n in audited:
                s = res["configs"][n]["skipping"].get(stage)
                row += [f"{s['computed']}/{s['skipped']}" if s else "-", s["share_computed"] if s else "",
                        s["seconds"] if s else ""]
            rows.append(row)
        header = ["stage"]
        for n in audited:
            header += [f"{n} done/skipped", "share_done", "s"]
        log(table(rows, header))
        for n in audited:
            sk = res["configs"][n]["skipping"]
            log(f"  {n}: {sk.get('static_ticks', 0)} static ticks (no flow), {sk.get('cuts', 0)} cuts")
        if "skip_cost" in res:
            b, ns = res["configs"]["balanced"], res["configs"][NOSKIP]
            cost = res["skip_cost"]["balanced_vs_noskip"]
            log(f"  skipping saves {ns['wall_s'] - b['wall_s']:.2f} s ({ns['wall_s']:.2f} -> {b['wall_s']:.2f} s); "
                f"balanced vs no-skip: vibration MAE {cost['vibration_mae']:.4f}, onset F1 {cost['onset_f1']:.3f}, "
                f"temperature MAE {cost['temperature_mae_c']:.3f} C, fan IoU {cost['fan_iou']:.3f}")
            if "error" in b:
                log(f"  against the reference: balanced vibration MAE {b['error']['vibration_mae']:.4f} / "
                    f"fan IoU {b['error']['fan_iou']:.3f}; no-skip {ns['error']['vibration_mae']:.4f} / "
                    f"{ns['error']['fan_iou']:.3f}")


def verdicts(res: dict) -> list[str]:
    """Target lines for the balanced and fast presets (met / NOT met), when both and the reference ran."""
    c = res["configs"]
    if not all(k in c for k in ("reference", "balanced")):
        return []
    b, e = c["balanced"], c["balanced"]["error"]
    checks = [("balanced wall / decode", b["x_decode"], "<=", TARGETS["x_decode"]),
              ("balanced vibration MAE", e["vibration_mae"], "<=", TARGETS["vibration_mae"]),
              ("balanced onset F1", e["onset_f1"], ">=", TARGETS["onset_f1"]),
              ("balanced temperature MAE (C)", e["temperature_mae_c"], "<=", TARGETS["temperature_mae_c"]),
              ("balanced fan IoU", e["fan_iou"], ">=", TARGETS["fan_iou"])]
    if "fast" in c and c["fast"]["wall_s"] > 0:
        checks.append(("fast speed-up vs balanced (wall time)", b["wall_s"] / c["fast"]["wall_s"], ">=",
                       TARGETS["fast_speedup"]))
    if "fast" in c and c["fast"]["analysis_stage_s"] > 0:
        checks.append(("fast analysis speed-up vs balanced (stage seconds)",
                       b["analysis_stage_s"] / c["fast"]["analysis_stage_s"], ">=", TARGETS["fast_speedup"]))
    if "fast" in c and c["fast"]["analysis_s"] > 0:
        checks.append(("fast analysis speed-up vs balanced (wall - decode)", b["analysis_s"] / c["fast"]["analysis_s"],
                       ">=", TARGETS["fast_speedup"]))
    out = []
    for label, value, op, target in checks:
        ok = value <= target if op == "<=" else value >= target
        out.append(f"{label}: {value:.4g} (target {op} {target:g}): {'met' if ok else 'NOT met'}")
    return out


def plot(res: dict, path: Path) -> Path:
    """Run time against error, one point per configuration, Pareto front drawn (matplotlib Agg)."""
    import matplotlib
    import numpy as np

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib import ticker

    names = [n for n, c in res["configs"].items() if "error" in c]
    x = [res["configs"][n]["x_decode"] for n in names]
    panels = [("vibration MAE", [res["configs"][n]["error"]["vibration_mae"] for n in names], TARGETS["vibration_mae"]),
              ("temperature MAE (C)", [res["configs"][n]["error"]["temperature_mae_c"] for n in names],
               TARGETS["temperature_mae_c"]),
              ("1 - fan IoU", [1.0 - res["configs"][n]["error"]["fan_iou"] for n in names], 1 - TARGETS["fan_iou"])]
    fig, axes = plt.subplots(1, 3, figsize=(13, 4.2), constrained_layout=True)
    for ax, (label, y, target) in zip(axes, panels):
        front = pareto_front(list(zip(x, y)))
        ax.plot([x[i] for i in front], [y[i] for i in front], "-", color="tab:orange", lw=2, zorder=1,
                label="Pareto front")
        span = (max(y) - min(y)) or 1.0
        placed: list[tuple[float, float]] = []
        for i, n in enumerate(names):
            on = i in front
            ax.scatter(x[i], y[i], s=60 if on else 40, zorder=2, color="tab:orange" if on else "tab:blue",
                       edgecolor="black" if on else "none")
            # labels of (nearly) coinciding points are stacked instead of printed over each other
            near = sum(1 for px, py in placed if abs(np.log10(px / x[i])) < 0.3 and abs(py - y[i]) < 0.1 * span)
            placed.append((x[i], y[i]))
            ax.annotate(n, (x[i], y[i]), textcoords="offset points", xytext=(5, 5 + 10 * near), fontsize=8)
        ax.axhline(target, color="grey", ls=":", lw=1, label="target")
        ax.axvline(TARGETS["x_decode"], color="grey", ls="--", lw=1, label=f"{TARGETS['x_decode']} x decode")
        ax.set_xscale("log")
        ax.xaxis.set_major_locator(ticker.LogLocator(subs=(1.0, 2.0, 5.0)))
        ax.xaxis.set_major_formatter(ticker.FuncFormatter(lambda v, _pos: f"{v:g}"))
        ax.xaxis.set_minor_formatter(ticker.NullFormatter())
        ax.set_xlabel("wall time / bare decode time")
        ax.set_ylabel(label)
        ax.grid(alpha=0.3, which="both")
    axes[0].legend(fontsize=8, loc="best")
    v = res.get("video") or {}
    fig.suptitle(f"{Path(res['clip']).name}: {res['duration_s']:.1f} s"
                 + (f", {v['width']}x{v['height']} @ {v['fps']:.3g} fps" if v else "")
                 + f"; bare decode {res['decode']['wall_s']:.2f} s; errors against 'reference'", fontsize=10)
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path


# ------------------------------------------------------------------ long clips
def synth_clip(out_dir: Path, spec: str) -> Path:
    """``WxH@FPS:SECONDS`` -> a synthetic clip (the README sample scene repeated every 10 s)."""
    from autohaptics import testing as synth

    try:
        size, seconds = spec.split(":")
        wh, fps = size.split("@")
        w, h = (int(v) for v in wh.lower().split("x"))
        fps_f, secs = float(fps), float(seconds)
    except ValueError:
        raise ParameterError(f"--synth expects WxH@FPS:SECONDS (e.g. 1920x1080@30:30), got {spec!r}") from None
    path = out_dir / f"synth_{w}x{h}_{fps}fps_{seconds}s.mp4"
    if path.exists():
        return path
    base = synth.sample_scene(10.0)
    reps = int(-(-secs // 10.0))

    def shift(items, dt):
        out = []
        for it in items:
            fields = {}
            for a in ("t0", "t1", "t_on", "t_off"):
                if hasattr(it, a):
                    fields[a] = min(getattr(it, a) + dt, secs)
            if all(fields.get(a, 1) < secs for a in ("t0", "t_on")):
                out.append(type(it)(**{**it.__dict__, **fields}))
        return out

    bg, shapes, audio = [], [], []
    for k in range(reps):
        bg += shift(base.background, 10.0 * k)
        shapes += shift(base.shapes, 10.0 * k)
        audio += shift(base.audio, 10.0 * k)
    scene = synth.Scene(duration_s=secs, background=tuple(bg), shapes=tuple(shapes), audio=tuple(audio),
                        name="bench")
    out_dir.mkdir(parents=True, exist_ok=True)
    return synth.write_scene(path, scene, width=w, height=h, fps=Fraction(fps_f).limit_denominator(1001),
                             quality="low")


# ------------------------------------------------------------------ command line
def register(sub) -> None:
    p = sub.add_parser("accuracy", help="run time against error of reference/balanced/fast (and --config)",
                       description="For each clip, run every configuration in a fresh process, measure wall time, "
                                   "peak RSS and the bare decode time of the same file, compare every timeline with "
                                   "the reference, audit skipping, print tables and write a plot and a JSON.")
    p.add_argument("video", nargs="*", help="input media files")
    p.add_argument("--config", action="append", default=[], metavar="NAME:k=v,k=v",
                   help="an extra configuration: dotted overrides, preset=NAME picks the base (default balanced); "
                        "repeatable")
    p.add_argument("--out", default="out/bench/accuracy", help="folder for the JSON, plots and timelines")
    p.add_argument("--repeat", type=int, default=1,
                   help="runs of the decode and of each configuration but the reference, alternating "
                        "(median wall time; default 1)")
    p.add_argument("--no-snapshot", action="store_true",
                   help="run the installed package; by default the children run a copy of it taken at the start, "
                        "so a long run measures one version of the code")
    p.add_argument("--no-skip-audit", action="store_true", help="do not run balanced with video.skip=false")
    p.add_argument("--loop", type=int, default=1, metavar="N",
                   help="first re-encode each VIDEO N times in a row into one longer clip in --out")
    p.add_argument("--synth", action="append", default=[], metavar="WxH@FPS:SECONDS",
                   help="also benchmark a synthetic clip of that size and length (written into --out)")
    p.add_argument("--format", choices=("png", "svg"), default="png", help="plot format (default png)")
    p.set_defaults(func=run)


def run(args) -> int:
    if args.repeat < 1 or args.loop < 1:
        raise ParameterError("--repeat and --loop must be >= 1")
    configs = default_configs(not args.no_skip_audit) + [parse_config(c) for c in args.config]
    names = [c.name for c in configs]
    if len(set(names)) != len(names):
        raise ParameterError(f"configuration names must be unique, got {names}")
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    git = _git_state()
    if not args.no_snapshot:
        snapshot_source(out / "_source")
    clips = []
    for v in args.video:
        p = Path(v)
        if not p.is_file():
            raise ParameterError(f"{p}: no such file")
        if args.loop > 1:
            from autohaptics.bench.pipeline import looped_clip

            p = looped_clip(p, args.loop, out)
        clips.append(p)
    clips += [synth_clip(out, spec) for spec in args.synth]
    if not clips:
        raise ParameterError("give at least one VIDEO or --synth WxH@FPS:SECONDS")
    print(f"source tree: {git}" + ("" if args.no_snapshot else f" (measured from a copy in {out / '_source'})")
          + f"; {os.cpu_count()} CPUs; load average {os.getloadavg()[0]:.1f}")
    print(f"configurations: {', '.join(f'{c.name} ({c.preset}' + ''.join(f', {k}={v}' for k, v in c.overrides) + ')' for c in configs)}")
    doc = {"configs": [{"name": c.name, "preset": c.preset, "overrides": dict(c.overrides)} for c in configs],
           "targets": TARGETS, "python": sys.version.split()[0], "cpu_count": os.cpu_count(), "git": git,
           "snapshot": not args.no_snapshot, "load_average_start": os.getloadavg(),
           "clips": []}
    for clip in clips:
        res = bench_clip(clip, configs, out, repeat=args.repeat)
        print_tables(res)
        for line in verdicts(res):
            print("  " + line)
        if any("error" in c for c in res["configs"].values()):
            res["plot"] = str(plot(res, out / f"accuracy_{clip.stem}.{args.format}"))
            print(f"plot: {res['plot']}")
        doc["clips"].append(res)
        (out / "accuracy.json").write_text(json.dumps(doc, indent=1))
    print(f"figures: {out / 'accuracy.json'}")
    return 0


def _git_state() -> str | None:
    """The source tree measured: commit, plus "+dirty" when files differ from it (None outside git)."""
    root = Path(__file__).resolve().parents[3]
    try:
        head = subprocess.run(["git", "-C", str(root), "rev-parse", "--short", "HEAD"], capture_output=True,
                              text=True, timeout=10).stdout.strip()
        dirty = subprocess.run(["git", "-C", str(root), "status", "--porcelain", "--untracked-files=no"],
                               capture_output=True, text=True, timeout=10).stdout.strip()
    except (OSError, subprocess.SubprocessError):
        return None
    return (head + ("+dirty" if dirty else "")) or None


def _main(argv: list[str]) -> int:
    """Entry point of the measured child processes (``python -m autohaptics.bench.accuracy``)."""
    if not argv or argv[0] not in ("_decode", "_generate"):
        print("usage: python -m autohaptics.bench.accuracy _decode|_generate ... (use `autohaptics bench accuracy`)",
              file=sys.stderr)
        return 2
    (_worker_decode if argv[0] == "_decode" else _worker_generate)(argv[1:])
    return 0


if __name__ == "__main__":
    sys.exit(_main(sys.argv[1:]))
