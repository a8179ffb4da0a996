"""``autohaptics generate VIDEO -o OUT.json``: the whole pipeline, with a progress bar on stderr."""

from __future__ import annotations

import sys
from pathlib import Path

from autohaptics.outputs import check_output
from autohaptics.progress import ProgressBar

COMMAND = "generate"
HELP = "generate a haptic timeline from a video (or audio) file"


def register(sub) -> None:
    from autohaptics.cli.style import add_style_option
    from autohaptics.params import add_generation_options

    p = sub.add_parser(COMMAND, help=HELP,
                       description="Analyse a film's sound and picture and write a timeline JSON file.")
    p.add_argument("video", help="input media file")
    p.add_argument("-o", "--output", required=True, help="output timeline JSON file")
    add_generation_options(p)
    add_style_option(p)
    p.add_argument("--quiet", action="store_true", help="no progress bar")
    p.set_defaults(func=run, exit_at_once=True)  # nothing left open: cli.main.end_process


def run(args) -> int:
    from autohaptics.runner.heap import release_between_passes
    from autohaptics.pipeline import generate
    from autohaptics.cli.style import style_from_args
    from autohaptics.params import params_from_args

    params, preset = params_from_args(args)
    style = style_from_args(args)  # a bad style file fails before the analysis
    out = check_output(args.output)  # before the analysis, worded as every command's output
    bar = ProgressBar(Path(args.video).name) if not args.quiet else None
    try:
        tl = generate(args.video, params, preset=preset, progress=bar, between_passes=release_between_passes,
                      style=style)
    finally:
        if bar:
            bar.close()
    tl.save(out)
    active = int((tl.vibration.max(axis=1) > 0).sum())
    print(f"{out}: {tl.n_ticks} ticks ({tl.n_ticks * tl.tick_s:.1f} s), vibration on {active} ticks, "
          f"mode {tl.generator['mode']}, preset {preset}, {tl.stats.get('total_seconds', 0):.2f} s",
          file=sys.stderr)
    return 0
