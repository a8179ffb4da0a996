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


def looped_clip(src: str | Path, times: int, out_dir: Path) -> Path:
    """Write ``src`` played ``times`` times in a row (x264 veryfast + AAC), reusing an existing file."""
    import av
    import numpy as np

    src = Path(src)
    out = out_dir / f"{src.stem}_x{times}.mp4"
    if out.exists():
        return out
    out_dir.mkdir(parents=True, exist_ok=True)
    info = media.probe(src)
    tmp = out.with_suffix(".part.mp4")
    with av.open(str(tmp), "w") as dst:
        vs = as_ = None
        if info.video is not None:
            vs = dst.add_stream("libx264", rate=round(info.video.fps))
            vs.width, vs.height, vs.pix_fmt = info.video.width, info.video.height, "yuv420p"
            vs.options = {"preset": "veryfast", "crf": "20"}
        if info.audio is not None:
            layout = {1: "mono", 2: "stereo", 6: "5.1"}.get(info.audio.channels, "stereo")
            as_ = dst.add_stream("aac", rate=info.audio.sample_rate, layout=layout)
        v_n = a_n = 0
        for _ in range(times):
            with av.open(str(src)) as s:
                streams = [x for x in (s.streams.video[:1] + s.streams.audio[:1])]
                for frame in s.decode(*streams):
                    if isinstance(frame, av.VideoFrame) and vs is not None:
                        f = av.VideoFrame.from_ndarray(frame.to_ndarray(format="yuv420p"), format="yuv420p")
                        f.pts = v_n
                        v_n += 1
                        dst.mux(vs.encode(f))
                    elif isinstance(frame, av.AudioFrame) and as_ is not None:
                        arr = frame.to_ndarray()
                        if not frame.format.is_planar:
                            arr = arr.reshape(-1, frame.layout.nb_channels).T
                        arr = np.ascontiguousarray(arr[: as_.layout.nb_channels].astype(np.float32))
                        f = av.AudioFrame.from_ndarray(arr, format="fltp", layout=as_.layout.name)
                        f.sample_rate = info.audio.sample_rate
                        f.pts = a_n
                        a_n += f.samples
                        dst.mux(as_.encode(f))
        if vs is not None:
            dst.mux(vs.encode(None))
        if as_ is not None:
            dst.mux(as_.encode(None))
    tmp.replace(out)
    return out


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
