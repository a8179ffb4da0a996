"""Helpers shared by the benchmarks: wall time, CPU time and peak memory of a callable."""

from __future__ import annotations

import resource
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass
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
