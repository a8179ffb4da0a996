"""``autohaptics bench NAME ...``: benchmarks that print figures (see autohaptics.bench)."""

from __future__ import annotations

from autohaptics.cli.main import register_all

COMMAND = "bench"
HELP = "run a benchmark and print its figures"


def register(sub) -> None:
    p = sub.add_parser(COMMAND, help=HELP,
                       description="Benchmarks print figures; targets are ratios measured in one run.")
    bench_sub = p.add_subparsers(dest="bench", metavar="NAME")
    bench_sub.required = True
    register_all(bench_sub, "autohaptics.bench")
