"""Benchmarks that print figures (``autohaptics bench NAME``). Each module of this package
exposes ``register(subparsers)`` and is found automatically by :mod:`autohaptics.cli.bench`.

Speed and memory targets are checked here, never by timed assertions in tests: machines are
shared and noisy, so every figure that matters is a ratio measured inside one run.
"""
