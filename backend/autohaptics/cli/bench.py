"""``autohaptics bench NAME ...``: benchmarks that print figures (see autohaptics.bench)."""

from __future__ import annotations

from autohaptics.cli.main import command_group, register_all

COMMAND = "bench"
HELP = "run a benchmark and print its figures"


def register(sub) -> None:
    bench_sub = command_group(sub, COMMAND, HELP, "Benchmarks print figures; targets are ratios measured in one run.",
                              dest="bench", metavar="NAME")
    register_all(bench_sub, "autohaptics.bench")
