"""The ``autohaptics`` command line. Each sub-command lives in its own module of this package
and exposes ``register(subparsers)``; this module finds them, parses and turns every expected
failure into one clear line on stderr and a non-zero exit (never a traceback)."""

from __future__ import annotations

import argparse
import importlib
import os
import pkgutil
import sys

from autohaptics import __version__
from autohaptics.errors import AutohapticsError, CancelledError
from autohaptics.runner.heap import bound_heap

EXIT_ERROR = 2
EXIT_CANCELLED = 130


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="autohaptics",
        description="Turn a movie into 4D haptic effects (vibration, temperature, airflow).")
    parser.add_argument("--version", action="version", version=f"autohaptics {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    sub.required = True
    register_all(sub, "autohaptics.cli", skip=("main",))
    return parser


def register_all(sub, package: str, *, skip: tuple[str, ...] = ()) -> None:
    """Call ``register(sub)`` of every module of ``package`` that has one (by name, ``skip`` and
    private modules left out): each sub-command lives in its own module."""
    pkg = importlib.import_module(package)
    for mod in sorted(pkgutil.iter_modules(pkg.__path__), key=lambda m: m.name):
        if mod.name in skip or mod.name.startswith("_"):
            continue
        register = getattr(importlib.import_module(f"{package}.{mod.name}"), "register", None)
        if register is not None:
            register(sub)


def main(argv: list[str] | None = None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    debug = bool(os.environ.get("AUTOHAPTICS_DEBUG"))
    bound_heap()  # freed temporaries go back to the OS (docs/BENCHMARKS.md, '2-hour film')
    try:
        rc = args.func(args)
        return int(rc or 0)
    except CancelledError as exc:
        print(f"autohaptics: cancelled: {exc}", file=sys.stderr)
        return EXIT_CANCELLED
    except KeyboardInterrupt:
        print("autohaptics: interrupted", file=sys.stderr)
        return EXIT_CANCELLED
    except AutohapticsError as exc:
        if debug:
            raise
        print(f"autohaptics: error: {exc}", file=sys.stderr)
        return EXIT_ERROR
    except BrokenPipeError:
        return EXIT_ERROR
    except Exception as exc:  # an unexpected failure still gets one line, not a traceback
        if debug:
            raise
        print(f"autohaptics: internal error: {type(exc).__name__}: {(str(exc).strip().splitlines() or [''])[0]} "
              "(set AUTOHAPTICS_DEBUG=1 for the traceback)", file=sys.stderr)
        return EXIT_ERROR


if __name__ == "__main__":
    sys.exit(main())
