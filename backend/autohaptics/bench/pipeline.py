"""``autohaptics bench pipeline VIDEO``: full generation time / bare decode time, per-stage seconds.

Both are measured in this one run, alternating, each repeated, so machine noise hits both alike;
the figure that matters is the ratio (target <= 1.25 on a 1080p clip with the balanced preset).
``--loop N`` first writes a longer clip by playing VIDEO N times in a row (re-encoded with x264
and AAC at the source resolution), for clips too short to measure.
"""

from __future__ import annotations

import json
import statistics
import sys
import time
from pathlib import Path

from autohaptics import media
from autohaptics.bench.clips import looped_clip
from autohaptics.bench.common import measure, table
from autohaptics.params import add_generation_options, params_from_args


def register(sub) -> None:
    p = sub.add_parser("pipeline", help="generation wall time divided by bare decode time, per-stage seconds")
    p.add_argument("video", help="input media file")
    p.add_argument("--repeat", type=int, default=3, help="measurements of each (default 3; the median is reported)")
    p.add_argument("--loop", type=int, default=1, help="first write a clip that plays VIDEO this many times")
    p.add_argument("--out", default="out/bench", help="folder for the looped clip and the JSON figures")
    add_generation_options(p)
    p.set_defaults(func=run)


def run(args) -> int:
    from autohaptics.pipeline import generate

    params, preset = params_from_args(args)
    path = Path(args.video)
    if args.loop > 1:
        print(f"writing {args.loop} x {path.name} ...", file=sys.stderr)
        path = looped_clip(path, args.loop, Path(args.out))
    info = media.probe(path)
    generate(path, params, preset=preset)  # warm-up: JIT caches, file cache
    decode_s, gen_s, rss = [], [], []
    tl = None
    for _ in range(max(1, args.repeat)):
        decode_s.append(measure(lambda: media.decode_all(path, info=info)).wall_s)
        m = measure(lambda: generate(path, params, preset=preset))
        gen_s.append(m.wall_s)
        rss.append(m.peak_rss_mb)
        tl = m.result
    d, g = statistics.median(decode_s), statistics.median(gen_s)
    v = info.video
    print(f"{path.name}: {info.duration_s:.1f} s, "
          f"{'%dx%d @ %.2f fps' % (v.width, v.height, v.fps) if v else 'no video'}, preset {preset}, mode {params.mode}")
    print(f"bare decode {d:.3f} s, generate {g:.3f} s, ratio {g / d:.3f} (median of {len(gen_s)}), "
          f"peak RSS {max(rss):.0f} MB")
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
           "peak_rss_mb": max(rss), "stats": st, "time": time.strftime("%Y-%m-%d %H:%M:%S")}
    (out / f"pipeline_{path.stem}_{preset}.json").write_text(json.dumps(fig, indent=1, default=str))
    return 0
