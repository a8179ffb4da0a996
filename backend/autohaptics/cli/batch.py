"""Generate OUTDIR/<name>.timeline.json for every film. Films already done with the same source (SHA-256) and the
same parameters are skipped; a failing film does not stop the others. Exit status 0: all done, 1: some failed,
2: usage error (each failed film is listed on stderr with a one-line reason).
"""

from __future__ import annotations

import sys

from autohaptics.errors import ParameterError
from autohaptics.progress import ProgressBar

COMMAND = "batch"
HELP = "generate timelines for many films (folders, files or glob patterns)"


def register(sub) -> None:
    from autohaptics.cli.style import add_style_option
    from autohaptics.params import add_generation_options

    p = sub.add_parser(COMMAND, help=HELP, description=__doc__)
    p.add_argument("inputs", nargs="+", metavar="FOLDER_OR_GLOB",
                   help="a folder (its media files), a file, or a quoted glob pattern ('films/**/*.mkv')")
    p.add_argument("-o", "--output-dir", required=True, metavar="OUTDIR",
                   help="folder for the timelines and batch-manifest.json (created when missing)")
    add_generation_options(p)
    add_style_option(p)
    p.add_argument("--jobs", type=int, default=None, metavar="N",
                   help="films analysed at once in local worker processes (default 1)")
    p.add_argument("--scheduler", default=None, metavar="tcp://HOST:PORT",
                   help="run one task per film on this Dask distributed cluster instead of locally "
                        "(its workers must see the input files at the same paths)")
    p.add_argument("--quiet", action="store_true", help="no progress bar")
    p.set_defaults(func=run)


def run(args) -> int:
    from autohaptics.batch import run_batch
    from autohaptics.cli.style import style_from_args
    from autohaptics.params import params_from_args

    if args.scheduler is not None and args.jobs is not None:
        raise ParameterError("--jobs is for local runs; with --scheduler the cluster's workers set the parallelism")
    params, preset = params_from_args(args)
    style = style_from_args(args)
    bar = None if args.quiet else ProgressBar("batch", force=True)
    try:
        report = run_batch(args.inputs, args.output_dir, params, preset,
                           jobs=1 if args.jobs is None else args.jobs, scheduler=args.scheduler, progress=bar,
                           style=style)
    finally:
        if bar:
            bar.close()
    for r in report.failed:
        print(f"failed: {r.source}: {r.reason}", file=sys.stderr)
    print(f"batch: {report.summary()}", file=sys.stderr)
    return report.exit_status
