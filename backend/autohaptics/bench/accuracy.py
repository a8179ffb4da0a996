"""``autohaptics bench accuracy VIDEO...``: run time against error, per configuration.

For each clip, every configuration (``reference``, ``balanced``, ``fast``, ``balanced`` without
skipping, and any ``--config``) runs ``generate`` in a FRESH process, so its peak memory is its
own; the bare decode (:func:`autohaptics.bench.decode.bare_decode`) runs in its own process in the
same run. Wall time is the ``generate`` call itself (after imports and a warm-up of
the compiled audio kernels, which a long film pays once); peak RSS is the whole process's
(``ru_maxrss`` from ``wait4``). Each timeline is compared with the reference one
(:mod:`autohaptics.metrics`).

Outputs (in ``--out``): ``accuracy.json``, ``accuracy_<clip>.png`` (x = wall time / decode time,
y = vibration MAE, temperature MAE, 1 - fan IoU; the Pareto front drawn), and the timelines. Printed: the table, the per-stage seconds (where the time
goes) and the skipping audit (share of ticks computed vs skipped per stage, and what skipping
costs in error: ``balanced`` vs ``balanced`` with ``video.skip=false``, both against the reference
and against each other).

Each ratio is given twice: in-process (``x_decode``: the ``generate`` call against the decode
call) and whole-process (``x_decode_process``: from process start to exit, imports, kernel loading
and writing the timeline included, against a process that only decodes). ``--films`` adds the
film-like clips of :mod:`autohaptics.bench.clips`, written into ``--out``.

Targets (checked here, never by timed assertions): balanced <= 1.25 x decode on a 1080p clip with
vibration MAE <= 0.02, onset F1 >= 0.97, temperature MAE <= 0.3 C and fan IoU >= 0.9 against
the reference; fast at least 2 x cheaper than balanced in analysis cost (wall - decode).
"""

from __future__ import annotations

import json
import os
import statistics
import subprocess
from fractions import Fraction
from pathlib import Path

from autohaptics.bench.child import measure_decode, measure_generate, snapshot_source
from autohaptics.bench.common import machine, machine_line
from autohaptics.bench.configs import NOSKIP, REFERENCE, SKIP_STAGES, TARGETS, Config, default_configs, parse_config
from autohaptics.bench.report import plot, print_tables, verdicts
from autohaptics.errors import ParameterError

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
    decode_process_s = statistics.median(d["process_wall_s"] for d in decodes)
    result = {"clip": str(video), "duration_s": info.duration_s,
              "video": None if info.video is None else {"width": info.video.width, "height": info.video.height,
                                                        "fps": info.video.fps, "codec": info.video.codec},
              "audio": None if info.audio is None else {"codec": info.audio.codec, "channels": info.audio.channels,
                                                        "sample_rate": info.audio.sample_rate},
              "repeat": repeat, "load_average": os.getloadavg(),
              "decode": {"wall_s": decode_s, "runs_s": [d["wall_s"] for d in decodes],
                         "process_wall_s": decode_process_s,
                         "cpu_s": statistics.median(d["cpu_s"] for d in decodes),
                         "peak_rss_mb": max(d["peak_rss_mb"] for d in decodes),
                         "video_frames": decodes[0]["video_frames"], "audio_samples": decodes[0]["audio_samples"]},
              "configs": {}}
    timelines = {c.name: Timeline.load(work / f"{c.name}.json") for c in configs}
    ref = timelines.get(REFERENCE)
    for c in configs:
        rs = runs[c.name]
        wall = statistics.median(r["wall_s"] for r in rs)
        process_s = statistics.median(r["process_wall_s"] for r in rs)
        entry = {"preset": c.preset, "overrides": dict(c.overrides), "wall_s": wall, "runs_s": [r["wall_s"] for r in rs],
                 "process_wall_s": process_s,
                 "x_decode_process": process_s / decode_process_s if decode_process_s > 0 else float("nan"),
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
    p.add_argument("--films", action="store_true",
                   help="also benchmark the film-like clips made from the shared clips (1080p24 letterboxed and "
                        "full-frame, 480p25 5.1; into --out)")
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
            from autohaptics.bench.clips import looped_clip

            p = looped_clip(p, args.loop, out)
        clips.append(p)
    clips += [synth_clip(out, spec) for spec in args.synth]
    if args.films:
        from autohaptics.bench.clips import film_clips

        clips += film_clips(out)
    if not clips:
        raise ParameterError("give at least one VIDEO, --films or --synth WxH@FPS:SECONDS")
    here = machine()
    print(f"source tree: {git}" + ("" if args.no_snapshot else f" (measured from a copy in {out / '_source'})")
          + f"; load average {os.getloadavg()[0]:.1f}")
    print(machine_line(here))
    print(f"configurations: {', '.join(f'{c.name} ({c.preset}' + ''.join(f', {k}={v}' for k, v in c.overrides) + ')' for c in configs)}")
    doc = {"configs": [{"name": c.name, "preset": c.preset, "overrides": dict(c.overrides)} for c in configs],
           "targets": TARGETS, "machine": here, "git": git,
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
