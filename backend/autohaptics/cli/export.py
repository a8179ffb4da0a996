"""``autohaptics export TIMELINE.json --format csv|json|ahap|hjif|mpegv -o OUT``."""

from __future__ import annotations

import argparse
import sys

from autohaptics.errors import ParameterError

COMMAND = "export"
HELP = "convert a timeline to CSV, AHAP, MPEG-I hjif, MPEG-V SEM or JSON"


def register(sub) -> None:
    from autohaptics.formats import FORMATS

    formats = "; ".join(f"{f.name}: {f.description}" for f in FORMATS.values())
    p = sub.add_parser(
        COMMAND, help=HELP,
        description=f"Convert a timeline file to another format ({formats}). "
                    "docs/EXPORT.md documents the mapping and the limits of each format.")
    p.add_argument("timeline", help="the timeline JSON file")
    p.add_argument("-f", "--format", required=True, choices=list(FORMATS), help="output format")
    p.add_argument("-o", "--output", required=True, help="output file, or '-' for standard output")
    p.add_argument("--meta", action="store_true",
                   help="csv only: also write the metadata sidecar OUT.meta.json (source, generator, "
                        "layout), which 'autohaptics import' picks up")
    p.add_argument("--sharpness", type=float, default=None,
                   help="ahap only: HapticSharpness of every event, 0..1 (default 0.5)")
    p.add_argument("--date", default=None,
                   help="the date the export carries, YYYY-MM-DD (ahap: Created and the zip entries; "
                        "hjif: its date field; the other formats carry none). Default: "
                        "$SOURCE_DATE_EPOCH where set, else today")
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    from autohaptics.formats import export_timeline, get_format, write_csv_sidecar
    from autohaptics.outputs import atomic_output
    from autohaptics.formats.importing import csv_meta_path
    from autohaptics.timeline import Timeline

    spec = get_format(args.format)
    if args.meta and spec.name != "csv":
        raise ParameterError("--meta applies to --format csv only")
    if args.meta and args.output == "-":
        raise ParameterError("--meta needs an output file, not '-'")
    options = {k: v for k, v in (("sharpness", args.sharpness), ("date", args.date)) if v is not None}
    if "date" in options and "date" not in spec.options:
        del options["date"]  # formats without a date carry nothing to pin
    tl = Timeline.load(args.timeline)
    if args.output == "-":
        export_timeline(tl, spec.name, sys.stdout.buffer, **options)
        sys.stdout.buffer.flush()
        return 0
    path = export_timeline(tl, spec.name, args.output, **options)
    print(f"wrote {path} ({spec.name}, {tl.n_ticks} ticks, {path.stat().st_size} bytes)")
    if args.meta:
        side = csv_meta_path(path)
        with atomic_output(side, binary=False) as fh:
            write_csv_sidecar(tl, fh)
        print(f"wrote {side} (metadata sidecar)")
    return 0
