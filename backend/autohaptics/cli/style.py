"""``autohaptics style learn|show``: learn a designer's style from films they edited, print one."""

from __future__ import annotations

import sys

from autohaptics.cli.main import command_group
from autohaptics.errors import ParameterError

COMMAND = "style"
HELP = "learn a designer's style from edited timelines, or show a style file"


def register(sub) -> None:
    from autohaptics.params import add_generation_options

    group = command_group(sub, COMMAND, HELP, "A style is a designer's taste as a few numbers "
                          "(docs/STYLE_FORMAT.md); generate --style and batch --style apply it.",
                          dest="style_action", metavar="ACTION")
    learn = group.add_parser("learn", help="fit a style to films and their edited timelines",
                             description="Fit a style to pairs FILM EDITED: FILM a media file (analysed "
                                         "with the generation options) or its analysis cache (.npz), "
                                         "EDITED the designer's edited timeline of it.")
    learn.add_argument("pairs", nargs="+", metavar="FILM EDITED")
    learn.add_argument("-o", "--output", required=True, help="style file to write (JSON)")
    learn.add_argument("--name", default="", help="the style's name (default: the output's stem)")
    add_generation_options(learn)
    learn.set_defaults(func=run_learn)
    show = group.add_parser("show", help="print a style file's numbers")
    show.add_argument("style", help="style file (JSON)")
    show.set_defaults(func=run_show)


def add_style_option(p) -> None:
    """``--style STYLE.json`` for the commands that generate."""
    p.add_argument("--style", default=None, metavar="STYLE.json",
                   help="derive every timeline in this learned style (autohaptics style learn)")


def style_from_args(args):
    """The :class:`~autohaptics.style.Style` named by ``--style``, or None."""
    from autohaptics.style import load

    return None if args.style is None else load(args.style)


def run_learn(args) -> int:
    from pathlib import Path

    from autohaptics.outputs import check_output
    from autohaptics.params import params_from_args
    from autohaptics.style import learn, save
    from autohaptics.timeline import Timeline

    if len(args.pairs) % 2:
        raise ParameterError(f"style learn takes pairs FILM EDITED; got {len(args.pairs)} paths (an odd count)")
    params, _ = params_from_args(args)
    out = check_output(args.output)
    pairs = [(_analysis(film, params), Timeline.load(edited))
             for film, edited in zip(args.pairs[0::2], args.pairs[1::2])]
    style = learn(pairs, params, name=args.name or Path(args.output).stem)
    save(style, out)
    print(f"{out}: learned from {style.learned['films']} film(s), {style.learned['ticks']} ticks sampled",
          file=sys.stderr)
    return 0


def run_show(args) -> int:
    from autohaptics.layout import ACTUATOR_IDS
    from autohaptics.style import load

    style = load(args.style)
    rows = [f"style {style.name or '(unnamed)'}{' (identity: changes nothing)' if style.is_identity else ''}",
            f"threshold scale {style.threshold_scale:g}",
            f"temperature: distance from neutral x {style.temperature_scale:g}, offset {style.temperature_offset_c:+g} C",
            "tone curves, level at input " + " ".join(f"{k:g}" for k in style.knots)]
    rows += [f"  {name:<5}" + " ".join(f"{v:.3f}" for v in curve)
             for name, curve in zip((*ACTUATOR_IDS, "fans"), (*style.vibration, style.fans))]
    rows.append("floors (levels below them off) " + " ".join(
        f"{name} {v:g}" for name, v in zip((*ACTUATOR_IDS, "fans"), (*style.vibration_floor, style.fans_floor))))
    rows += [f"override {k} = {v!r}" for k, v in sorted(style.overrides.items())]
    rows += [f"learned {k}: {v}" for k, v in sorted(style.learned.items())]
    print("\n".join(rows))
    return 0


def _analysis(film: str, params):
    """The analysis of ``film``: its cache file (.npz) read, else the media file analysed."""
    from pathlib import Path

    from autohaptics import pipeline

    if Path(film).suffix.lower() == ".npz":
        try:
            analysis = pipeline.Analysis.load(film)
        except (OSError, ValueError, KeyError) as exc:
            raise ParameterError(f"{film}: not an analysis cache ({exc})") from None
        if not pipeline.reusable(analysis, params):
            raise ParameterError(f"{film}: analysed with other analysis-time parameters than the options give")
        return analysis
    return pipeline.analyse(film, params)
