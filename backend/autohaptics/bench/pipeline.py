"""``autohaptics bench pipeline VIDEO...``: full generation time / bare decode time, per-stage seconds.

Both are measured in this one run, alternating, each repeated, so machine noise hits both alike;
the figure that matters is the ratio (target <= 1.25 on a 1080p clip with the balanced preset).
It is given in-process (the ``generate`` call against :func:`autohaptics.bench.decode.bare_decode`,
warmed up) and for whole processes (start to exit, imports and kernel loading included, against a
process that only decodes). ``--loop N`` first writes a longer clip by playing VIDEO N times in a
row (re-encoded with x264 and AAC at the source resolution), for clips too short to measure;
``--copies N`` writes one that plays it N times by copying its packets (the same encode at feature
length: 35 copies of a 53 s clip make 31 minutes); ``--films`` adds the film-like clips of
:mod:`autohaptics.bench.clips` (1080p24 letterboxed and full-frame, 480p25 5.1).
"""

from __future__ import annotations

import json
import statistics
import sys
import time
from dataclasses import dataclass
from pathlib import Path

from autohaptics import media
from autohaptics.bench.clips import copied_clip, film_clips, looped_clip
from autohaptics.bench.common import machine, machine_line, measure, table
from autohaptics.bench.decode import bare_decode
from autohaptics.errors import ParameterError
from autohaptics.params import add_generation_options, params_from_args


def register(sub) -> None:
    p = sub.add_parser("pipeline", help="generation wall time divided by bare decode time, per-stage seconds")
    p.add_argument("video", nargs="*", help="input media files")
    p.add_argument("--films", action="store_true",
                   help="also the film-like clips made from the shared clips (1080p24 letterboxed and full-frame, "
                        "480p25 5.1; into --out)")
    p.add_argument("--repeat", type=int, default=3, help="measurements of each (default 3; the median is reported)")
    p.add_argument("--loop", type=int, default=1, help="first write a clip that plays VIDEO this many times")
    p.add_argument("--copies", type=int, default=1,
                   help="first write a film that plays VIDEO this many times by copying its packets (feature length)")
    p.add_argument("--out", default="out/bench", help="folder for the looped clip and the JSON figures")
    add_generation_options(p)
    p.set_defaults(func=run)


@dataclass(frozen=True)
class GenerateRun:
    """The measured child's generation options (what :func:`autohaptics.bench.child.measure_generate` takes)."""

    name: str
    argv: tuple[str, ...]

    def cli_args(self) -> list[str]:
        return list(self.argv)


def generation_argv(args) -> tuple[str, ...]:
    """The generation options of ``args`` (:func:`autohaptics.params.add_generation_options`) as argv."""
    argv = ["--preset", args.preset] + (["--mode", args.mode] if args.mode else [])
    argv += [a for t in args.threshold for a in ("--threshold", t)]
    argv += [a for o in args.overrides for a in ("--set", o)]
    argv += ["--pa-per-unit", repr(args.pa_per_unit)] if args.pa_per_unit is not None else []
    return tuple(argv + (["--allow-truncated"] if args.allow_truncated else []))


def whole_process(path: Path, args, out: Path) -> tuple[float, float, float, float]:
    """Median whole-process seconds (start to exit) of a bare decode and of ``generate``, alternating:
    wall decode, wall generate, CPU (user + system) decode, CPU generate."""
    from autohaptics.bench.child import measure_decode, measure_generate

    work = out / f"{path.stem}_process"
    work.mkdir(parents=True, exist_ok=True)
    run = GenerateRun(f"generate_{args.preset}", generation_argv(args))
    runs = []
    for _ in range(max(1, args.repeat)):
        d, g = measure_decode(path, work), measure_generate(path, run, work)
        runs.append((d["process_wall_s"], g["process_wall_s"], d["process_cpu_s"], g["process_cpu_s"]))
    return tuple(statistics.median(col) for col in zip(*runs))


def run(args) -> int:
    from autohaptics.pipeline import generate

    params, preset = params_from_args(args)
    paths = [Path(v) for v in args.video]
    if args.loop > 1:
        print(f"writing {args.loop} x ...", file=sys.stderr)
        paths = [looped_clip(p, args.loop, Path(args.out)) for p in paths]
    if args.copies > 1:
        print(f"writing {args.copies} copies ...", file=sys.stderr)
        paths = [copied_clip(p, args.copies, Path(args.out)) for p in paths]
    if args.films:
        paths += film_clips(Path(args.out))
    if not paths:
        raise ParameterError("give at least one VIDEO or --films")
    print(machine_line())
    for path in paths:
        bench_one(path, args, params, preset, generate)


def bench_one(path: Path, args, params, preset: str, generate) -> None:
    """The figures of one clip: in-process (median of --repeat) and whole-process, printed and saved."""
    info = media.probe(path)
    generate(path, params, preset=preset)  # warm-up: JIT caches, file cache
    decode_s, gen_s, rss = [], [], []
    tl = None
    for _ in range(max(1, args.repeat)):
        decode_s.append(measure(lambda: bare_decode(path)).wall_s)
        m = measure(lambda: generate(path, params, preset=preset))
        gen_s.append(m.wall_s)
        rss.append(m.peak_rss_mb)
        tl = m.result
    d, g = statistics.median(decode_s), statistics.median(gen_s)
    v = info.video
    print(f"{path.name}: {info.duration_s:.1f} s, "
          f"{'%dx%d @ %.2f fps' % (v.width, v.height, v.fps) if v else 'no video'}, preset {preset}, mode {params.mode}")
    print(f"in-process: bare decode {d:.3f} s, generate {g:.3f} s, ratio {g / d:.3f} (median of {len(gen_s)}), "
          f"peak RSS {max(rss):.0f} MB")
    pd, pg, cd, cg = whole_process(path, args, Path(args.out))
    print(f"whole process (start to exit): bare decode {pd:.3f} s, generate {pg:.3f} s, ratio {pg / pd:.3f}; "
          f"CPU {cd:.3f} s and {cg:.3f} s, ratio {cg / cd:.3f}")
    rows = []
    st = tl.stats
    rows.append(["audio (decode+features)", st.get("audio", {}).get("seconds", 0.0), "", "", ""])
    for name, s in (st.get("video") or {}).items():
        if isinstance(s, dict) and "seconds" in s:
            rows.append([f"video.{name}", s["seconds"], s.get("ticks_computed", s.get("computed", "")),
                         s.get("ticks_skipped", ""), s.get("ticks_held", "")])
    rows.append(["derive", st.get("derive", {}).get("seconds", 0.0), "", "", ""])
    print(table(rows, ["stage", "seconds", "computed", "skipped", "held"]))
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    fig = {"file": str(path), "preset": preset, "decode_s": decode_s, "generate_s": gen_s, "ratio": g / d,
           "process_decode_s": pd, "process_generate_s": pg, "process_ratio": pg / pd,
           "process_decode_cpu_s": cd, "process_generate_cpu_s": cg, "process_cpu_ratio": cg / cd,
           "peak_rss_mb": max(rss), "stats": st, "time": time.strftime("%Y-%m-%d %H:%M:%S"), "machine": machine()}
    (out / f"pipeline_{path.stem}_{preset}.json").write_text(json.dumps(fig, indent=1, default=str))
