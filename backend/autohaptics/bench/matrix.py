"""``autohaptics bench matrix``: the material matrix, the forms a film reaches us in.

Each source (the shared film clips, or any file given) is written again as each row of
:data:`~autohaptics.bench.variants.VARIANTS` says: re-encoded as it is (H.264); letterboxed and pillarboxed; at half
and double size, and at a size that changes every six seconds (an adaptive stream's recording); at 23.976, 25,
29.97, 50, 59.94 and 120 fps and at a variable frame rate; in 10 bits (H.264, and a ProRes master with its sound in
one stream or, as editing suites write it, each channel in a mono track); as an HDR10 grade; as HEVC and AV1; as
DVDs (NTSC telecined, coded progressive and interlaced; PAL anamorphic); as 3D films, their two views packed side by
side or top and bottom; as VP9 and H.264 screeners; with its sound as mono, stereo (Opus, and AAC from FFmpeg's
downmix), 5.1 and 7.1, as AC-3 carrying Dolby's dynamic range words, behind a commentary and a compatibility stereo
track, and changing its sample rate for 10 s (a channel's advertisement); cut to start mid-score, as a broadcast
recording begun mid-GOP on a clock that wraps, and as the first of two programmes in the recording of a whole
multiplex. Every row's timeline is compared with the source's own (the clean variant; for a cut, the clean analysis
from the cut on derived as a film of its own, so what differs is the start of the file, not the context a whole film
gives its film-relative levels): onset F1, fan-tick F1, tolerant fan IoU and temperature MAE against
:data:`TARGETS`, and a cut's largest vibration in its first 0.5 s where the film itself does not vibrate. With
``--speed`` each file's ``generate`` and its bare decode (:func:`~autohaptics.bench.decode.bare_decode`) also run as
whole processes, and the row gives their ratio. The digital-silence pair (booms and blips over exact silence, and
over a -100 dBFS floor) is a row of its own: the silence variant against the floor variant, and the ratio of their
generate times. With ``--over WORDS`` each row is written from the file of the first row whose name holds those
words instead of the source (a grainy film as each screener, letterboxed, at each rate: material that meets two
rows at once), and still compared with the clean source.

Variant files are written once into ``--out`` and reused; nothing large is committed.
"""

from __future__ import annotations

import json
import sys
import time
from pathlib import Path
from typing import Any

import numpy as np

from autohaptics.bench.common import machine, machine_line, table
from autohaptics.bench.variants import VARIANTS, Variant, not_applicable, variant_file
from autohaptics.errors import ParameterError
from autohaptics.metrics import compare_tracks, headline
from autohaptics.timebase import TICK_S

# the issue-31 acceptance of every row against its clean variant: (comparison, bound)
TARGETS = {"onset_f1": (">=", 0.9), "fan_ticks_f1": (">=", 0.9), "fan_iou_tolerant": (">=", 0.8),
           "temperature_mae_c": ("<=", 0.5)}
JOLT_S = 0.5  # a cut's opening judged for a jolt
JOLT_MAX = 0.2  # the largest vibration allowed there, 0..1
SHARED_SOURCES = ("bbb_opening_30s_1280x720_vp8_vorbis.webm", "sintel_trailer_640x272_vp8_vorbis.webm")
SILENCE_S = 180.0  # the digital-silence pair's length, s (the 3-minute clip)


def cut_analysis(analysis, start_s: float, n_ticks: int):
    """The feature cache of ``analysis`` (:class:`~autohaptics.pipeline.cache.Analysis`) from
    ``start_s`` for ``n_ticks`` ticks, as the cache of a film of its own: what a cut made without any
    loss would give, so a cut file's timeline compares with ``derive`` of it."""
    from autohaptics.pipeline.cache import Analysis
    from autohaptics.pipeline.ticks import VideoAnalysis
    from autohaptics.timebase import FRAMES_PER_TICK

    k0 = int(round(start_s / TICK_S))
    n = min(int(n_ticks), analysis.n_ticks - k0)
    if n <= 0:
        raise ParameterError(f"a cut at {start_s} s starts after the film's end")
    audio = None if analysis.audio is None else {
        k: v[k0 * FRAMES_PER_TICK:(k0 + n) * FRAMES_PER_TICK].copy() for k, v in analysis.audio.items()}
    video = None if analysis.video is None else VideoAnalysis.from_arrays(
        {k: v[k0:k0 + n].copy() for k, v in analysis.video.arrays().items()}, analysis.video.stats)
    info = {**analysis.info, "duration_s": n * TICK_S}
    return Analysis(info=info, sha256=analysis.sha256, n_ticks=n, params=analysis.params, audio=audio, video=video,
                    stats=analysis.stats, revision=analysis.revision)


def row_figures(clean, test, variant: Variant, film=None) -> dict:
    """The invariance figures of ``test`` (a variant's timeline) against ``clean`` (the clean
    variant's: for a cut, ``derive`` of :func:`cut_analysis`): :func:`~autohaptics.metrics.headline`
    over the ticks both cover, plus for a cut its largest vibration in the first ``JOLT_S`` and the
    whole ``film``'s there (what the film itself vibrates at that place)."""
    n = min(test.n_ticks, clean.n_ticks)
    report = compare_tracks(clean.vibration[:n], test.vibration[:n], clean.temperature_c[:n], test.temperature_c[:n],
                            clean.fans[:n], test.fans[:n])
    report["n_ticks"] = {"ref": int(clean.n_ticks), "test": int(test.n_ticks), "compared": n,
                         "difference": int(test.n_ticks) - int(clean.n_ticks)}
    fig = headline(report)
    fig["fan_ticks_on"] = int(report["fans"].get("ref_ticks_on", 0))
    if variant.start_s > 0:
        j = int(round(JOLT_S / TICK_S))
        fig["jolt"] = float(test.vibration[:j].max(initial=0.0))
        k0 = int(round(variant.start_s / TICK_S))
        fig["film_there"] = float((film if film is not None else clean).vibration[k0:k0 + j].max(initial=0.0))
    return fig


def named_rows(words: str) -> list[Variant]:
    """The rows whose name contains one of the comma-separated ``words`` (case aside; all rows for none)."""
    wanted = [w.strip().lower() for w in words.split(",") if w.strip()]
    return [v for v in VARIANTS if not wanted or any(w in v.name.lower() for w in wanted)]


def over_row(words: str) -> Variant | None:
    """The row ``--over`` names: the first whose name contains ``words`` (case aside; None for none
    asked). A cut cannot be one: the rows after it would compare a film from the cut on with the film."""
    if not words.strip():
        return None
    found = named_rows(words)
    if not found:
        raise ParameterError(f"--over {words.strip()!r}: no row of the matrix has that in its name")
    if found[0].start_s > 0:
        raise ParameterError(f"--over {found[0].name!r}: a cut cannot be written under other rows")
    return found[0]


def misses(fig: dict) -> list[str]:
    """The targets a row's figures miss, as short phrases (empty: the row meets them all). A cut's
    jolt counts only where the film itself does not vibrate at that place."""
    out = []
    for key, (op, bound) in TARGETS.items():
        value = fig.get(key)
        if value is None or not np.isfinite(value):
            continue
        if (op == ">=" and value < bound) or (op == "<=" and value > bound):
            out.append(f"{key} {value:.3g} (target {op} {bound})")
    if "jolt" in fig and fig["jolt"] > JOLT_MAX >= fig["film_there"]:
        out.append(f"jolt {fig['jolt']:.2f} in the first {JOLT_S:g} s (target <= {JOLT_MAX}, the film there "
                   f"{fig['film_there']:.2f})")
    return out


def silence_pair(out_dir: Path, *, duration_s: float = SILENCE_S, width: int = 64, height: int = 36) -> tuple[Path, Path]:
    """The digital-silence pair: booms and blips over exact digital silence, and the same over a
    -100 dBFS noise floor (float samples, so neither is rounded to the other), with a still picture.
    Returns (silence, floor) paths, written once into ``out_dir``."""
    from autohaptics.testing import sounds, write_scene

    paths = []
    for floor in (None, -100.0):
        scene = sounds.booms_and_blips(duration_s, floor_db=floor)
        dst = out_dir / f"{scene.name}_{duration_s:g}s.mkv"
        if not dst.exists():
            out_dir.mkdir(parents=True, exist_ok=True)
            write_scene(dst, scene, width=width, height=height, fps=5, audio_codec="pcm_f32le", long=True)
        paths.append(dst)
    return paths[0], paths[1]


# ------------------------------------------------------------------ the command
def register(sub) -> None:
    p = sub.add_parser("matrix", help="the material matrix: variants of each clip against the clean one")
    p.add_argument("video", nargs="*", help="source files (default: the shared film clips)")
    p.add_argument("--rows", default="", help="only the rows whose name contains one of these comma-separated words")
    p.add_argument("--over", default="",
                   help="write each row from the first row whose name contains these words instead of the source "
                        "(e.g. 'grain': a grainy film as each screener, letterboxed, at each rate), against the "
                        "clean source")
    p.add_argument("--speed", action="store_true",
                   help="also time each file's generate and bare decode as whole processes (ratio per row)")
    p.add_argument("--no-silence", action="store_true", help="leave out the digital-silence pair")
    p.add_argument("--silence-s", type=float, default=SILENCE_S, help="length of the digital-silence pair, s")
    p.add_argument("--out", default="out/matrix", help="folder for the variant files, timelines and figures")
    p.set_defaults(func=run)


def run(args) -> int:
    from autohaptics.bench.clips import shared_media
    from autohaptics.media import probe

    out = Path(args.out)
    sources = [Path(v) for v in args.video] or [shared_media() / name for name in SHARED_SOURCES]
    for s in sources:
        if not s.is_file():
            raise ParameterError(f"{s}: no such file")
    over = over_row(args.over)
    variants = [v for v in named_rows(args.rows) if v is not over]
    here = machine()
    print(machine_line(here), file=sys.stderr)
    rows, figures = [], []
    for src in sources:
        clean = _measured(src, out, args.speed)
        rows.append(_table_row(src.name, "clean", clean, None))
        analysis = None
        base = src if over is None else variant_file(src, over, out / "variants")
        info = probe(base)
        for v in variants:
            why = not_applicable(v, info)
            if why:
                print(f"{src.name}: {v.name}: left out ({why})", file=sys.stderr)
                continue
            name = v.name if over is None else f"{over.name}, then {v.name}"
            print(f"{src.name}: {name} ...", file=sys.stderr)
            path = variant_file(base, v, out / "variants")
            got = _measured(path, out, args.speed)
            ref = clean["timeline"]
            if v.start_s > 0:
                analysis = analysis or _analysis(src)
                ref = _derive(cut_analysis(analysis, v.start_s, got["timeline"].n_ticks))
            fig = {**row_figures(ref, got["timeline"], v, film=clean["timeline"]), **_speed(got)}
            figures.append({"source": src.name, "variant": name, "group": v.group, **fig,
                            "misses": misses(fig)})
            rows.append(_table_row(src.name, name, got, fig))
    if not args.no_silence:
        silent, floor = silence_pair(out / "variants", duration_s=args.silence_s)
        a, b = _measured(floor, out, True), _measured(silent, out, True)
        fig = {**row_figures(a["timeline"], b["timeline"], Variant("digital silence", "silence")), **_speed(b)}
        fig["generate_vs_floor"] = b["generate_s"] / a["generate_s"]
        figures.append({"source": floor.name, "variant": "exact digital silence", "group": "silence", **fig,
                        "misses": misses(fig)})
        rows.append(_table_row(floor.name, "clean (-100 dBFS floor)", a, None))
        rows.append(_table_row(floor.name, "exact digital silence", b, fig))
    print(table(rows, ["source", "variant", "onset F1", "fan-tick F1", "fan IoU (tol.)", "temp. MAE C",
                       "jolt / film", "generate / decode", "meets"]))
    out.mkdir(parents=True, exist_ok=True)
    doc = {"time": time.strftime("%Y-%m-%d %H:%M:%S"), "machine": here, "targets": TARGETS, "rows": figures}
    (out / "matrix.json").write_text(json.dumps(doc, indent=1, default=str))
    missed = [f for f in figures if f["misses"]]
    print(f"{len(figures) - len(missed)} of {len(figures)} rows meet every target; figures in {out / 'matrix.json'}")
    for f in missed:
        print(f"  {f['source']}: {f['variant']}: {'; '.join(f['misses'])}")
    return 0


def _measured(path: Path, out: Path, speed: bool) -> dict[str, Any]:
    """``generate`` of ``path`` in a fresh process (its timeline and whole-process seconds), and with
    ``speed`` the bare decode's whole-process seconds too."""
    from autohaptics.bench.child import measure_decode, measure_generate
    from autohaptics.bench.pipeline import GenerateRun
    from autohaptics.timeline import Timeline

    work = out / "runs" / path.stem
    work.mkdir(parents=True, exist_ok=True)
    g = measure_generate(path, GenerateRun("generate", ()), work)
    got = {"timeline": Timeline.load(work / "generate.json"), "generate_s": g["process_wall_s"]}
    if speed:
        got["decode_s"] = measure_decode(path, work)["process_wall_s"]
    return got


def _analysis(path: Path):
    from autohaptics.pipeline import analyse

    return analyse(path)


def _derive(analysis):
    from autohaptics.pipeline.derive import derive

    return derive(analysis)


def _speed(got: dict) -> dict:
    return {"generate_s": got["generate_s"], "decode_s": got.get("decode_s"),
            "ratio": got["generate_s"] / got["decode_s"] if got.get("decode_s") else None}


def _table_row(source: str, variant: str, got: dict, fig: dict | None) -> list:
    ratio = got["generate_s"] / got["decode_s"] if got.get("decode_s") else ""
    if fig is None:
        return [source, variant, "", "", "", "", "", ratio, ""]
    jolt = f"{fig['jolt']:.2f} / {fig['film_there']:.2f}" if "jolt" in fig else ""
    return [source, variant, fig["onset_f1"], fig["fan_ticks_f1"], fig["fan_iou_tolerant"], fig["temperature_mae_c"],
            jolt, ratio, "yes" if not misses(fig) else "NO"]
