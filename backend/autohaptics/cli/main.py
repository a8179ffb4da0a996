"""The ``autohaptics`` command line. Each sub-command lives in its own module of this package
and exposes ``register(subparsers)``; this module finds them, parses and turns every expected
failure into one clear line on stderr and a non-zero exit (never a traceback)."""

from __future__ import annotations

import argparse
import atexit
import importlib
import os
import pkgutil
import sys
import threading

from autohaptics import __version__
from autohaptics.errors import AutohapticsError, CancelledError

EXIT_ERROR = 2
EXIT_CANCELLED = 130


def build_parser(command: str | None = None) -> argparse.ArgumentParser:
    """The parser; only ``command``'s module registers its options (see :func:`add_commands`)."""
    parser = argparse.ArgumentParser(
        prog="autohaptics",
        description="Turn a movie into 4D haptic effects (vibration, temperature, airflow).")
    parser.add_argument("--version", action="version", version=f"autohaptics {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    sub.required = True
    add_commands(sub, "autohaptics.cli", chosen=command, skip=("main",))
    return parser


def add_commands(sub, package: str, *, chosen: str | None, skip: tuple[str, ...] = ()) -> None:
    """Every module of ``package`` with a ``COMMAND`` name: the ``chosen`` one calls its
    ``register(sub)``, the others are listed by ``COMMAND`` and ``HELP`` only. Command modules
    import nothing heavy at module level, so ``--help`` and a mistyped command start in a few
    tens of milliseconds; the pipeline is imported by the command that runs."""
    for module in _modules(package, skip):
        name = getattr(module, "COMMAND", None)
        if name is None:
            continue
        if name == chosen:
            module.register(sub)
        else:
            sub.add_parser(name, help=module.HELP, add_help=False)


def command_group(sub, name: str, help: str, description: str, *, dest: str, metavar: str):
    """A sub-command made of actions of its own (``chair ports``, ``bench audio``): its parser's
    sub-parsers, one of which must be given."""
    group = sub.add_parser(name, help=help, description=description).add_subparsers(dest=dest, metavar=metavar)
    group.required = True
    return group


def register_all(sub, package: str, *, skip: tuple[str, ...] = ()) -> None:
    """Call ``register(sub)`` of every module of ``package`` that has one (by name, ``skip`` and
    private modules left out): each sub-command lives in its own module."""
    for module in _modules(package, skip):
        register = getattr(module, "register", None)
        if register is not None:
            register(sub)


def _modules(package: str, skip: tuple[str, ...]) -> list:
    pkg = importlib.import_module(package)
    names = sorted(m.name for m in pkgutil.iter_modules(pkg.__path__))
    return [importlib.import_module(f"{package}.{name}") for name in names
            if name not in skip and not name.startswith("_")]


def command_word(argv: list[str]) -> str | None:
    """The sub-command named in ``argv`` (its first word that is not an option), if any."""
    return next((a for a in argv if not a.startswith("-")), None)


def parse(argv: list[str] | None = None) -> argparse.Namespace:
    """``argv`` (default: the process's arguments) parsed; argparse exits on a usage error."""
    argv = sys.argv[1:] if argv is None else list(argv)
    return build_parser(command_word(argv)).parse_args(argv)


def main(argv: list[str] | None = None) -> int:
    """Run the command ``argv`` names (default: the process's arguments); its exit status."""
    return run_command(parse(argv))


def run_command(args: argparse.Namespace) -> int:
    """Call the parsed command; every expected failure is one line on stderr and a status."""
    debug = bool(os.environ.get("AUTOHAPTICS_DEBUG"))
    from autohaptics.runner.heap import bound_heap

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


def program() -> None:
    """The ``autohaptics`` program (console script, ``python -m autohaptics.cli.main``): :func:`main`,
    then the process ends. A command that sets the default ``exit_at_once`` (it leaves no file open)
    ends it with :func:`end_process` when no other thread runs."""
    args = parse()
    rc = run_command(args)
    if getattr(args, "exit_at_once", False) and threading.active_count() == 1:
        end_process(rc)
    sys.exit(rc)


def end_process(rc: int) -> None:
    """End this process now with status ``rc``: the exit handlers run and the standard streams are
    flushed, but the interpreter's teardown (freeing each object of numpy, PyAV and OpenCV, 30-40
    ms of CPU) is skipped. Only where no file is left open and no other thread runs."""
    atexit._run_exitfuncs()
    for stream in (sys.stdout, sys.stderr):
        try:
            stream.flush()
        except (OSError, ValueError):
            rc = rc or EXIT_ERROR
    os._exit(rc)


if __name__ == "__main__":
    program()
