"""``autohaptics bench matrix``: the material matrix, the forms a film reaches us in.

Each source (the shared film clips, or any file given) is written again as each :data:`VARIANTS` row says:
re-encoded as it is (H.264); letterboxed and pillarboxed; at half and double size, and at a size that changes every
six seconds (an adaptive stream's recording); at 23.976, 25, 29.97, 50, 59.94 and 120 fps and at a variable frame
rate; in 10 bits (H.264, and a ProRes master with its sound in one stream or, as editing suites write it, each
channel in a mono track); as an HDR10 grade; as HEVC and AV1; as DVDs (NTSC telecined, coded progressive and
interlaced; PAL anamorphic); as 3D films, their two views packed side by side or top and bottom; as VP9 and H.264
screeners; with its sound as mono, stereo (Opus, and AAC from FFmpeg's downmix), 5.1 and 7.1, as AC-3 carrying
Dolby's dynamic range words, behind a commentary and a compatibility stereo track, and changing its sample rate
for 10 s (a channel's advertisement); cut to start mid-score, and as a broadcast recording begun mid-GOP on a clock
that wraps. Every row's timeline is compared with the source's own
(the clean variant; for a cut, the clean analysis from the cut on derived as a film of its own, so what differs is
the start of the file, not the context a whole film gives its film-relative levels): onset F1, fan-tick F1, tolerant
fan IoU and temperature MAE against :data:`TARGETS`, and a cut's largest vibration in its first 0.5 s where the film
itself does not vibrate. With ``--speed`` each file's ``generate`` and its bare decode
(:func:`~autohaptics.bench.decode.bare_decode`) also run as whole processes, and the row gives their ratio. The
digital-silence pair (booms and blips over exact silence, and over a -100 dBFS floor) is a row of its own: the
silence variant against the floor variant, and the ratio of their generate times.

Variant files are written once into ``--out`` and reused; nothing large is committed.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import time
from dataclasses import dataclass, field
from fractions import Fraction
from pathlib import Path
from typing import Any, Callable

import numpy as np

from autohaptics.bench.common import machine, machine_line, table
from autohaptics.errors import ParameterError
from autohaptics.metrics import compare_tracks, headline
from autohaptics.timebase import TICK_S

# the issue-31 acceptance of every row against its clean variant: (comparison, bound)
TARGETS = {"onset_f1": (">=", 0.9), "fan_ticks_f1": (">=", 0.9), "fan_iou_tolerant": (">=", 0.8),
           "temperature_mae_c": ("<=", 0.5)}
JOLT_S = 0.5  # a cut's opening judged for a jolt
JOLT_MAX = 0.2  # the largest vibration allowed there, 0..1
SHARED_SOURCES = ("bbb_opening_30s_1280x720_vp8_vorbis.webm", "sintel_trailer_640x272_vp8_vorbis.webm")
CUT_MIN_S = 2.5  # the shortest cut worth comparing, s
SILENCE_S = 180.0  # the digital-silence pair's length, s (the 3-minute clip)


def _even(x: float) -> int:
    return max(2, int(round(x / 2)) * 2)


@dataclass(frozen=True)
class Variant:
    """One row of the matrix: how a source is written again (``testing.reencode``'s options).

    size : (source width, height) -> (width, height) of the variant's frame, or None (the source's).
    screener : a codec of ``testing.reencode.screener`` ("vp9", "h264") instead of ``reencode``
        (``options`` then go to ``screener``: its height, frame rate).
    start_s : where a cut starts in the source, s (on the 100 ms grid); its ticks are compared with
        the clean film's from there.
    write : writes the row's file instead of ``reencode``, (source, dst, ``options``) -> dst (a 3D film
        packed from the source, :func:`_packed`; AC-3 given Dolby's dynamic range words, :func:`_film_drc`;
        the mix behind other tracks, :func:`_tracks_ahead`).
    isolated : written by a fresh interpreter, for an encoder that changes the process that runs it
        (FFmpeg's libsvtav1, run as root, leaves the thread that opened it real-time, SCHED_FIFO 99,
        and every process started from it later inherits that).
    """

    name: str
    group: str
    suffix: str = ".mp4"
    options: dict = field(default_factory=dict)
    size: Callable[[int, int], tuple[int, int]] | None = None
    screener: str | None = None
    crf: int | None = None
    start_s: float = 0.0
    write: Callable[[Path, Path, dict], Path] | None = None
    isolated: bool = False

    @property
    def slug(self) -> str:
        return "".join(c if c.isalnum() else "_" for c in self.name).strip("_")


def _sound(layout: str, bit_rate: int, codec: str = "libopus") -> dict:
    """A sound row's options: the picture's packets as they are, the sound mixed to ``layout`` as
    ``codec`` (Opus: a codec of its own, not the AAC of the picture rows)."""
    return {"video_codec": "copy", "audio_codec": codec, "audio_layout": layout, "audio_bit_rate": bit_rate}


def _film_drc(src: Path, dst: Path, options: dict) -> Path:
    """``src`` re-encoded with ``options`` (an AC-3 sound), then given Dolby's Film Standard dynamic range
    words (``testing.dolby``), as a DVD's, a Blu-ray's or a broadcast's sound carries them and FFmpeg's
    encoder does not write them."""
    from autohaptics.testing.dolby import with_film_drc
    from autohaptics.testing.reencode import reencode

    written = reencode(src, dst.with_name(f"{dst.stem}.written{dst.suffix}"), **options)
    with_film_drc(written, dst)
    written.unlink()
    return dst


def _tracks_ahead(src: Path, dst: Path, options: dict) -> Path:
    """``src`` with a commentary and a compatibility stereo track ahead of its own mix
    (``testing.tracks.with_tracks_ahead``)."""
    from autohaptics.testing.tracks import with_tracks_ahead

    return with_tracks_ahead(src, dst)


def _broadcast(src: Path, dst: Path, options: dict) -> Path:
    """``src`` re-encoded as a channel sends it (H.264, a keyframe every 12 frames; the sound as ``options``
    say), then kept as ``options["kept"]`` says (``testing.broadcast``): "recording", begun at ``begin_s`` on
    a clock that wraps ``wrap_after_s`` later; "adaptive", an adaptive stream's renditions in turn; "rate
    break", its sound at another rate over 10-20 s (``testing.broadcast.as_rate_break``)."""
    from autohaptics.testing.broadcast import WRAP_S, as_adaptive, as_rate_break, as_recording
    from autohaptics.testing.reencode import reencode

    options = dict(options)
    kept, begin_s, wrap_after_s = options.pop("kept"), options.pop("begin_s", 0.0), options.pop("wrap_after_s", 0.0)
    sent = reencode(src, dst.with_name(f"{dst.stem}.sent.mp4"), video_options={**ENCODE, "g": "12"}, **options)
    if kept == "recording":
        as_recording(sent, dst, clock_s=WRAP_S - begin_s - wrap_after_s, begin_s=begin_s)
    else:
        {"adaptive": as_adaptive, "rate break": as_rate_break}[kept](sent, dst)
    sent.unlink()
    return dst


def _packed(src: Path, dst: Path, options: dict) -> Path:
    """``src`` as a 3D film, its two views packed as ``options`` say (``testing.stereo.write_packed``)."""
    from autohaptics.testing.stereo import write_packed

    return write_packed(src, dst, **options)


ENCODE = {"preset": "veryfast", "crf": "18"}  # x264 settings of every row that re-encodes the picture itself
VARIANTS: tuple[Variant, ...] = (
    Variant("H.264 re-encode, nothing else changed", "encode"),
    Variant("letterbox (bars top and bottom)", "picture", options={"fit": "pad"}, size=lambda w, h: (w, _even(h * 4 / 3))),
    Variant("pillarbox (bars left and right)", "picture", options={"fit": "pad"}, size=lambda w, h: (_even(w * 4 / 3), h)),
    Variant("half size", "picture", size=lambda w, h: (_even(w / 2), _even(h / 2))),
    Variant("double size (a UHD master of an HD film)", "picture", size=lambda w, h: (_even(w * 2), _even(h * 2))),
    Variant("an adaptive stream's recording (HLS): the picture's size changing every 6 s, MPEG-TS, H.264, AAC",
            "picture", ".ts", write=_broadcast, options={"kept": "adaptive"}),
    Variant("a channel's recording, its sound at another rate over 10-20 s (an advertisement), MPEG-TS, H.264, AC-3",
            "sound", ".ts", write=_broadcast, options={"kept": "rate break", "audio_codec": "ac3"}),
    Variant("23.976 fps", "rate", options={"fps": Fraction(24000, 1001)}),
    Variant("25 fps", "rate", options={"fps": 25}),
    Variant("29.97 fps", "rate", options={"fps": Fraction(30000, 1001)}),
    Variant("50 fps", "rate", options={"fps": 50}),
    Variant("59.94 fps (a 720p broadcast: each picture repeated 2 and 3 times in turn)", "rate",
            options={"fps": Fraction(60000, 1001)}),
    Variant("120 fps (each picture repeated 5 times)", "rate", options={"fps": 120}),
    Variant("variable frame rate", "rate", options={"conversion": "vfr"}),
    Variant("10-bit H.264", "depth", options={"pix_fmt": "yuv420p10le"}),
    Variant("ProRes 422 HQ master, 24-bit PCM", "depth", ".mov",
            options={"video_codec": "prores_ks", "pix_fmt": "yuv422p10le", "video_options": {"profile": "3"},
                     "audio_codec": "pcm_s24le"}),
    Variant("ProRes 422 HQ master, 24-bit PCM in mono tracks", "depth", ".mov",
            options={"video_codec": "prores_ks", "pix_fmt": "yuv422p10le", "video_options": {"profile": "3"},
                     "audio_codec": "pcm_s24le", "audio_tracks": "mono"}),
    Variant("HDR10 grade (PQ, BT.2020), 10-bit H.264", "depth", options={"pix_fmt": "yuv420p10le", "transfer": "pq"}),
    Variant("HEVC, x265 veryfast crf 18", "codec",
            options={"video_codec": "libx265",
                     "video_options": {"preset": "veryfast", "crf": "18", "x265-params": "log-level=error"}}),
    Variant("AV1, SVT-AV1 preset 10 crf 35 (a streaming service's), Opus", "codec", ".mkv", isolated=True,
            options={"video_codec": "libsvtav1", "video_options": {"preset": "10", "crf": "35"}, "audio_codec": "libopus"}),
    Variant("MPEG-2 with two B-frames (a DVD's), AC-3", "codec", ".mkv",
            options={"video_codec": "mpeg2video", "video_bit_rate": 6_000_000, "video_options": {"bf": "2", "g": "15"},
                     "audio_codec": "ac3"}),
    Variant("NTSC DVD: 3:2 pulldown to 30 fps, MPEG-2 with two B-frames, AC-3", "codec", ".mkv",
            options={"fps": 30, "conversion": "pulldown", "video_codec": "mpeg2video", "video_bit_rate": 6_000_000,
                     "video_options": {"bf": "2", "g": "18"}, "audio_codec": "ac3"}),
    Variant("NTSC DVD hard-telecined: 3:2 pulldown coded interlaced, MPEG-2, AC-3", "codec", ".mkv",
            options={"fps": 30, "conversion": "pulldown", "video_codec": "mpeg2video", "video_bit_rate": 6_000_000,
                     "video_options": {"bf": "2", "g": "18", "flags": "+ilme+ildct", "top": "1"}, "audio_codec": "ac3"}),
    Variant("PAL DVD: 720 x 576 anamorphic 16:9, MPEG-2 with two B-frames, AC-3", "codec", ".mkv",
            size=lambda w, h: (720, 576),
            options={"fps": 25, "fit": "pad", "pixel_aspect": Fraction(64, 45), "video_codec": "mpeg2video",
                     "video_bit_rate": 6_000_000, "video_options": {"bf": "2", "g": "12"}, "audio_codec": "ac3"}),
    Variant("3D half side-by-side, declared by H.264's frame-packing message (a 3D Blu-ray's rip)", "codec", ".mkv",
            options={"packing": "side_by_side", "declared": "h264"}, write=_packed),
    Variant("3D half top-and-bottom, not declared", "codec", ".mkv",
            options={"packing": "top_bottom", "declared": "none"}, write=_packed),
    Variant("MPEG-4 Part 2 AVI with two B-frames (a DivX or Xvid copy), MP3 stereo", "codec", ".avi",
            options={"video_codec": "mpeg4", "video_bit_rate": 1_200_000, "video_options": {"bf": "2", "g": "250"},
                     "audio_codec": "libmp3lame", "audio_layout": "stereo"}),
    Variant("screener VP9 240p crf 32 realtime, Opus", "screener", ".webm", screener="vp9", crf=32),
    Variant("screener H.264 360p crf 35", "screener", screener="h264", crf=35),
    Variant("screener H.264 240p crf 32", "screener", screener="h264", crf=32, options={"height": 240}),
    Variant("sound mono", "sound", ".mkv", options=_sound("mono", 96_000)),
    Variant("sound stereo", "sound", ".mkv", options=_sound("stereo", 192_000)),
    Variant("sound 5.1", "sound", ".mkv", options=_sound("5.1", 384_000)),
    Variant("sound 7.1", "sound", ".mkv", options=_sound("7.1", 512_000)),
    Variant("sound 8 dB quieter", "sound", ".mkv", options={**_sound("stereo", 192_000), "audio_gain_db": -8.0}),
    # as ``ffmpeg -ac 2 -c:a aac`` makes it: FFmpeg's float downmix, which a loud 5.1 mix takes past full
    # scale, and FFmpeg's AAC encoder then turns such blocks down (docs/BENCHMARKS.md, "Stop 57")
    Variant("sound stereo AAC 128 kb/s, FFmpeg's downmix", "sound", ".mkv", options=_sound("stereo", 128_000, "aac")),
    Variant("sound AC-3 with Dolby's Film Standard DRC words (a DVD's, a broadcast's)", "sound", ".mkv",
            options={"video_codec": "copy", "audio_codec": "ac3", "audio_bit_rate": 448_000}, write=_film_drc),
    Variant("sound behind a commentary and a compatibility stereo track (a rip's, HandBrake's)", "sound", ".mkv",
            write=_tracks_ahead),
    Variant("cut mid-score at 7.3 s", "start", options={"start_s": 7.3}, start_s=7.3),
    Variant("cut mid-score at 13.7 s", "start", options={"start_s": 13.7}, start_s=13.7),
    Variant("cut mid-score at 21.1 s", "start", options={"start_s": 21.1}, start_s=21.1),
    Variant("broadcast recording begun mid-GOP at 4.3 s, its clock wrapping 10 s in: MPEG-TS, H.264 GOP 12, AC-3",
            "start", ".ts", start_s=4.3, write=_broadcast,
            options={"kept": "recording", "audio_codec": "ac3", "audio_bit_rate": 384_000, "begin_s": 4.3,
                     "wrap_after_s": 10.0}),
)


def not_applicable(variant: Variant, info) -> str | None:
    """Why ``variant`` does not apply to a source (``media.MediaInfo``), or None: a sound row needs
    sound, a picture row a picture, 3:2 pulldown a 24 fps film, a cut at least ``CUT_MIN_S`` of film after it."""
    if variant.group == "sound" and info.audio is None:
        return "no sound"
    if info.video is None:
        return "no picture"
    if variant.options.get("audio_codec") == "ac3" and info.audio is not None and info.audio.channels > 6:
        return f"AC-3 carries at most 5.1, the sound has {info.audio.channels} channels"
    if variant.options.get("conversion") == "pulldown" and round(float(info.video.fps), 2) != 24:
        return f"3:2 pulldown telecines a 24 fps film, this one is {float(info.video.fps):g} fps"
    if variant.start_s and variant.start_s > info.duration_s - CUT_MIN_S:
        return f"the film is {info.duration_s:.1f} s long"
    return None


def variant_file(src: Path, variant: Variant, out_dir: Path) -> Path:
    """``src`` written as ``variant`` says, into ``out_dir`` (reused when already there)."""
    from autohaptics.media import probe
    from autohaptics.testing.reencode import reencode, screener

    dst = out_dir / f"{src.stem}__{variant.slug}{variant.suffix}"
    if dst.exists():
        return dst
    out_dir.mkdir(parents=True, exist_ok=True)
    if variant.isolated:
        if variant not in VARIANTS:
            raise ParameterError(f"only a row of the matrix is written by a fresh interpreter, not {variant.name!r}")
        code = ("import sys; from dataclasses import replace; from pathlib import Path; "
                "from autohaptics.bench.matrix import VARIANTS, variant_file; "
                "v = next(v for v in VARIANTS if v.slug == sys.argv[3]); "
                "variant_file(Path(sys.argv[1]), replace(v, isolated=False), Path(sys.argv[2]))")
        env = {**os.environ, "SVT_LOG": "2"}  # SVT-AV1's warnings and errors, not its banner
        subprocess.run([sys.executable, "-c", code, str(src), str(out_dir), variant.slug], check=True, timeout=3600,
                       env=env)
        return dst
    if variant.screener is not None:
        return screener(src, dst, codec=variant.screener, crf=variant.crf, **variant.options)
    if variant.write is not None:
        return variant.write(src, dst, dict(variant.options))
    options = dict(variant.options)
    if options.get("video_codec", "libx264") == "libx264" and variant.suffix in (".mp4", ".mkv"):
        options.setdefault("video_options", dict(ENCODE))
    if variant.size is not None:
        w, h = probe(src).video.display_size
        options["width"], options["height"] = variant.size(int(w), int(h))
    return reencode(src, dst, **options)


def cut_analysis(analysis, start_s: float, n_ticks: int):
    """The feature cache of ``analysis`` (:class:`~autohaptics.pipeline.cache.Analysis`) from
    ``start_s`` for ``n_ticks`` ticks, as the cache of a film of its own: what a cut made without any
    loss would give, so a cut file's timeline compares with ``derive`` of it."""
    from autohaptics.pipeline.cache import Analysis
    from autohaptics.pipeline.video import VideoAnalysis
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
    words = [w.strip().lower() for w in args.rows.split(",") if w.strip()]
    variants = [v for v in VARIANTS if not words or any(w in v.name.lower() for w in words)]
    here = machine()
    print(machine_line(here), file=sys.stderr)
    rows, figures = [], []
    for src in sources:
        clean = _measured(src, out, args.speed)
        rows.append(_table_row(src.name, "clean", clean, None))
        analysis = None
        for v in variants:
            why = not_applicable(v, probe(src))
            if why:
                print(f"{src.name}: {v.name}: left out ({why})", file=sys.stderr)
                continue
            print(f"{src.name}: {v.name} ...", file=sys.stderr)
            path = variant_file(src, v, out / "variants")
            got = _measured(path, out, args.speed)
            ref = clean["timeline"]
            if v.start_s > 0:
                analysis = analysis or _analysis(src)
                ref = _derive(cut_analysis(analysis, v.start_s, got["timeline"].n_ticks))
            fig = {**row_figures(ref, got["timeline"], v, film=clean["timeline"]), **_speed(got)}
            figures.append({"source": src.name, "variant": v.name, "group": v.group, **fig,
                            "misses": misses(fig)})
            rows.append(_table_row(src.name, v.name, got, fig))
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
