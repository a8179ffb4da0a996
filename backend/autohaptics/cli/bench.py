"""``autohaptics bench NAME ...``: benchmarks that print figures (see autohaptics.bench)."""

from __future__ import annotations

import importlib
import pkgutil


def register(sub) -> None:
    p = sub.add_parser("bench", help="run a benchmark and print its figures",
                       description="Benchmarks print figures; targets are ratios measured in one run.")
    bench_sub = p.add_subparsers(dest="bench", metavar="NAME")
    bench_sub.required = True
    import autohaptics.bench as pkg

    for mod in sorted(pkgutil.iter_modules(pkg.__path__), key=lambda m: m.name):
        if mod.name in ("common",) or mod.name.startswith("_"):
            continue
        module = importlib.import_module(f"autohaptics.bench.{mod.name}")
        if hasattr(module, "register"):
            module.register(bench_sub)
