"""``autohaptics bench style``: how well a style learned from one film carries a designer's taste to
other films.

Each simulated designer (:data:`autohaptics.testing.designers.DESIGNERS`: a documented taste plus
seeded one-off edits on each film) edits every film; a style is learned on one film's edits and
applied to each other film, and both the plain derive and the styled one are compared with the
designer's taste on that film (their edit without the one-offs, which no style can foresee); per
learn film, and jointly (all films but one learn one style, applied to that one).
Films: the shared clips and synthetic scenes, analysed once into ``--work``; ``--hours H`` adds a
written film of H hours (the learn time on it is the figure for a feature film). Figures are
printed, never asserted.
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

import numpy as np

from autohaptics.bench.clips import shared_media
from autohaptics.bench.common import table
from autohaptics.errors import ParameterError

CLIPS = ("sintel_trailer_480x204_h264_aac.mp4", "bbb_opening_30s_1280x720_vp8_vorbis.webm")
SCENES = ("material_scene", "sample_scene", "left_boom_right_hum_scene")
TRACK_ERRORS = ("vibration_mae", "onset_f1", "temperature_mae_c", "fan_mae")
# the acceptance's distances: MAE as it is, 1 - F1 or IoU (closed = share of the plain derive's removed)
DISTANCES = ("vibration_mae", "onset_f1", "temperature_mae_c", "fan_mae", "fan_iou_tolerant")
OFF = 1e-6  # a mean distance above this: the default is off on that metric


def register(sub) -> None:
    p = sub.add_parser("style", help="learned styles: simulated designers, learn on one film, apply to others",
                       description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--work", default="/tmp/autohaptics-bench-style",
                   help="folder for the written scenes and the analyses, reused (default %(default)s)")
    p.add_argument("--hours", type=float, default=0.0,
                   help="also a written film of this many hours (bench commit's film; 0 = none, the default)")
    p.add_argument("--seed", type=int, default=0, help="seed of the designers' one-off edits")
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    from autohaptics.style import learn
    from autohaptics.testing.designers import DESIGNERS, edit

    work = Path(args.work)
    work.mkdir(parents=True, exist_ok=True)
    films = _analyses(work, args.hours)
    names = list(films)
    print(f"films: {', '.join(f'{n} ({films[n].n_ticks} ticks)' for n in names)}")
    identity = [learn([(a, _plain(a))]).is_identity for a in films.values()]
    print(f"unedited films learn the identity: {sum(identity)} of {len(identity)}")
    rows, closed_rows, per_film_rows, joint_rows, learn_s = [], [], [], [], {}
    for designer in DESIGNERS:
        edited = {n: edit(designer, films[n], seed=args.seed + i) for i, n in enumerate(names)}
        taste = {n: edit(designer, films[n], one_offs=0) for n in names}
        bare = {n: _errors(_plain(films[n]), taste[n]) for n in names}
        plain, styled, scales, own_plain, own_styled, per_film = [], [], [], [], [], []
        for source in names:
            t0 = time.perf_counter()
            style = learn([(films[source], edited[source])], name=designer.name)
            learn_s.setdefault(source, []).append(time.perf_counter() - t0)
            scales.append(style.threshold_scale)
            own_plain.append(bare[source])
            own_styled.append(_errors(_styled(films[source], style), taste[source]))
            others = [n for n in names if n != source]
            styled_here = [_errors(_styled(films[t], style), taste[t]) for t in others]
            plain += [bare[t] for t in others]
            styled += styled_here
            per_film.append(f"{style.threshold_scale:.2f}: {_worst(_closed([bare[t] for t in others], styled_here))}")
        joint = [_errors(_styled(films[t], learn([(films[n], edited[n]) for n in names if n != t])), taste[t])
                 for t in names]
        rows.append(_row(designer, plain, styled, scales))
        other, own, together = _closed(plain, styled), _closed(own_plain, own_styled), _closed(list(bare.values()), joint)
        closed_rows.append([designer.name, *(other[k] for k in DISTANCES), _worst(other),
                            *(own[k] for k in DISTANCES), _worst(own)])
        per_film_rows.append([designer.name, *per_film])
        joint_rows.append([designer.name, *(together[k] for k in DISTANCES), _worst(together)])
    print(table(rows, ["designer", "taste", "scales", "vib MAE plain", "styled", "onset F1 plain", "styled",
                       "temp MAE C plain", "styled", "fan MAE plain", "styled", "edit reproduced"]))
    print("share of the default's distance closed per metric (- where the default is not off), "
          "other films | the learn film:")
    print(table(closed_rows, ["designer", *DISTANCES, "worst", *DISTANCES, "worst"]))
    print("per learn film: the scale learned there and the worst share closed on the other films:")
    print(table(per_film_rows, ["designer", *names]))
    print("joint: the other films learn one style together, applied to each film in turn (share closed):")
    print(table(joint_rows, ["designer", *DISTANCES, "worst"]))
    print("learn time per film (median over designers, s): "
          + ", ".join(f"{n} {np.median(v):.3f}" for n, v in learn_s.items()))
    return 0


def _analyses(work: Path, hours: float) -> dict:
    """{name: Analysis} of the shared clips, the synthetic scenes and, with ``hours``, the long film."""
    from autohaptics import pipeline
    from autohaptics.testing import scenes, write_scene

    sources: dict[str, Path] = {}
    for clip in CLIPS:
        path = shared_media() / clip
        if not path.is_file():
            raise ParameterError(f"{path}: shared clip not found")
        sources[clip.split("_")[0] + "_" + clip.split("_")[1]] = path
    for name in SCENES:
        path = work / f"{name}.mp4"
        if not path.is_file():
            write_scene(path, getattr(scenes, name)(), width=160, height=90)
        sources[name] = path
    if hours > 0:
        from autohaptics.bench.commit import write_film

        path = work / f"film_{hours:g}h.mp4"
        if not path.is_file():
            write_film(path, hours * 3600.0)
        sources[f"film_{hours:g}h"] = path
    out = {}
    for name, path in sources.items():
        cache = work / f"{name}.analysis.npz"
        if cache.is_file():
            out[name] = pipeline.Analysis.load(cache)
        else:
            out[name] = pipeline.analyse(path)
            out[name].save(cache)
    return out


def _plain(analysis):
    from autohaptics.pipeline import derive

    return derive(analysis)


def _styled(analysis, style):
    from autohaptics.pipeline import derive

    return derive(analysis, style=style)


def _errors(test, ref) -> dict:
    from autohaptics.metrics import compare_tracks

    r = compare_tracks(ref.vibration, test.vibration, ref.temperature_c, test.temperature_c, ref.fans, test.fans)
    return {"vibration_mae": r["vibration"]["mae"], "onset_f1": r["vibration"]["onsets"]["f1"],
            "temperature_mae_c": r["temperature"]["mae_c"], "fan_mae": r["fans"]["mae"],
            "fan_iou_tolerant": r["fans"]["iou_tolerant"]}


def _closed(plain: list[dict], styled: list[dict]) -> dict:
    """Per metric of :data:`DISTANCES`: 1 - mean styled distance / mean plain distance over the
    pairs (a distance: MAE, or 1 - F1 / IoU, NaN as 0), or "-" where the default is not off."""
    out = {}
    for k in DISTANCES:
        def dist(e: dict) -> float:
            v = float(e[k])
            return 0.0 if not np.isfinite(v) else (1.0 - v if k in ("onset_f1", "fan_iou_tolerant") else v)
        before, after = np.mean([dist(e) for e in plain]), np.mean([dist(e) for e in styled])
        out[k] = round(1.0 - after / before, 3) if before > OFF else "-"
    return out


def _worst(closed: dict) -> float | str:
    values = [v for v in closed.values() if v != "-"]
    return min(values) if values else "-"


def _row(designer, plain: list[dict], styled: list[dict], scales: list[float]) -> list:
    """One table row: the mean of each figure over (learn film, apply film) pairs, and the share of
    the taste's error the style removes (vibration, temperature / 5 C and fans MAE summed)."""
    mean = {k: (float(np.mean([p[k] for p in plain])), float(np.mean([s[k] for s in styled]))) for k in TRACK_ERRORS}

    def total(i: int) -> float:
        return mean["vibration_mae"][i] + mean["temperature_mae_c"][i] / 5.0 + mean["fan_mae"][i]

    reproduced = 1.0 - total(1) / total(0) if total(0) > 0 else float("nan")
    cells = [designer.name, designer.taste, f"{min(scales):.2f}-{max(scales):.2f}"]
    for k in TRACK_ERRORS:
        cells += [round(mean[k][0], 4), round(mean[k][1], 4)]
    return cells + [round(reproduced, 3)]
