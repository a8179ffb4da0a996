"""The rows of the material matrix (``bench matrix``): how each writes a source again (:data:`VARIANTS`), and
which apply to a source (:func:`not_applicable`). :func:`variant_file` writes a row's file.
"""

from __future__ import annotations

import os
import subprocess
import sys
from dataclasses import dataclass, field
from fractions import Fraction
from pathlib import Path
from typing import Callable

from autohaptics.errors import ParameterError

CUT_MIN_S = 2.5  # the shortest cut worth comparing, s


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
    break", its sound at another rate over 10-20 s (``testing.broadcast.as_rate_break``); "multiplex", the first
    of two programmes, the other a channel's (``other_channel``) on a clock an hour earlier."""
    from autohaptics.testing import broadcast as tb
    from autohaptics.testing.reencode import reencode

    options = dict(options)
    kept, begin_s, wrap_after_s = options.pop("kept"), options.pop("begin_s", 0.0), options.pop("wrap_after_s", 0.0)
    sent = reencode(src, dst.with_name(f"{dst.stem}.sent.mp4"), video_options={**ENCODE, "g": "12"}, **options)
    if kept == "recording":
        tb.as_recording(sent, dst, clock_s=tb.WRAP_S - begin_s - wrap_after_s, begin_s=begin_s)
    elif kept == "multiplex":
        from autohaptics.media import probe

        other = tb.other_channel(dst.with_name(f"{dst.stem}.other.mp4"), probe(sent).duration_s)
        tb.as_multiplex([sent, other], dst, clocks_s=(3600.0, 0.0))
        other.unlink()
    else:
        {"adaptive": tb.as_adaptive, "rate break": tb.as_rate_break}[kept](sent, dst)
    sent.unlink()
    return dst


def _burnt(src: Path, dst: Path, options: dict) -> Path:
    """``src`` with an overlay or film grain burnt in (``testing.burnin.with_burn_in``, ``options["kind"]``)."""
    from autohaptics.testing.burnin import with_burn_in

    return with_burn_in(src, dst, options["kind"])


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
    Variant("a recording of a whole multiplex: the film the first of two programmes, the other's clock an hour "
            "earlier and its sound 5.1, MPEG-TS, H.264, AC-3", "codec", ".ts", write=_broadcast,
            options={"kept": "multiplex", "audio_codec": "ac3", "audio_bit_rate": 384_000}),
    Variant("a channel's recording, its sound at another rate over 10-20 s (an advertisement), MPEG-TS, H.264, AC-3",
            "sound", ".ts", write=_broadcast, options={"kept": "rate break", "audio_codec": "ac3"}),
    Variant("a screener's burnt-in timecode (a black box at the bottom centre, its digits counting the frames)",
            "overlay", ".mkv", write=_burnt, options={"kind": "timecode"}),
    Variant("a channel's logo burnt in (a ring and letters at 60 % white, top right)", "overlay", ".mkv",
            write=_burnt, options={"kind": "logo"}),
    Variant("a watermark burnt in across the middle (a line of words at 35 % white)", "overlay", ".mkv",
            write=_burnt, options={"kind": "watermark"}),
    Variant("film grain (Gaussian, sd 8 grey levels, a little over a pixel across, new every frame)", "picture",
            ".mkv", write=_burnt, options={"kind": "grain"}),
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
                "from autohaptics.bench.variants import VARIANTS, variant_file; "
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
