"""``autohaptics compare REF.json TEST.json [--json]``: error metrics between two timelines of one source."""

from __future__ import annotations

import json
import sys

from autohaptics.errors import ParameterError

COMMAND = "compare"
HELP = "error metrics between two timelines of the same source"


def register(sub) -> None:
    p = sub.add_parser(
        COMMAND, help=HELP,
        description="Compare a timeline (TEST) against a reference (REF) of the same source: vibration MAE and "
                    "onset precision/recall/F1 (onsets matched within +-1 tick per actuator), temperature MAE (C), "
                    "fan-cell IoU over the ticks where either side blows (exact, and with a tolerance of one cell: an "
                    "on-cell counts as matched when the other side has an on-cell among its 8 neighbours), and the MAE of every feature curve both "
                    "hold. Timelines of different lengths are compared on their common ticks.")
    p.add_argument("ref", help="reference timeline JSON")
    p.add_argument("test", help="timeline JSON to compare against the reference")
    p.add_argument("--json", action="store_true", help="print the full report as JSON")
    p.add_argument("--tolerance", type=int, default=1, metavar="TICKS",
                   help="onset matching window, +-ticks (default 1)")
    p.add_argument("--fan-tolerance", type=int, default=1, metavar="CELLS",
                   help="fan cells within this many cells (8-neighbourhood) count as matched in the tolerant "
                        "fan IoU, 0..17 (default 1)")
    p.add_argument("--any-source", action="store_true",
                   help="compare even when the two timelines come from different files (sha256 differs)")
    p.set_defaults(func=run)


def run(args) -> int:
    from autohaptics.metrics import compare_timelines, format_report
    from autohaptics.timeline import Timeline

    if args.tolerance < 0:
        raise ParameterError(f"--tolerance must be >= 0 ticks, got {args.tolerance}")
    ref, test = Timeline.load(args.ref), Timeline.load(args.test)
    report = compare_timelines(ref, test, tolerance=args.tolerance, fan_tolerance=args.fan_tolerance)
    if report["same_source"] is False and not args.any_source:
        raise ParameterError(f"{args.test}: comes from a different source than {args.ref} "
                             f"(sha256 {test.source.get('sha256', '')[:12]}.. vs {ref.source.get('sha256', '')[:12]}..); "
                             "pass --any-source to compare anyway")
    if args.json:
        json.dump(report, sys.stdout, indent=2)
        sys.stdout.write("\n")
    else:
        print(format_report(report))
    return 0
