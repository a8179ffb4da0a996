"""``autohaptics generate VIDEO -o OUT.json``: the whole pipeline, with a progress bar on stderr."""

from __future__ import annotations

import sys
from pathlib import Path

from autohaptics.errors import ParameterError
from autohaptics.records import parse_assignments
from autohaptics.progress import ProgressBar


def add_generation_options(p) -> None:
    """Options shared by every command that generates (generate, batch, bench)."""
    from autohaptics.fusion import MODES
    from autohaptics.params import PRESETS

    p.add_argument("--mode", choices=MODES, default=None,
                   help="vibration rendering (the thesis's study conditions); default from the params")
    p.add_argument("--preset", choices=sorted(PRESETS), default="balanced",
                   help="quality preset (default: balanced)")
    p.add_argument("--threshold", action="append", metavar="NAME=VALUE", default=[],
                   help="feature threshold after normalisation, 0..1: sharpness, booming, low_energy, "
                        "loudness (repeatable)")
    p.add_argument("--set", action="append", metavar="PARAM=VALUE", default=[], dest="overrides",
                   help="override any parameter by its dotted name, e.g. audio.pa_per_unit=3.5566 "
                        "or intensity.normaliser=percentile (repeatable)")
    p.add_argument("--pa-per-unit", type=float, default=None,
                   help="calibration, pascal per digital full-scale unit (film default 3.5566: "
                        "0 dBFS rms = 105 dB SPL)")
    p.add_argument("--allow-truncated", action="store_true",
                   help="accept a damaged file that decodes shorter than declared")


def params_from_args(args):
    """(GenerateParams, preset name) from parsed generation options."""
    from autohaptics.params import resolve_params

    overrides = parse_assignments(args.overrides)
    if args.mode:
        overrides["mode"] = args.mode
    if args.pa_per_unit is not None:
        overrides["audio.pa_per_unit"] = args.pa_per_unit
    if getattr(args, "allow_truncated", False):
        overrides["allow_truncated"] = True
    thresholds = parse_assignments(args.threshold)
    return resolve_params(args.preset, overrides, thresholds)


def register(sub) -> None:
    p = sub.add_parser("generate", help="generate a haptic timeline from a video (or audio) file",
                       description="Analyse a film's sound and picture and write a timeline JSON file.")
    p.add_argument("video", help="input media file")
    p.add_argument("-o", "--output", required=True, help="output timeline JSON file")
    add_generation_options(p)
    p.add_argument("--quiet", action="store_true", help="no progress bar")
    p.set_defaults(func=run)


def run(args) -> int:
    from autohaptics.runner.heap import release_between_passes
    from autohaptics.pipeline import generate

    params, preset = params_from_args(args)
    out = Path(args.output)
    if out.exists() and out.is_dir():
        raise ParameterError(f"{out}: is a directory; give a file name for the timeline")
    if not out.parent.exists():
        raise ParameterError(f"{out.parent}: output folder does not exist")
    bar = ProgressBar(Path(args.video).name) if not args.quiet else None
    try:
        tl = generate(args.video, params, preset=preset, progress=bar, between_passes=release_between_passes)
    finally:
        if bar:
            bar.close()
    tl.save(out)
    active = int((tl.vibration.max(axis=1) > 0).sum())
    print(f"{out}: {tl.n_ticks} ticks ({tl.n_ticks * tl.tick_s:.1f} s), vibration on {active} ticks, "
          f"mode {tl.generator['mode']}, preset {preset}, {tl.stats.get('total_seconds', 0):.2f} s",
          file=sys.stderr)
    return 0
