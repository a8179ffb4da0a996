"""``autohaptics bench export``: time and peak memory of every exporter on a generated timeline.

The timeline (default 2 hours = 72,000 ticks) comes from :func:`synthetic_timeline`: film-like
scenes of silence, held levels, ramps and busy per-tick action on the motors, slow temperature
drifts, and bursts of fans. Each format is measured in its own fresh process (so one export's
freed memory does not hide the next one's peak). Figures are printed, never asserted.
"""

from __future__ import annotations

import argparse
import gc
import json
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np
import psutil

from autohaptics.bench.common import measure, table
from autohaptics.errors import AutohapticsError
from autohaptics.formats import FORMATS, export_timeline, get_format
from autohaptics.layout import DEVICE_TEMP_MAX_C, FAN_COLS, FAN_ROWS, N_ACTUATORS, TEMP_LOW_C
from autohaptics.temperature import played_curve
from autohaptics.timebase import n_ticks as ticks_for
from autohaptics.timeline import Timeline


def synthetic_timeline(n_ticks: int, *, seed: int = 0) -> Timeline:
    """A deterministic film-like timeline of ``n_ticks`` ticks (values rounded to 4 decimals).

    Scenes of 1..90 s, each one of: silence, a held level, a ramp, or busy per-tick action on a
    random subset of motors; the temperature ramps to a new target each scene and holds, as a chair
    plays it (:func:`~autohaptics.temperature.played_curve`: from 33 C, at most 1 C/s); about a
    third of the scenes carry a burst of fans over a random block of cells.
    """
    rng = np.random.default_rng(seed)
    n = int(n_ticks)
    tl = Timeline.empty(n, source={"name": f"synthetic-{seed}", "duration_s": round(n * 0.1, 4),
                                   "video": None, "audio": None})
    vib = np.zeros((n, N_ACTUATORS))
    temp = np.empty(n)
    fans = np.zeros((n, FAN_ROWS, FAN_COLS))
    current_t = 33.0
    a = 0
    while a < n:
        b = min(n, a + int(rng.integers(10, 900)))
        m = b - a
        weights = rng.random(N_ACTUATORS) * (rng.random(N_ACTUATORS) < 0.6)
        kind = rng.choice(4, p=[0.3, 0.2, 0.2, 0.3])
        if kind == 1:
            vib[a:b] = rng.uniform(0.2, 1.0) * weights
        elif kind == 2:
            vib[a:b] = np.linspace(rng.uniform(0, 1), rng.uniform(0, 1), m)[:, None] * weights
        elif kind == 3:
            env = rng.random(m)
            env[env < 0.4] = 0.0
            vib[a:b] = env[:, None] * weights
        target = rng.uniform(TEMP_LOW_C, DEVICE_TEMP_MAX_C)
        ramp = min(m, int(rng.integers(20, 200)))
        temp[a:a + ramp] = np.linspace(current_t, target, ramp)
        temp[a + ramp:b] = target
        current_t = target
        if rng.random() < 0.35:
            r0, c0 = int(rng.integers(0, FAN_ROWS)), int(rng.integers(0, FAN_COLS))
            r1, c1 = min(FAN_ROWS, r0 + int(rng.integers(1, 5))), min(FAN_COLS, c0 + int(rng.integers(1, 7)))
            s = a + int(rng.integers(0, m))
            e = min(b, s + int(rng.integers(5, 60)))
            fans[s:e, r0:r1, c0:c1] = rng.uniform(0.3, 1.0, size=(e - s, 1, 1))
        a = b
    tl.vibration = np.round(np.clip(vib, 0, 1), 4).astype(np.float32)
    tl.temperature_c = np.round(played_curve(temp), 4).astype(np.float32)
    tl.fans = np.round(np.clip(fans, 0, 1), 4).astype(np.float32)
    return tl.validate()


def register(sub) -> None:
    p = sub.add_parser("export", help="export time and peak memory per format for a generated 2-hour timeline",
                       description="Generate a film-like timeline and export it in every format, printing "
                                   "wall time, CPU time, peak RSS and output size per format.")
    p.add_argument("--hours", type=float, default=2.0, help="timeline length in hours (default 2)")
    p.add_argument("--seed", type=int, default=0, help="random seed of the generated timeline")
    p.add_argument("--formats", default=",".join(FORMATS), help="comma-separated formats (default: all)")
    p.add_argument("--keep", metavar="DIR", default=None, help="write the exports into DIR and keep them")
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    specs = [get_format(f.strip()) for f in args.formats.split(",") if f.strip()]
    n = ticks_for(args.hours * 3600.0)
    built = measure(lambda: synthetic_timeline(n, seed=args.seed))
    print(f"timeline: {n} ticks ({args.hours:g} h), generated in {built.wall_s:.2f} s; each format is "
          "exported in a fresh process that first generates the same timeline")
    del built
    rows = []
    with tempfile.TemporaryDirectory(prefix="autohaptics-bench-") as tmp:
        out_dir = Path(args.keep) if args.keep else Path(tmp)
        out_dir.mkdir(parents=True, exist_ok=True)
        for spec in specs:
            path = out_dir / f"bench-{args.hours:g}h-{spec.name}{spec.suffix}"
            r = _run_child(spec.name, n, args.seed, path)
            rows.append([spec.name, r["wall_s"], r["cpu_s"], r["rss_before_MiB"], r["peak_rss_MiB"],
                         r["peak_rss_MiB"] - r["rss_before_MiB"], path.stat().st_size / 2**20])
    print(table(rows, ["format", "wall_s", "cpu_s", "rss_before_MiB", "peak_rss_MiB", "peak_increase_MiB",
                       "size_MiB"]))
    if args.keep:
        print(f"files kept in {args.keep}")
    return 0


def _run_child(fmt: str, n: int, seed: int, path: Path) -> dict:
    cmd = [sys.executable, "-m", "autohaptics.bench.export", fmt, str(n), str(seed), str(path)]
    proc = subprocess.run(cmd, capture_output=True, text=True, check=False)
    if proc.returncode != 0:
        raise AutohapticsError(f"bench export: exporting {fmt} failed: {proc.stderr.strip()[-400:]}")
    return json.loads(proc.stdout.strip().splitlines()[-1])


def _child(fmt: str, n: int, seed: int, path: str) -> dict:
    """Generate the timeline, then export it once, measured (runs in a fresh process)."""
    tl = synthetic_timeline(n, seed=seed)
    gc.collect()
    before = psutil.Process().memory_info().rss / 2**20
    m = measure(lambda: export_timeline(tl, fmt, path))
    return {"wall_s": m.wall_s, "cpu_s": m.cpu_s, "rss_before_MiB": before, "peak_rss_MiB": m.peak_rss_mb}


if __name__ == "__main__":  # the measured child of run(): FORMAT N_TICKS SEED PATH
    print(json.dumps(_child(sys.argv[1], int(sys.argv[2]), int(sys.argv[3]), sys.argv[4])))
