"""``autohaptics bench vibration CLIP...``: the share of each clip's ticks that vibrate, with the
default rule ("events"), the thesis rule (``params.THESIS_RULES``) and a requested density.

Each clip's audio is analysed once (the audio pass only); the rules are derived from that one
analysis, as the editor re-derives. Target (docs/GUIDE.md "Vibration"): the default vibrates on
10 % .. 60 % of the ticks of every clip longer than 10 s; a density of d gives about d.
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

from autohaptics.bench.common import table
from autohaptics.errors import ParameterError

TARGET_SHARE = (0.10, 0.60)
TARGET_MIN_S = 10.0


def register(sub) -> None:
    p = sub.add_parser("vibration", help="share of ticks that vibrate per clip: default rule, thesis rule, density",
                       description="Analyse each clip's sound once and print the share of its ticks that vibrate "
                                   "with the default 'events' rule, the thesis rule and a requested density.")
    p.add_argument("clips", nargs="+", metavar="CLIP", help="media files")
    p.add_argument("--density", type=float, default=0.25, help="the density to check, 0..1 (default 0.25)")
    p.add_argument("--preset", default="balanced", help="base preset (default balanced)")
    p.add_argument("--json", metavar="OUT.json", default=None, help="also write every figure as JSON")
    p.set_defaults(func=run)


def clip_shares(path: Path, *, preset: str, density: float) -> dict:
    """{"clip", "duration_s", "ticks", "default", "thesis", "density"} for one clip (shares 0..1)."""
    from autohaptics.params import THESIS_RULES, resolve_params
    from autohaptics.pipeline.analyse import analyse
    from autohaptics.pipeline.derive import derive

    base = {"mode": "audio", "tracks": ["vibration"]}
    params, _ = resolve_params(preset, base)
    analysis = analyse(path, params)
    out = {"clip": path.name, "duration_s": float(analysis.info.get("duration_s") or 0.0), "ticks": analysis.n_ticks}
    for name, overrides in (("default", {}), ("thesis", dict(THESIS_RULES)), ("density", {"intensity.density": density})):
        tl = derive(analysis, resolve_params(preset, {**base, **overrides})[0], preset=preset)
        out[name] = tl.stats["vibration"]["share"]
        if name == "density":
            out["threshold_scale"] = tl.stats["vibration"]["threshold_scale"]
    return out


def run(args: argparse.Namespace) -> int:
    if not 0.0 <= args.density <= 1.0:
        raise ParameterError(f"--density must lie in 0..1, got {args.density}")
    rows, results = [], []
    for clip in args.clips:
        path = Path(clip)
        if not path.is_file():
            raise ParameterError(f"{clip}: no such file")
        r = clip_shares(path, preset=args.preset, density=args.density)
        results.append(r)
        checked = r["duration_s"] > TARGET_MIN_S
        ok = TARGET_SHARE[0] <= r["default"] <= TARGET_SHARE[1]
        rows.append([r["clip"], r["duration_s"], r["ticks"], r["default"], r["thesis"], r["density"],
                     ("met" if ok else "NOT met") if checked else "-"])
    print(table(rows, ["clip", "seconds", "ticks", "default", "thesis", f"density {args.density:g}",
                       f"default in {TARGET_SHARE[0]:g}..{TARGET_SHARE[1]:g}"]))
    print(f"(share of ticks that vibrate; the target applies to clips longer than {TARGET_MIN_S:g} s)")
    if args.json:
        Path(args.json).write_text(json.dumps({"density": args.density, "clips": results}, indent=1), encoding="utf-8")
    return 0
