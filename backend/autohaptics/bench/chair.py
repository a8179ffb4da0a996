"""``autohaptics bench chair [--seconds 60]``: stream to the virtual chair and print timing.

Method. A virtual chair (the firmware core on a pty, see autohaptics.chair.simulate) logs the
CLOCK_MONOTONIC time at which its core applied each frame; the host records CLOCK_MONOTONIC
(``time.monotonic_ns``) just before it writes each frame. Both clocks are the same clock on the
same machine, so:

- tick jitter: deviation of each tick's time from an ideal 100 ms grid, ``|t_k - k * 100 ms - c|``
  with ``c`` the median offset, for the chair's applied times and for the host's send times;
  and the deviation of each interval from 100 ms;
- end-to-end latency: chair applied time - host send time, per tick (pyserial write, the pty,
  the chair's parser and apply).

Target: chair-side tick jitter and latency p99 <= 2 ms. Figures depend on the machine's load,
so the same window also measures a scheduler baseline: a plain 10 Hz timer thread in this
process (the player's wait primitive, half a tick out of phase), and prints how late it woke.
When the baseline's p99 is far above 2 ms, the machine, not the link, sets the tail.
Also prints the Cortex-M4 flash/RAM of the core when arm-none-eabi-gcc and make are present.
"""

from __future__ import annotations

import re
import shutil
import subprocess
import tempfile
import threading
import time
from pathlib import Path

import numpy as np

from autohaptics.bench.common import table
from autohaptics.chair.link import ChairLink
from autohaptics.chair.player import push
from autohaptics.chair.simulate import VirtualChair, firmware_dir
from autohaptics.errors import DeviceError, ParameterError
from autohaptics.timeline import Timeline

TARGET_P99_MS = 2.0


def register(sub) -> None:
    p = sub.add_parser("chair", help="stream to the virtual chair: tick jitter and end-to-end latency",
                       description=__doc__.split("\n\n", 1)[1] if __doc__ else None,
                       formatter_class=__import__("argparse").RawDescriptionHelpFormatter)
    p.add_argument("--seconds", type=float, default=60.0, help="how long to stream (default 60)")
    p.add_argument("--seed", type=int, default=0, help="random timeline content")
    p.set_defaults(func=run)


def run(args) -> int:
    if not args.seconds > 0:
        raise ParameterError(f"--seconds must be positive, got {args.seconds}")
    print(f"streaming {args.seconds:g} s ({int(np.ceil(args.seconds * 10))} ticks) to a virtual chair ...", flush=True)
    r = measure_stream(args.seconds, seed=args.seed)
    print(f"frames: sent {r['sent']}, applied {r['applied']}, duplicates {r['duplicates']}, "
          f"gaps {r['gaps']}, ticks skipped by the player {r['skipped']}; player clock {r['clock_priority']}, "
          f"virtual chair nice {r['chair_nice']}")
    rows = []
    for label, values in (("chair tick vs 100 ms grid", r["chair_grid"]), ("chair interval - 100 ms", r["chair_interval"]),
                          ("host send vs 100 ms grid", r["host_grid"]), ("host interval - 100 ms", r["host_interval"]),
                          ("latency send -> applied", r["latency"]),
                          ("baseline: plain timer lateness", r["baseline"])):
        rows.append([label, *_percentiles(values)])
    print(table(rows, ["ms", "p50", "p99", "max"]))
    for label, values in (("chair tick jitter", r["chair_grid"]), ("latency", r["latency"])):
        p99 = float(np.percentile(values, 99))
        print(f"{label} p99 {p99:.3f} ms: {'meets' if p99 <= TARGET_P99_MS else 'MISSES'} the {TARGET_P99_MS:g} ms target")
    size = cross_size()
    if size is None:
        print("cross-compiled size: skipped (needs make and arm-none-eabi-gcc: "
              "apt-get install make gcc-arm-none-eabi libnewlib-arm-none-eabi)")
    else:
        print(f"core on Cortex-M4 (-Os): flash {size['core_flash']} B, static RAM {size['chair_ram']} B (chair_t), "
              f"deepest stack frame {size['max_frame']} B; minimal linked image text {size['image_text']} B, "
              f"data {size['image_data']} B, bss {size['image_bss']} B")
    return 0


def measure_stream(seconds: float, *, seed: int = 0) -> dict:
    """Stream ``seconds`` of a random timeline to a fresh virtual chair; return the raw figures (ms)."""
    n = int(np.ceil(seconds * 10))
    rng = np.random.default_rng(seed)
    tl = Timeline.empty(n)
    tl.vibration[:] = rng.random((n, 9))
    tl.fans[:] = rng.random((n, 9, 17))
    tl.temperature_c[:] = rng.uniform(30.0, 40.0, n)
    sent: dict[int, float] = {}
    baseline: list[float] = []
    stop = threading.Event()
    timer = threading.Thread(target=_timer_baseline, args=(stop, baseline), daemon=True)
    with tempfile.TemporaryDirectory(prefix="autohaptics-bench-chair-") as tmp:
        with VirtualChair(link_path=Path(tmp) / "chair", log_path=Path(tmp) / "chair.jsonl") as chair:
            with ChairLink(chair.device) as link:
                link.on("sent", lambda tick, seq, t_ns: sent.__setitem__(tick, t_ns / 1e6))
                timer.start()
                try:
                    status = push(link, tl)
                finally:
                    stop.set()
                    timer.join()
            chair.wait_for(lambda e: e["ev"] == "stop")
            frames = chair.frames()
            nice = chair.read_log()[0].get("nice")
    ticks = np.array([e["tick"] for e in frames], dtype=np.int64)
    if len(ticks) < 2:
        raise DeviceError(f"the virtual chair applied only {len(ticks)} frames")
    applied = np.array([e["t_ms"] for e in frames])
    send = np.array([sent[k] for k in ticks])
    return {
        "sent": status.frames_sent, "applied": len(ticks), "skipped": status.ticks_skipped,
        "duplicates": int(len(ticks) - len(np.unique(ticks))), "gaps": int(np.sum(np.diff(ticks) > 1)),
        "chair_grid": _grid_deviation(ticks, applied), "host_grid": _grid_deviation(ticks, send),
        "chair_interval": _interval_deviation(ticks, applied), "host_interval": _interval_deviation(ticks, send),
        "latency": applied - send,
        "baseline": np.array(baseline), "clock_priority": status.clock_priority, "chair_nice": nice,
    }


def _timer_baseline(stop: threading.Event, out: list[float]) -> None:
    """Lateness (ms) of a plain 10 Hz timer thread, offset by half a tick from the player."""
    t0 = time.monotonic() + 0.05
    k = 0
    while not stop.is_set():
        k += 1
        due = t0 + k * 0.1
        while (wait := due - time.monotonic()) > 0:
            if stop.wait(wait):
                return
        out.append((time.monotonic() - due) * 1000.0)


def _grid_deviation(ticks: np.ndarray, t_ms: np.ndarray) -> np.ndarray:
    d = t_ms - ticks * 100.0
    return np.abs(d - np.median(d))


def _interval_deviation(ticks: np.ndarray, t_ms: np.ndarray) -> np.ndarray:
    ok = np.diff(ticks) == 1
    return np.abs(np.diff(t_ms)[ok] - 100.0)


def _percentiles(values: np.ndarray) -> list[float]:
    return [float(np.percentile(values, 50)), float(np.percentile(values, 99)), float(np.max(values))]


def cross_size() -> dict | None:
    """Cross-compile the core (``make size``) and parse its figures; None without the toolchain."""
    if shutil.which("make") is None or shutil.which("arm-none-eabi-gcc") is None:
        return None
    with tempfile.TemporaryDirectory(prefix="autohaptics-fw-size-") as build:
        proc = subprocess.run(["make", "-C", str(firmware_dir()), f"BUILD={build}", "size"],
                              capture_output=True, text=True)
    if proc.returncode != 0:
        raise DeviceError(f"cross-compiling the firmware core failed:\n{proc.stderr.strip()}")
    out = proc.stdout
    total = re.search(r"^\s*(\d+)\s+(\d+)\s+(\d+)\s+\d+\s+[0-9a-f]+\s+\(TOTALS\)", out, re.M)
    image = re.search(r"^\s*(\d+)\s+(\d+)\s+(\d+)\s+\d+\s+[0-9a-f]+\s+\S*size_main\.elf", out, re.M)
    chair = re.search(r"^[0-9a-f]+ ([0-9a-f]+) b chair$", out, re.M)
    frames = [int(m) for m in re.findall(r"^\S+\t(\d+)\t", out, re.M)]
    if not (total and image and chair):
        raise DeviceError(f"unexpected `make size` output:\n{out}")
    return {"core_flash": int(total.group(1)) + int(total.group(2)), "chair_ram": int(chair.group(1), 16),
            "image_text": int(image.group(1)), "image_data": int(image.group(2)), "image_bss": int(image.group(3)),
            "max_frame": max(frames) if frames else 0}
