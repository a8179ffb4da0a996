"""Helpers shared by the benchmarks: wall time, CPU time and peak memory of a callable, and the
machine a figure was measured on."""

from __future__ import annotations

import hashlib
import os
import platform
import resource
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import psutil


@dataclass
class Measurement:
    wall_s: float
    cpu_s: float
    peak_rss_mb: float  # peak resident set size of this process while the call ran, MiB
    result: Any = None


def measure(fn: Callable[[], Any], *, sample_s: float = 0.01) -> Measurement:
    """Run ``fn`` once; return its wall time, process CPU time and peak RSS (sampled every 10 ms)."""
    proc = psutil.Process()
    peak = proc.memory_info().rss
    stop = threading.Event()

    def sampler():
        nonlocal peak
        while not stop.is_set():
            try:
                peak = max(peak, proc.memory_info().rss)
            except psutil.Error:
                return
            stop.wait(sample_s)

    t = threading.Thread(target=sampler, daemon=True)
    t.start()
    cpu0 = time.process_time()
    t0 = time.perf_counter()
    try:
        result = fn()
    finally:
        wall = time.perf_counter() - t0
        cpu = time.process_time() - cpu0
        stop.set()
        t.join()
    peak = max(peak, proc.memory_info().rss)
    return Measurement(wall_s=wall, cpu_s=cpu, peak_rss_mb=peak / 2**20, result=result)


def lifetime_peak_rss_mb() -> float:
    """Peak RSS of this process since it started (ru_maxrss), MiB."""
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0


ENV_PACKAGES = ("numpy", "scipy", "av", "opencv-contrib-python-headless", "numba", "onnxruntime")


def environment() -> dict:
    """What decides the last bits of the floating-point results: the packages' versions and the
    CPU's instruction sets (a hash of /proc/cpuinfo's flags; None where it cannot be read)."""
    from importlib.metadata import PackageNotFoundError, version

    env: dict[str, Any] = {"machine": platform.machine(), "python": platform.python_version()}
    for pkg in ENV_PACKAGES:
        try:
            env[pkg] = version(pkg)
        except PackageNotFoundError:
            env[pkg] = None
    flags = _cpuinfo("flags")
    env["cpu_flags_sha256"] = None if flags is None else \
        hashlib.sha256(" ".join(sorted(flags.split())).encode()).hexdigest()[:16]
    return env


def machine() -> dict:
    """:func:`environment` plus the CPU's model and core count and the FFmpeg inside PyAV: a
    benchmark's figures belong to them (timings do; the same re-encoded pair read other accuracy
    figures on two CPUs, docs/BENCHMARKS.md "Stop 51"), so every figures file records them."""
    import av

    return {**environment(), "cpu": _cpuinfo("model name") or platform.processor() or None,
            "cores": os.cpu_count(), "ffmpeg": getattr(av, "ffmpeg_version_info", None)}


def machine_line(m: dict | None = None) -> str:
    """:func:`machine` in one line, for the top of a benchmark's output."""
    m = m or machine()
    return f"machine: {m['cpu'] or m['machine']}, {m['cores']} cores; FFmpeg {m['ffmpeg']}, PyAV {m['av']}"


def _cpuinfo(key: str) -> str | None:
    """The value of the first ``key`` line of /proc/cpuinfo, or None (not Linux, no such line)."""
    try:
        lines = Path("/proc/cpuinfo").read_text().splitlines()
    except OSError:
        return None
    for line in lines:
        name, _, value = line.partition(":")
        if name.strip() == key:
            return value.strip()
    return None


def table(rows: list[list[Any]], header: list[str]) -> str:
    """A plain-text table with right-aligned numeric columns."""
    cells = [[_fmt(c) for c in r] for r in [header] + rows]
    widths = [max(len(r[i]) for r in cells) for i in range(len(header))]
    lines = []
    for j, r in enumerate(cells):
        lines.append("  ".join(c.rjust(widths[i]) if j and _isnum(rows[j - 1][i]) else c.ljust(widths[i])
                               for i, c in enumerate(r)))
        if j == 0:
            lines.append("  ".join("-" * w for w in widths))
    return "\n".join(lines)


def _isnum(v: Any) -> bool:
    return isinstance(v, (int, float)) and not isinstance(v, bool)


def _fmt(v: Any) -> str:
    if isinstance(v, float):
        if v == 0:
            return "0"
        if abs(v) >= 100:
            return f"{v:.1f}"
        if abs(v) >= 0.01:
            return f"{v:.4f}".rstrip("0").rstrip(".")
        return f"{v:.2e}"
    return str(v)
