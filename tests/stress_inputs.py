"""Bad and odd media for the stress suite (tests/test_stress.py), generated on demand.

Every :class:`Case` names one input kind, how to write it into a folder (small files, written
with :mod:`autohaptics.testing` or directly with PyAV where synth cannot express it: irregular
timestamps, rotation metadata, NaN samples, streams of different lengths) and its expected
outcome: a valid timeline, or a clear error whose one-line message contains ``message``.

Inputs run through the real command line (``autohaptics generate``) inside a long-lived worker
process (:class:`Worker`), so a hard crash (a segfault in a decoder) fails one case instead of
killing the test run, and the Python start-up is paid once. Run as a script, this module is
that worker: it reads one JSON request per line on stdin and answers one JSON line on stdout.
"""

from __future__ import annotations

import json
import math
import os
import select
import subprocess
import sys
import tempfile
import zipfile
from collections.abc import Callable
from dataclasses import dataclass
from fractions import Fraction
from pathlib import Path

import numpy as np

CLIP_S = 1.0  # duration of most generated clips, s
W, H = 64, 36  # frame size of most generated clips


@dataclass(frozen=True)
class Case:
    """One stress input and what must come out of it.

    name : the input kind (test id). build : writes the input into a folder, returns its path.
    expect : "timeline" or "error". message : for errors, a fragment of the one-line message.
    args : extra ``autohaptics generate`` options (preset, mode, --allow-truncated).
    duration_s : the duration the file was written with (None: not checked).
    check : further known-answer checks on the loaded Timeline.
    """

    name: str
    build: Callable[[Path], Path]
    expect: str
    message: str = ""
    args: tuple[str, ...] = ()
    duration_s: float | None = None
    check: Callable | None = None


# ------------------------------------------------------------------ writers
def _scene(duration_s: float = CLIP_S, rgb=(200, 40, 30), *, audio=True, moving=True):
    """A textured background with a moving, growing disc and a noise bed plus a 50 Hz boom."""
    from autohaptics import testing as synth

    shapes = (synth.Shape("circle", (250, 250, 240), xy0=(0.25, 0.5), xy1=(0.75, 0.5), size0=(0.2, 0.3),
                          size1=(0.45, 0.7), texture=synth.Texture("checker", 0.25, 0.6)),) if moving else ()
    sound = (synth.Noise(0.0, duration_s, -30.0, seed=3),
             synth.Tone(0.2 * duration_s, 0.6 * duration_s, 50.0, -12.0)) if audio else ()
    return synth.Scene(duration_s=duration_s, shapes=shapes, audio=sound,
                       background=(synth.Segment(0.0, duration_s, rgb, texture=synth.Texture("noise", 0.08, 0.4)),))


def synth_clip(name: str, *, duration_s: float = CLIP_S, rgb=(200, 40, 30), moving: bool = True,
               **kwargs) -> Callable[[Path], Path]:
    """A builder writing :func:`_scene` with :func:`autohaptics.testing.write_scene` (kwargs go there)."""

    def build(folder: Path) -> Path:
        from autohaptics import testing as synth

        if (folder / name).exists():
            return folder / name
        kwargs.setdefault("width", W)
        kwargs.setdefault("height", H)
        return synth.write_scene(folder / name, _scene(duration_s, rgb, moving=moving), **kwargs)

    return build


def write_streams(path: Path, *, frames=None, fps: float | Fraction = 24, times_s=None, audio=None,
                  sample_rate: int = 48_000, layout: str = "stereo", audio_codec: str = "aac",
                  video_codec: str = "libx264", rotation: int | None = None, audio_start_s: float = 0.0,
                  options: dict | None = None, pix_fmt: str = "yuv420p", container: str | None = None,
                  video_options: dict | None = None) -> Path:
    """Write frames and samples exactly as given (PyAV), for what synth cannot express.

    frames : RGB uint8 arrays [shape=(h, w, 3)]; times_s : their presentation times, s (default
    i / fps; irregular times make a variable frame rate). audio : float32 [shape=(channels, n)],
    written as packed float (NaN and inf survive in pcm_f32le). rotation : display rotation, degrees.
    options : the container's; video_options : the video encoder's (e.g. x264's ``interlaced=1``).
    """
    import av

    with av.open(str(path), "w", format=container, options=options or {}) as c:
        vs = as_ = None
        if frames is not None:
            vs = c.add_stream(video_codec, rate=Fraction(fps).limit_denominator(1001))
            vs.height, vs.width = frames[0].shape[:2]
            vs.pix_fmt = pix_fmt
            if video_options:
                vs.options = dict(video_options)
            if times_s is not None:
                vs.time_base = Fraction(1, 1000)
            if rotation is not None:
                vs.set_display_rotation(rotation)
        if audio is not None:
            as_ = c.add_stream(audio_codec, rate=sample_rate, layout=layout)
        if vs is not None:
            for i, rgb in enumerate(frames):
                fr = av.VideoFrame.from_ndarray(np.ascontiguousarray(rgb), format="rgb24")
                if times_s is None:
                    fr.pts, fr.time_base = i, Fraction(1) / vs.codec_context.framerate
                else:
                    fr.pts, fr.time_base = int(round(times_s[i] * 1000)), Fraction(1, 1000)
                for pkt in vs.encode(fr):
                    c.mux(pkt)
            for pkt in vs.encode(None):
                c.mux(pkt)
        if as_ is not None:
            x = np.asarray(audio, np.float32)
            start = int(round(audio_start_s * sample_rate))
            for s in range(0, x.shape[1], 1024):
                block = np.ascontiguousarray(x[:, s:s + 1024].T).reshape(1, -1)
                fr = av.AudioFrame.from_ndarray(block, format="flt", layout=layout)
                fr.sample_rate, fr.pts, fr.time_base = sample_rate, start + s, Fraction(1, sample_rate)
                for pkt in as_.encode(fr):
                    c.mux(pkt)
            for pkt in as_.encode(None):
                c.mux(pkt)
    return path


def _noise(seconds: float, channels: int = 2, level: float = 0.1, sr: int = 48_000, seed: int = 0) -> np.ndarray:
    rng = np.random.default_rng(seed)
    return (level * rng.standard_normal((channels, int(round(seconds * sr))))).astype(np.float32)


def _frames(n: int, kind: str = "ramp", size=(H, W)) -> list[np.ndarray]:
    """n frames: "ramp" (brightness steps with a moving bar), "flash" (black/white), or an RGB colour."""
    out = []
    for i in range(n):
        if kind == "flash":
            out.append(np.full(size + (3,), 255 if i % 2 else 0, np.uint8))
        elif kind == "ramp":
            f = np.full(size + (3,), 40 + (i * 7) % 150, np.uint8)
            x = (i * 3) % (size[1] - 8)
            f[:, x:x + 8] = 250
            out.append(f)
        else:
            out.append(np.full(size + (3,), kind, np.uint8))
    return out


def build_with(name: str, writer: Callable[[Path], object]) -> Callable[[Path], Path]:
    def build(folder: Path) -> Path:
        path = folder / name
        if not path.exists():
            writer(path)
        return path

    return build


def truncated(source: Callable[[Path], Path], name: str, fraction: float = 0.5) -> Callable[[Path], Path]:
    """The first ``fraction`` of the bytes of another input."""

    def build(folder: Path) -> Path:
        src = source(folder)
        data = src.read_bytes()
        out = folder / name
        out.write_bytes(data[: int(len(data) * fraction)])
        return out

    return build


def patched(source: Callable[[Path], Path], name: str, replace: dict[bytes, bytes]) -> Callable[[Path], Path]:
    """Another input with byte strings replaced (same length: the container stays parseable)."""

    def build(folder: Path) -> Path:
        data = source(folder).read_bytes()
        for old, new in replace.items():
            assert len(old) == len(new) and old in data, old
            data = data.replace(old, new)
        out = folder / name
        out.write_bytes(data)
        return out

    return build


def _bytes(name: str, data: bytes) -> Callable[[Path], Path]:
    return build_with(name, lambda p: p.write_bytes(data))


def _header_only(path: Path) -> None:
    """A container with a video and an audio stream and no packet at all."""
    import av

    with av.open(str(path), "w") as c:
        vs = c.add_stream("libx264", rate=24)
        vs.width, vs.height, vs.pix_fmt = W, H, "yuv420p"
        c.add_stream("aac", rate=48_000, layout="stereo")
        c.start_encoding()


def _zip(path: Path) -> None:
    with zipfile.ZipFile(path, "w") as z:
        z.writestr("film.txt", "not a film " * 200)


def _directory(folder: Path) -> Path:
    d = folder / "a_folder.mp4"
    d.mkdir(exist_ok=True)
    return d


def _vfr(path: Path) -> None:
    rng = np.random.default_rng(1)
    gaps = rng.choice([0.010, 0.033, 0.041, 0.080, 0.150, 0.300], size=40)
    times = np.concatenate([[0.0], np.cumsum(gaps)[:-1]])
    write_streams(path, frames=_frames(40), times_s=times, audio=_noise(float(times[-1]) + 0.05),
                  audio_codec="aac")


def _nan_audio(seconds: float = CLIP_S) -> np.ndarray:
    x = _noise(seconds, 2, 0.2)
    x[:, 4_800:9_600] = np.nan
    x[0, 20_000] = np.inf
    x[1, 30_000:30_010] = -np.inf
    return x


def _square(path: Path, *, antiphase: bool = False) -> None:
    """60 Hz full-scale square waves (in phase on both channels, or in anti-phase)."""
    t = np.arange(int(48_000 * CLIP_S)) / 48_000
    sq = np.where(np.sin(2 * np.pi * 60 * t) >= 0, 1.0, -1.0).astype(np.float32)
    write_streams(path, frames=_frames(24), audio=np.stack([sq, -sq if antiphase else sq]), audio_codec="pcm_s16le")


def _dc(path: Path) -> None:
    x = _noise(CLIP_S, 2, 0.05) + 0.7  # a large DC offset under a little noise
    write_streams(path, audio=x.astype(np.float32), audio_codec="pcm_s16le")


def _one_sample(path: Path) -> None:
    write_streams(path, audio=np.full((1, 1), 0.5, np.float32), layout="mono", audio_codec="pcm_s16le")


# ------------------------------------------------------------------ checks
def _silent(tl) -> None:
    assert not tl.vibration.any(), "silence must not vibrate"
    for name in ("loudness", "sharpness", "booming", "low_energy", "intensity"):
        assert not tl.features[name].any(), name


def _still(tl) -> None:
    assert not tl.vibration.any(), "this input must not vibrate"


def _vibrates(tl) -> None:
    assert tl.vibration.max() > 0, "an audible clip must vibrate somewhere"


def _warm(tl) -> None:
    """Pure red warms the chair from neutral as fast as the device follows (the default mapping)."""
    t = tl.temperature_c
    assert (np.diff(t) >= 0).all() and t[-1] > t[0] + 0.5, f"pure red must warm the chair, got {t.round(2)}"


def _cold(tl) -> None:
    """Pure green cools the chair from neutral as fast as the device follows."""
    t = tl.temperature_c
    assert (np.diff(t) <= 0).all() and t[-1] < t[0] - 0.5, f"pure green must cool the chair, got {t.round(2)}"


def _repaired(tl) -> None:
    assert tl.stats["audio"]["nonfinite_samples_repaired"] > 0, tl.stats["audio"]


def _rotated(tl) -> None:
    assert tl.source["video"]["rotation"] == 90, tl.source["video"]


def _no_video(tl) -> None:
    assert tl.source["video"] is None and not tl.fans.any()


def _no_audio(tl) -> None:
    assert tl.source["audio"] is None and not tl.vibration.any()


def _all_checks(*fns):
    def check(tl):
        for fn in fns:
            fn(tl)

    return check


# ------------------------------------------------------------------ the cases
# 8K: three frames drawn directly (rendering them with synth's float pipeline takes ~800 MB and 40 s)
_8k = build_with("8k.mp4", lambda p: write_streams(p, frames=_frames(3, size=(4320, 7680)), audio=_noise(3 / 24)))
_mp4 = synth_clip("clip.mp4")
_webm = synth_clip("clip.webm")
_mkv = synth_clip("clip.mkv")

CASES: list[Case] = [
    # --- clear errors
    Case("truncated_mp4_50pct", truncated(_mp4, "truncated.mp4"), "error", "not a readable media file"),
    Case("truncated_mp4_faststart_50pct",
         truncated(build_with("faststart.mp4", lambda p: write_streams(
             p, frames=_frames(48), audio=_noise(2.0), options={"movflags": "faststart"})), "truncated_fs.mp4"),
         "error", "truncated or damaged file"),
    Case("truncated_mp4_faststart_allowed",
         truncated(build_with("faststart.mp4", lambda p: write_streams(
             p, frames=_frames(48), audio=_noise(2.0), options={"movflags": "faststart"})), "truncated_fs.mp4"),
         "timeline", args=("--allow-truncated",), duration_s=2.0),
    Case("truncated_webm_50pct", truncated(_webm, "truncated.webm"), "error", "truncated or damaged file"),
    Case("truncated_webm_allowed", truncated(_webm, "truncated.webm"), "timeline", args=("--allow-truncated",),
         duration_s=CLIP_S),
    Case("garbage_bytes_mp4", _bytes("garbage.mp4", bytes(np.random.default_rng(0).integers(0, 256, 50_000,
                                                                                          np.uint8))),
         "error", "not a readable media file"),
    Case("zero_byte_file", _bytes("empty.mp4", b""), "error", "file is empty"),
    Case("zero_length_streams_mp4", build_with("header_only.mp4", _header_only), "error", "no audio or video"),
    Case("zero_length_streams_mkv", build_with("header_only.mkv", _header_only), "error", "not a readable media"),
    Case("directory_as_file", _directory, "error", "is a directory"),
    Case("missing_file", lambda folder: folder / "does_not_exist.mp4", "error", "no such file"),
    Case("zip_archive_as_mkv", build_with("archive.mkv", _zip), "error", "not a readable media file"),
    Case("subtitles_only", _bytes("subtitles.srt", b"1\n00:00:01,000 --> 00:00:02,000\nhello\n"), "error",
         "no audio or video stream"),
    Case("unsupported_video_codec", patched(_mkv, "bad_video_codec.mkv", {b"V_MPEG4/ISO/AVC": b"V_QQQQQ/ISO/QQQ"}),
         "error", "codec"),
    Case("unsupported_audio_codec", patched(_mkv, "bad_audio_codec.mkv", {b"A_AAC": b"A_QQQ"}), "error", "codec"),
    Case("audio_mode_without_audio", synth_clip("video_only.mp4", audio=False), "error", "no audio stream",
         args=("--mode", "audio")),
    Case("visual_mode_without_video", synth_clip("audio_only.wav"), "error", "no video stream",
         args=("--mode", "visual")),
    # --- valid timelines
    Case("video_only", synth_clip("video_only.mp4", audio=False), "timeline", duration_s=CLIP_S, check=_no_audio),
    Case("audio_only_wav", synth_clip("audio_only.wav"), "timeline", duration_s=CLIP_S,
         check=_all_checks(_no_video, _vibrates)),
    Case("audio_only_m4a", synth_clip("audio_only.m4a"), "timeline", duration_s=CLIP_S,
         check=_all_checks(_no_video, _vibrates)),
    Case("one_frame", synth_clip("one_frame.mp4", duration_s=1 / 24, audio=False), "timeline", duration_s=1 / 24),
    Case("one_frame_reference", synth_clip("one_frame.mp4", duration_s=1 / 24, audio=False), "timeline",
         args=("--preset", "reference"), duration_s=1 / 24),
    Case("frames_16x16", synth_clip("tiny.mp4", width=16, height=16), "timeline", duration_s=CLIP_S),
    Case("frames_16x16_reference", synth_clip("tiny.mp4", width=16, height=16), "timeline",
         args=("--preset", "reference"), duration_s=CLIP_S),
    Case("frames_7680x4320", _8k, "timeline", duration_s=3 / 24),
    Case("frames_7680x4320_reference", _8k, "timeline", args=("--preset", "reference"), duration_s=3 / 24),
    Case("odd_size_17x15_yuv444", build_with("odd.mkv", lambda p: write_streams(
        p, frames=_frames(24, size=(15, 17)), audio=_noise(CLIP_S), pix_fmt="yuv444p")), "timeline",
         duration_s=CLIP_S),
    Case("mpeg_ts_mpeg2_mp2", build_with("stream.ts", lambda p: write_streams(
        p, frames=_frames(24), audio=_noise(CLIP_S), video_codec="mpeg2video", audio_codec="mp2",
        container="mpegts")), "timeline", duration_s=CLIP_S),
    Case("avi_mpeg4_pcm", synth_clip("clip.avi"), "timeline", duration_s=CLIP_S, check=_vibrates),
    Case("variable_frame_rate", build_with("vfr.mkv", _vfr), "timeline"),
    Case("fps_23_976", synth_clip("ntsc.mp4", fps=Fraction(24000, 1001)), "timeline", duration_s=CLIP_S),
    Case("fps_120", synth_clip("fps120.mp4", fps=120), "timeline", duration_s=CLIP_S),
    Case("fps_2_holds_ticks", synth_clip("fps2.mkv", duration_s=2.0, fps=2), "timeline", duration_s=2.0),
    Case("audio_8khz", synth_clip("sr8k.wav", sample_rate=8_000), "timeline", duration_s=CLIP_S, check=_vibrates),
    Case("audio_96khz", synth_clip("sr96k.mkv", sample_rate=96_000, audio_codec="pcm_s24le"), "timeline",
         duration_s=CLIP_S, check=_vibrates),
    Case("audio_mono", synth_clip("mono.mp4", channels=1), "timeline", duration_s=CLIP_S, check=_vibrates),
    Case("audio_5_1", synth_clip("surround51.mp4", channels=6), "timeline", duration_s=CLIP_S, check=_vibrates),
    Case("audio_7_1_aac", synth_clip("surround71.mkv", channels=8), "timeline", duration_s=CLIP_S, check=_vibrates),
    Case("audio_7_1_pcm", synth_clip("surround71.wav", channels=8), "timeline", duration_s=CLIP_S, check=_vibrates),
    Case("audio_6ch_no_layout", synth_clip("six_unlabelled.mkv", channels=6, channel_layout=None,
                                           audio_codec="pcm_s16le"), "timeline", duration_s=CLIP_S, check=_vibrates),
    Case("audio_longer_than_video", build_with("audio_longer.mp4", lambda p: write_streams(
        p, frames=_frames(24), audio=_noise(3.0))), "timeline", duration_s=3.0),
    Case("audio_shorter_than_video", build_with("audio_shorter.mp4", lambda p: write_streams(
        p, frames=_frames(72), audio=_noise(0.5))), "timeline", duration_s=3.0),
    Case("audio_starts_late", build_with("audio_late.mkv", lambda p: write_streams(
        p, frames=_frames(48), audio=_noise(1.0), audio_start_s=1.0, audio_codec="pcm_s16le")), "timeline",
         duration_s=2.0),
    Case("nan_inf_samples_wav", build_with("nan.wav", lambda p: write_streams(
        p, audio=_nan_audio(), audio_codec="pcm_f32le")), "timeline", duration_s=CLIP_S, check=_repaired),
    Case("nan_inf_samples_mkv", build_with("nan.mkv", lambda p: write_streams(
        p, frames=_frames(24), audio=_nan_audio(), audio_codec="pcm_f32le")), "timeline", duration_s=CLIP_S,
         check=_repaired),
    # a steady tone under way from the first frame is no event (the start of a file is not one: issue 31)
    Case("full_scale_square", build_with("square.mkv", _square), "timeline", duration_s=CLIP_S, check=_still),
    # the mono downmix is the mean of the channels: anti-phase stereo cancels (documented decision)
    Case("antiphase_stereo_square", build_with("square_antiphase.mkv", lambda p: _square(p, antiphase=True)),
         "timeline", duration_s=CLIP_S, check=_still),
    Case("dc_offset", build_with("dc.wav", _dc), "timeline", duration_s=CLIP_S),
    Case("one_sample_audio", build_with("one_sample.wav", _one_sample), "timeline", duration_s=1 / 48_000),
    Case("long_silence", build_with("silence.wav", lambda p: write_streams(
        p, audio=np.zeros((1, 48_000 * 120), np.float32), layout="mono", audio_codec="pcm_s16le")), "timeline",
         duration_s=120.0, check=_silent),
    Case("black_frames", build_with("black.mp4", lambda p: write_streams(p, frames=_frames(24, (0, 0, 0)))),
         "timeline", duration_s=CLIP_S),
    Case("white_frames", build_with("white.mp4", lambda p: write_streams(p, frames=_frames(24, (255, 255, 255)))),
         "timeline", duration_s=CLIP_S),
    Case("pure_red_frames", build_with("red.mp4", lambda p: write_streams(p, frames=_frames(24, (255, 0, 0)))),
         "timeline", duration_s=CLIP_S, check=_warm),
    Case("pure_green_frames", build_with("green.mp4", lambda p: write_streams(p, frames=_frames(24, (0, 255, 0)))),
         "timeline", duration_s=CLIP_S, check=_cold),
    Case("pure_blue_frames", build_with("blue.mp4", lambda p: write_streams(p, frames=_frames(24, (0, 0, 255)))),
         "timeline", duration_s=CLIP_S),
    Case("flashing_frames", build_with("flash.mp4", lambda p: write_streams(
        p, frames=_frames(48, "flash"), audio=_noise(2.0))), "timeline", duration_s=2.0),
    Case("one_frame_visual_mode", synth_clip("one_frame.mp4", duration_s=1 / 24, audio=False), "timeline",
         args=("--mode", "visual"), duration_s=1 / 24),
    Case("frames_16x16_visual_mode", synth_clip("tiny.mp4", width=16, height=16), "timeline",
         args=("--mode", "visual"), duration_s=CLIP_S),
    Case("flashing_frames_visual_mode", build_with("flash.mp4", lambda p: write_streams(
        p, frames=_frames(48, "flash"), audio=_noise(2.0))), "timeline", args=("--mode", "visual"), duration_s=2.0),
    Case("audio_only_random_mode", synth_clip("audio_only.wav"), "timeline", args=("--mode", "random"),
         duration_s=CLIP_S, check=_no_video),
    Case("rotated_90_metadata", build_with("rotated.mp4", lambda p: write_streams(
        p, frames=_frames(24), audio=_noise(CLIP_S), rotation=90)), "timeline", duration_s=CLIP_S, check=_rotated),
]


def case(name: str) -> Case:
    for c in CASES:
        if c.name == name:
            return c
    raise KeyError(name)


def long_film(path: Path, *, hours: float = 2.0, width: int = 64, height: int = 36, fps: float = 24) -> Path:
    """A long low-resolution film (synth ``long=True``): cuts every 5 minutes, a moving disc and a
    boom every minute, quiet noise throughout."""
    from autohaptics import testing as synth

    d = hours * 3600.0
    seg_s = 300.0
    colours = [(200, 40, 30), (35, 165, 55), (110, 110, 115), (40, 50, 70)]
    segments = tuple(synth.Segment(t, min(d, t + seg_s), colours[i % 4], texture=synth.Texture("noise", 0.1, 0.3, i))
                     for i, t in enumerate(np.arange(0.0, d, seg_s)))
    shapes = tuple(synth.Shape("circle", (250, 250, 240), t_on=t, t_off=t + 8.0, xy0=(0.2, 0.5), xy1=(0.8, 0.5),
                               size0=(0.1, 0.2), size1=(0.4, 0.7)) for t in np.arange(10.0, d - 10, 60.0))
    audio = (synth.Noise(0.0, d, -35.0, seed=1),) + tuple(
        synth.Tone(t, t + 1.0, 50.0, -12.0) for t in np.arange(12.0, d - 10, 60.0))
    scene = synth.Scene(duration_s=d, background=segments, shapes=shapes, audio=audio, name="long")
    return synth.write_scene(path, scene, width=width, height=height, fps=fps, long=True, quality="low")


# ------------------------------------------------------------------ the worker
class Worker:
    """A long-lived ``autohaptics`` process: each request runs the CLI's ``main(argv)`` with stderr
    captured at the file-descriptor level (FFmpeg's own messages included). A crash of the
    process is reported as such and the next request starts a fresh one."""

    def __init__(self, timeout_s: float = 120.0):
        self.timeout_s = timeout_s
        self.proc: subprocess.Popen | None = None

    def _start(self) -> None:
        env = dict(os.environ, PYTHONFAULTHANDLER="1")
        self.proc = subprocess.Popen([sys.executable, str(Path(__file__).resolve())], stdin=subprocess.PIPE,
                                     stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=env)

    def run(self, argv: list[str]) -> dict:
        """{"rc": exit code, "stderr": text} for ``autohaptics *argv``; on a crash
        {"rc": None, "crash": "signal/exit ...", "stderr": the process's last words}."""
        if self.proc is None or self.proc.poll() is not None:
            self._start()
        with tempfile.NamedTemporaryFile("w+", suffix=".stderr", delete=False) as fh:
            err_path = fh.name
        try:
            self.proc.stdin.write(json.dumps({"argv": argv, "stderr": err_path}) + "\n")
            self.proc.stdin.flush()
            ready, _, _ = select.select([self.proc.stdout], [], [], self.timeout_s)
            line = self.proc.stdout.readline() if ready else ""
            if not line:
                if not ready:
                    self.proc.kill()
                rc = self.proc.wait()
                tail = Path(err_path).read_text(errors="replace")[-4000:] + self.proc.stderr.read()[-4000:]
                self.proc = None
                why = f"no answer within {self.timeout_s:g} s" if not ready else f"process died (exit status {rc})"
                return {"rc": None, "crash": why, "stderr": tail}
            answer = json.loads(line)
            answer["stderr"] = Path(err_path).read_text(errors="replace")
            return answer
        finally:
            Path(err_path).unlink(missing_ok=True)

    def close(self) -> None:
        if self.proc is not None and self.proc.poll() is None:
            self.proc.stdin.close()
            try:
                self.proc.wait(timeout=10)
            except subprocess.TimeoutExpired:
                self.proc.kill()
                self.proc.wait()
        self.proc = None


def _serve() -> None:
    """Worker loop: one JSON request per stdin line -> run the CLI -> one JSON answer per line."""
    from autohaptics.cli.main import main

    out = os.fdopen(os.dup(1), "w")
    for line in sys.stdin:
        req = json.loads(line)
        sys.stdout.flush()
        sys.stderr.flush()
        saved_out, saved_err = os.dup(1), os.dup(2)
        with open(req["stderr"], "w") as err:
            os.dup2(err.fileno(), 2)
            os.dup2(err.fileno(), 1)  # nothing but the answer goes to the answer channel
            try:
                rc = main(req["argv"])
            except SystemExit as exc:  # argparse errors
                rc = exc.code if isinstance(exc.code, int) else 2
            finally:
                sys.stdout.flush()
                sys.stderr.flush()
                os.dup2(saved_out, 1)
                os.dup2(saved_err, 2)
                os.close(saved_out)
                os.close(saved_err)
        out.write(json.dumps({"rc": rc}) + "\n")
        out.flush()


def expected_ticks(duration_s: float) -> int:
    """ceil(duration / 0.1), the tick count every timeline of that duration must have."""
    return max(1, math.ceil(duration_s / 0.1 - 1e-6))


if __name__ == "__main__":
    _serve()
