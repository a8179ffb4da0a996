"""Read a timeline CSV as written by 'autohaptics export --format csv' (or a timeline JSON), check every row and
column, and write the timeline JSON. Problems are reported by row and column.
"""

from __future__ import annotations

import argparse

from autohaptics.errors import ParameterError

COMMAND = "import"
HELP = "read a timeline CSV (or JSON), validate it and write the timeline JSON"


def register(sub) -> None:
    p = sub.add_parser(COMMAND, help=HELP, description=__doc__)
    p.add_argument("file", help="the CSV or JSON file to import")
    p.add_argument("-o", "--output", required=True, help="the timeline JSON to write")
    p.add_argument("-f", "--format", choices=["csv", "json"], default=None,
                   help="input format (default: from the suffix, else from the content)")
    p.add_argument("--meta", default=None,
                   help="CSV metadata sidecar (default: FILE's .meta.json next to it, when present)")
    p.add_argument("--no-meta", action="store_true", help="ignore any CSV metadata sidecar")
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    from autohaptics.formats.importing import csv_meta_path, import_timeline

    if args.meta and args.no_meta:
        raise ParameterError("--meta and --no-meta exclude each other")
    meta = None if args.no_meta else (args.meta or "auto")
    tl = import_timeline(args.file, fmt=args.format, meta=meta)
    path = tl.save(args.output)
    side = args.meta or csv_meta_path(args.file)
    is_json = (args.format or "").lower() == "json" or str(args.file).lower().endswith(".json")
    used = not args.no_meta and not is_json and (args.meta or csv_meta_path(args.file).is_file())
    print(f"wrote {path} ({tl.n_ticks} ticks" + (f", metadata from {side})" if used else ")"))
    return 0
