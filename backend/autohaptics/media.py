"""Media decoding behind one small interface (PyAV / FFmpeg). Stages never touch FFmpeg.

- :func:`probe` -> :class:`MediaInfo` (streams, duration, fps, sample rate, channels).
- :func:`iter_audio` -> float32 mono chunks at 48 kHz, in pascal-free digital full scale
  (calibration to pascal is the loudness stage's parameter). Streaming: memory does not grow
  with the length of the film.
- :func:`iter_video` -> :class:`Frame` handles, one per decoded frame, in presentation order;
  a frame is converted to a small proxy array only when a stage asks for it
  (:meth:`Frame.proxy`), because converting every 1080p frame to RGB costs as much as decoding it.

Downmix (documented decision, ALGORITHM.md section 2): the mono analysis signal is the MEAN of
the main channels (not the sum, so a sound panned everywhere keeps its level) plus the LFE channel
with its cinema playback gain of +10 dB, also divided by the number of main channels:
``mono = (sum(main) + 10**(lfe_gain_db/20) * lfe) / n_main``. Channel roles come from the
stream's layout; a stream with 6 or 8 channels and no layout is read in FFmpeg's default
5.1 (FL FR FC LFE BL BR) or 7.1 (FL FR FC LFE BL BR SL SR) order; any other unlabelled layout
has no LFE. Non-finite samples (NaN, inf in float PCM) are replaced by 0 and counted.
"""

from __future__ import annotations

import math
import os
import queue
import threading
from collections.abc import Iterator
from dataclasses import asdict, dataclass, field, replace
from pathlib import Path

import av
import cv2
import numpy as np

from autohaptics.errors import MediaError, ParameterError
from autohaptics.timebase import ANALYSIS_SAMPLE_RATE

_PLANAR_YUV8 = {"yuv420p", "yuvj420p", "yuv422p", "yuvj422p", "yuv444p", "yuvj444p", "yuv440p", "yuvj440p"}

# Declared vs decoded duration: beyond this shortfall the file is called truncated.
TRUNCATION_TOLERANCE_S = 0.5
TRUNCATION_TOLERANCE_FRAC = 0.02


@dataclass(frozen=True)
class VideoInfo:
    index: int
    width: int
    height: int
    fps: float  # average frame rate, frames per second
    codec: str
    n_frames: int | None  # as declared by the container, None when unknown
    rotation: int  # display rotation in degrees (0, 90, 180, 270), counter-clockwise
    duration_s: float | None

    @property
    def display_size(self) -> tuple[int, int]:
        """(width, height) as shown, after the rotation metadata."""
        return (self.height, self.width) if self.rotation % 180 else (self.width, self.height)


@dataclass(frozen=True)
class AudioInfo:
    index: int
    sample_rate: int  # Hz
    channels: int
    layout: str
    codec: str
    duration_s: float | None


@dataclass(frozen=True)
class MediaInfo:
    path: str
    size_bytes: int
    container: str
    duration_s: float  # seconds, > 0
    start_s: float  # container start time; t = 0 of every analysis is this instant
    video: VideoInfo | None
    audio: AudioInfo | None

    def source_block(self, *, sha256: str | None = None, name: str | None = None) -> dict:
        """The timeline's ``source`` object (TIMELINE.md)."""
        v, a = self.video, self.audio
        return {
            "name": name if name is not None else os.path.basename(self.path),
            "sha256": sha256,
            "duration_s": round(self.duration_s, 6),
            "size_bytes": self.size_bytes,
            "container": self.container,
            "video": None if v is None else {"width": v.width, "height": v.height, "fps": round(v.fps, 6),
                                              "codec": v.codec, "rotation": v.rotation},
            "audio": None if a is None else {"sample_rate": a.sample_rate, "channels": a.channels,
                                              "layout": a.layout, "codec": a.codec},
        }

    def to_dict(self) -> dict:
        return asdict(self)


@dataclass
class AudioReport:
    """What :func:`iter_audio` saw; filled in while iterating."""

    samples_out: int = 0  # mono samples at the analysis rate
    nonfinite_samples: int = 0  # input samples replaced by 0
    decode_errors: int = 0
    first_error: str | None = None
    lfe_channel: int | None = None
    main_channels: list[int] = field(default_factory=list)

    @property
    def duration_s(self) -> float:
        return self.samples_out / ANALYSIS_SAMPLE_RATE


# ------------------------------------------------------------------- probe
def open_container(path: str | os.PathLike) -> av.container.InputContainer:
    """Open a media file, mapping every failure to a MediaError that names the file."""
    p = Path(path)
    if not p.exists():
        raise MediaError(f"{p}: no such file")
    if p.is_dir():
        raise MediaError(f"{p}: is a directory, not a media file")
    if p.stat().st_size == 0:
        raise MediaError(f"{p}: file is empty (0 bytes)")
    try:
        return av.open(str(p), mode="r", metadata_errors="ignore")
    except av.error.FFmpegError as exc:
        raise MediaError(f"{p}: not a readable media file ({_ffmpeg_reason(exc)})") from None
    except (OSError, ValueError, UnicodeDecodeError) as exc:
        raise MediaError(f"{p}: cannot open ({exc})") from None


def probe(path: str | os.PathLike) -> MediaInfo:
    """Streams, duration, frame rate, sample rate and channels of a media file.

    Raises MediaError when the file is missing, not media, has neither audio nor video,
    or has no usable duration.
    """
    p = Path(path)
    with open_container(p) as c:
        undecodable = [f"{s.type} stream #{s.index} ({_codec_name(s)})" for s in c.streams
                       if s.type in ("video", "audio") and s.codec_context is None]
        vs = next((s for s in c.streams.video if s.codec_context is not None and _is_real_video(s)), None)
        as_ = next((s for s in c.streams.audio if s.codec_context is not None), None)
        video = _video_info(vs) if vs is not None else None
        audio = _audio_info(as_) if as_ is not None else None
        if undecodable and ((video is None and any(u.startswith("video") for u in undecodable))
                            or (audio is None and any(u.startswith("audio") for u in undecodable))):
            raise MediaError(f"{p}: unsupported codec: no decoder for {', '.join(undecodable)}")
        if video is None and audio is None:
            raise MediaError(f"{p}: no audio or video stream (container {c.format.name})")
        if audio is not None and (audio.sample_rate <= 0 or audio.channels <= 0):
            raise MediaError(f"{p}: audio stream #{audio.index} ({audio.codec}) declares no sample rate or channels")
        start_s = _container_start(c)
        duration = _duration_s(c, [s for s in (vs, as_) if s is not None])
        if duration is None:
            duration = _scan_duration(c, [s for s in (vs, as_) if s is not None], start_s)
        if duration is None or not math.isfinite(duration) or duration <= 0:
            raise MediaError(f"{p}: zero-length media (no decodable duration)")
        if video is not None:
            c.seek(0)
            video = replace(video, rotation=_first_frame_rotation(c, vs))
        return MediaInfo(path=str(p), size_bytes=p.stat().st_size, container=c.format.name,
                         duration_s=float(duration), start_s=start_s, video=video, audio=audio)


# ------------------------------------------------------------------- audio
def iter_audio(path: str | os.PathLike, *, info: MediaInfo | None = None, lfe_gain_db: float = 10.0,
               chunk_s: float = 2.0, report: AudioReport | None = None) -> Iterator[np.ndarray]:
    """Decode the first audio stream as float32 mono chunks at 48 kHz (digital full scale).

    Time 0 is the container start (``info.start_s``): leading gaps are zero-filled so audio
    stays aligned with the picture. ``chunk_s`` bounds the chunk length (seconds); memory is
    constant in the film length. Raises MediaError when there is no audio stream or nothing
    decodes; a decode error in the middle of a file is counted in ``report`` and skipped.
    """
    info = info or probe(path)
    if info.audio is None:
        raise MediaError(f"{info.path}: no audio stream")
    report = report if report is not None else AudioReport()
    sr_in = info.audio.sample_rate
    resampler = None
    if sr_in != ANALYSIS_SAMPLE_RATE:
        resampler = av.AudioResampler(format="flt", layout="mono", rate=ANALYSIS_SAMPLE_RATE)
    chunk_n = max(1, int(chunk_s * ANALYSIS_SAMPLE_RATE))
    pending: list[np.ndarray] = []
    pending_n = 0
    next_t_in = 0.0  # seconds (relative to start) of the next expected input sample
    lfe_gain = 10.0 ** (lfe_gain_db / 20.0)

    def emit(x: np.ndarray):
        nonlocal pending_n
        if x.size:
            pending.append(x)
            pending_n += x.size

    def drain(final: bool):
        nonlocal pending, pending_n
        while pending_n >= chunk_n or (final and pending_n):
            buf = np.concatenate(pending) if len(pending) > 1 else pending[0]
            out, rest = buf[:chunk_n], buf[chunk_n:]
            pending = [rest] if rest.size else []
            pending_n = rest.size
            report.samples_out += out.size
            yield out.astype(np.float32, copy=False)

    def to_out_rate(mono: np.ndarray) -> np.ndarray:
        if resampler is None or mono.size == 0:
            return mono
        frame = av.AudioFrame.from_ndarray(mono[None, :], format="flt", layout="mono")
        frame.sample_rate = sr_in
        return _frames_to_array(resampler.resample(frame))

    with open_container(info.path) as c:
        stream = c.streams.audio[0]
        stream.thread_type = "AUTO"
        mapping = None
        interleave = _Interleaver()
        for frame in _decode_tolerant(c, stream, report, info.path):
            frame_time = frame.time
            x = _to_float(_samples(frame, interleave))
            if mapping is None:
                mapping = _channel_roles(frame.layout, x.shape[0])
                report.main_channels, report.lfe_channel = mapping
            bad = ~np.isfinite(x)
            if bad.any():
                report.nonfinite_samples += int(bad.sum())
                x = np.where(bad, 0.0, x)
            main, lfe = mapping
            mono = x[main].sum(axis=0, dtype=np.float64)
            if lfe is not None:
                mono += lfe_gain * x[lfe]
            mono = (mono / max(1, len(main))).astype(np.float32)
            # Align to the container clock: zero-fill gaps (and the lead-in), drop overlaps.
            if frame_time is not None:
                t0 = float(frame_time) - info.start_s
                gap = t0 - next_t_in
                if gap > 1.0 / sr_in * 2:
                    emit(to_out_rate(np.zeros(int(round(gap * sr_in)), np.float32)))
                    next_t_in += round(gap * sr_in) / sr_in
                elif gap < -1.0 / sr_in * 2:
                    drop = min(mono.size, int(round(-gap * sr_in)))
                    mono = mono[drop:]
            next_t_in += mono.size / sr_in
            emit(to_out_rate(mono))
            yield from drain(False)
        if resampler is not None:
            emit(_frames_to_array(resampler.resample(None)))
        yield from drain(True)
    if report.samples_out == 0:
        reason = f" ({report.first_error})" if report.first_error else ""
        raise MediaError(f"{info.path}: the audio stream holds no decodable samples{reason}")


def read_audio(path: str | os.PathLike, **kwargs) -> np.ndarray:
    """The whole mono 48 kHz track as one float32 array (tests and short clips only)."""
    chunks = list(iter_audio(path, **kwargs))
    return np.concatenate(chunks) if chunks else np.zeros(0, np.float32)


# ------------------------------------------------------------------- video
class Frame:
    """One decoded picture. Valid only inside the iteration step that yielded it."""

    __slots__ = ("_frame", "index", "time_s", "rotation", "width", "height")

    def __init__(self, frame: av.VideoFrame, index: int, time_s: float, rotation: int):
        self._frame = frame
        self.index = index  # decoded frame number, 0-based
        self.time_s = time_s  # presentation time relative to the container start, seconds
        self.rotation = rotation
        self.width, self.height = (frame.height, frame.width) if rotation % 180 else (frame.width, frame.height)

    def _size(self, width: int, height: int | None) -> tuple[int, int]:
        width = max(1, int(width))
        if height is None:
            height = max(1, int(round(width * self.height / max(1, self.width))))
        return width, max(1, int(height))

    def proxy(self, width: int, height: int | None = None, *, fmt: str = "rgb24",
              interpolation: str = "AREA") -> np.ndarray:
        """Scaled, colour-converted copy in display orientation.

        width, height : proxy size in pixels (height defaults to keep the display aspect).
        fmt : "rgb24" -> uint8 [shape=(h, w, 3)]; "gray" -> uint8 [shape=(h, w)] (luma).

        For 8-bit planar YUV smaller than the frame (nearly every film) the planes are area-averaged
        in place by OpenCV and converted on the small proxy (BT.709 matrix for BT.709-tagged
        frames, BT.601 otherwise, as FFmpeg's scaler does): about 3x cheaper than FFmpeg's
        scaled conversion of the full frame, within about 2 grey levels of it.
        """
        width, height = self._size(width, height)
        planes = self._planes_small(width, height, colour=fmt == "rgb24") if fmt in ("rgb24", "gray") else None
        if planes is not None:
            return _yuv_to_rgb(*planes, self._frame) if fmt == "rgb24" else _luma_full_range(planes[0], self._frame)
        w, h = (height, width) if self.rotation % 180 else (width, height)
        arr = self._frame.to_ndarray(width=max(1, w), height=max(1, h), format=fmt,
                                     interpolation=interpolation)
        if self.rotation:
            arr = np.ascontiguousarray(np.rot90(arr, k=self.rotation // 90))
        return arr

    def gray(self, width: int) -> np.ndarray:
        """Luma proxy ``width`` px wide (aspect kept), uint8 [shape=(h, w)], display orientation."""
        return self.proxy(width, fmt="gray")

    def rgb_and_gray(self, width: int, gray_width: int, *, luma_size: tuple[int, int] | None = None):
        """An RGB proxy ``width`` px wide and a luma proxy ``gray_width`` px wide from ONE read of
        the luma plane (reading a 1080p plane costs more than everything done to the proxy).

        The luma proxy is bit-identical to :meth:`gray` (optical flow compares it with the next
        frame's :meth:`gray`); the RGB proxy's luma is resampled from it.
        luma_size : (w, h) px: also return the luma area-averaged to exactly that size (aspect not
            kept) from the full-resolution plane in the same read, whatever the proxies' sizes;
            the third item of the result (uint8 [shape=(h, w)], full range, display orientation).
        Returns (rgb, gray) or, with ``luma_size``, (rgb, gray, luma).
        """
        gw, gh = self._size(gray_width, None)
        rw, rh = self._size(width, None)
        grid: list = []
        ys = self._planes_small(gw, gh, colour=False, grid=luma_size, grid_out=grid)
        chroma = self._planes_small(rw, rh, colour=True, luma=False) if ys is not None else None
        if ys is None or chroma is None:
            rgb, gray = self.proxy(width), self.gray(gray_width)
            if luma_size is None:
                return rgb, gray
            return rgb, gray, self.luma_grid(luma_size)
        y_raw = ys[0]
        y_rgb = y_raw if (gw, gh) == (rw, rh) else cv2.resize(
            y_raw, (rw, rh), interpolation=cv2.INTER_AREA if rw < gw else cv2.INTER_LINEAR)
        rgb, gray = _yuv_to_rgb(y_rgb, chroma[1], chroma[2], self._frame), _luma_full_range(y_raw, self._frame)
        if luma_size is None:
            return rgb, gray
        return rgb, gray, _luma_full_range(grid[0], self._frame)

    def luma_grid(self, size: tuple[int, int]) -> np.ndarray:
        """The luma area-averaged to exactly ``size`` (w, h) px from the full frame (aspect not
        kept), full range, display orientation: uint8 [shape=(h, w)]."""
        full = self.proxy(self.width, self.height, fmt="gray")
        return _area_resize(full, (max(1, int(size[0])), max(1, int(size[1]))))

    def full(self, *, fmt: str = "rgb24") -> np.ndarray:
        """Full-resolution copy in display orientation (the reference preset)."""
        return self.proxy(self.width, self.height, fmt=fmt)

    def _planes_small(self, width: int, height: int, *, colour: bool, luma: bool = True,
                      grid: tuple[int, int] | None = None, grid_out: list | None = None):
        """(Y, U, V) area-averaged to (height, width) in display orientation, uint8 (None for a
        plane not asked for); None when the pixel format has no fast path or the proxy is not
        smaller than the frame. ``grid`` (w, h): the luma is also area-averaged to that size
        (display orientation, limited range as stored) and appended to ``grid_out``."""
        f = self._frame
        name = f.format.name
        if name not in _PLANAR_YUV8 or width >= self.width or height >= self.height:
            return None
        k = self.rotation // 90
        dw, dh = (height, width) if k % 2 else (width, height)  # target (w, h) before rotation
        out = []
        for i in range(3 if colour else 1):
            if i == 0 and not luma:
                out.append(None)
                continue
            plane = f.planes[i]
            ph, pw = plane.height, plane.width
            arr = np.frombuffer(plane, np.uint8).reshape(-1, plane.line_size)[:ph, :pw]
            if i == 0 and pw >= 4 * dw and ph >= 4 * dh:
                # 4x or more: average 2 x 2 blocks first (cv2.pyrDown-like), then area-scale: half
                # the memory traffic of one big area pass, the same proxy within a grey level
                arr = cv2.resize(arr, (pw // 2, ph // 2), interpolation=cv2.INTER_AREA)
            if i == 0:
                small = _shrink(arr, (dw, dh))
                if grid is not None and grid_out is not None:
                    gw_, gh_ = (int(grid[1]), int(grid[0])) if k % 2 else (int(grid[0]), int(grid[1]))
                    g = _area_resize(arr, (gw_, gh_))
                    grid_out.append(np.ascontiguousarray(np.rot90(g, k=k)) if k else g)
            else:  # chroma: average at its own (sub-sampled) scale, then up to the luma size
                cw = max(1, round(dw * pw / f.width))
                ch = max(1, round(dh * ph / f.height))
                small = _shrink(arr, (cw, ch))
                if (cw, ch) != (dw, dh):
                    small = cv2.resize(small, (dw, dh), interpolation=cv2.INTER_LINEAR)
            out.append(np.ascontiguousarray(np.rot90(small, k=k)) if k else small)
        return out if colour else (out[0], None, None)


def _shrink(arr: np.ndarray, size: tuple[int, int]) -> np.ndarray:
    """Area-scale uint8 ``arr`` to ``size`` (w, h) for a proxy: halve by 2 x 2 averaging while 4x or
    more remains on both axes, then :func:`_area_resize`. A pyramid, not one exact area pass: on
    1080p luma 960x540 -> 128x72 costs 0.4 instead of 1.2 ms (OpenCV's fractional-ratio area);
    measured on 1080p frames, up to about 5 grey levels off the exact area average, at edges."""
    w, h = int(size[0]), int(size[1])
    while arr.shape[1] >= 4 * w and arr.shape[0] >= 4 * h:
        arr = cv2.resize(arr, (arr.shape[1] // 2, arr.shape[0] // 2), interpolation=cv2.INTER_AREA)
    return _area_resize(arr, (w, h))


def _area_resize(arr: np.ndarray, size: tuple[int, int]) -> np.ndarray:
    """Area-average uint8 ``arr`` to ``size`` (w, h). OpenCV's area resize has a fast path for whole
    ratios only; a downscale with a fractional ratio (960x540 -> 64x64: 15 x 8.44) runs one axis
    at a time instead (measured on 1080p frames: 0.25 instead of 1.2-1.4 ms, within a grey level
    of the one-pass result). An upscale falls back to bilinear."""
    w, h = int(size[0]), int(size[1])
    ah, aw = arr.shape[:2]
    if w > aw or h > ah:
        return cv2.resize(arr, (w, h), interpolation=cv2.INTER_LINEAR if (w > aw and h > ah) else cv2.INTER_AREA)
    if aw % w == 0 and ah % h == 0:
        return cv2.resize(arr, (w, h), interpolation=cv2.INTER_AREA)
    return cv2.resize(cv2.resize(arr, (w, ah), interpolation=cv2.INTER_AREA), (w, h), interpolation=cv2.INTER_AREA)


def _full_range(frame: av.VideoFrame) -> bool:
    return frame.format.name.startswith("yuvj") or getattr(frame, "color_range", 0) == 2


def _luma_full_range(y: np.ndarray, frame: av.VideoFrame) -> np.ndarray:
    """Limited-range luma 16..235 -> 0..255, as FFmpeg's gray conversion does."""
    if _full_range(frame):
        return y
    return cv2.convertScaleAbs(y, alpha=255.0 / 219.0, beta=-16.0 * 255.0 / 219.0)


def _yuv_to_rgb(y: np.ndarray, u: np.ndarray, v: np.ndarray, frame: av.VideoFrame) -> np.ndarray:
    kr, kb = (0.2126, 0.0722) if getattr(frame, "colorspace", 0) == 1 else (0.299, 0.114)
    kg = 1.0 - kr - kb
    if _full_range(frame):
        yy = y.astype(np.float32)
        cb = u.astype(np.float32) - 128.0
        cr = v.astype(np.float32) - 128.0
    else:
        yy = (y.astype(np.float32) - 16.0) * (255.0 / 219.0)
        cb = (u.astype(np.float32) - 128.0) * (255.0 / 224.0)
        cr = (v.astype(np.float32) - 128.0) * (255.0 / 224.0)
    rgb = np.empty(y.shape + (3,), np.float32)
    rgb[..., 0] = yy + (2.0 * (1.0 - kr)) * cr
    rgb[..., 1] = yy - (2.0 * kb * (1.0 - kb) / kg) * cb - (2.0 * kr * (1.0 - kr) / kg) * cr
    rgb[..., 2] = yy + (2.0 * (1.0 - kb)) * cb
    return np.clip(rgb + 0.5, 0.0, 255.0).astype(np.uint8)


DECODE_MODES = ("full", "nonref", "fast", "sparse")
# "sparse" skips every B-frame (reference or not) only from this frame rate up: with an encoder's
# usual 3 B-frames per reference frame the I/P-frames alone still come at 10 fps or more there,
# one per 100 ms tick; below it "sparse" decodes like "fast".
SPARSE_MIN_FPS = 40.0


def iter_video(path: str | os.PathLike, *, info: MediaInfo | None = None, prefetch: int = 0,
               decode: str = "full") -> Iterator[Frame]:
    """Decode the video stream frame by frame (presentation order); nothing is converted here.

    decode : "full" decodes every frame exactly; "nonref" asks FFmpeg to skip non-reference
        frames (in H.264/HEVC typically the B-frames: about half the frames; formats without them,
        such as VP8 or intra-only video, decode every frame), the others exactly; "fast" also
        skips the in-loop deblocking filter (invisible on small proxies, not decoded exactly);
        "sparse" (the fast preset) also skips the reference B-frames at ``SPARSE_MIN_FPS`` and
        above (H.264 B-pyramids; only I- and P-frames are decoded, about a quarter of the frames at
        60 fps): a P-frame that used a skipped B-frame as reference comes out approximate (the
        decoder conceals the missing reference; measured on the shared 1080p60 BBB clip: mean 3,
        at most 5.6 grey levels off the exact frame).
        The frames that come out keep their true timestamps.
    prefetch : when > 0, decode in a background thread up to this many frames ahead, so FFmpeg's
        decoder threads keep working while the caller analyses a frame (PyAV releases the GIL
        while decoding). Frames stay valid after the step that yielded them in this mode.
    Raises MediaError when there is no video stream or no frame decodes.
    """
    info = info or probe(path)
    if info.video is None:
        raise MediaError(f"{info.path}: no video stream")
    if decode not in DECODE_MODES:
        raise ParameterError(f"decode must be one of {DECODE_MODES}, got {decode!r}")
    if prefetch > 0:
        yield from _prefetched(lambda: _iter_video(info, decode), prefetch)
    else:
        yield from _iter_video(info, decode)


def _iter_video(info: MediaInfo, decode: str = "full") -> Iterator[Frame]:
    report = AudioReport()
    n = 0
    with open_container(info.path) as c:
        stream = _stream_by_index(c, info.video.index)
        stream.thread_type = "AUTO"
        if decode in ("nonref", "fast", "sparse"):
            sparse = decode == "sparse" and info.video.fps >= SPARSE_MIN_FPS
            stream.codec_context.skip_frame = "BIDIR" if sparse else "NONREF"
            if sparse:
                # a chain of P-frames gains nothing from frame threads (each waits for the one
                # before; measured: 2.49 s, one thread 2.42 s); slice threads do where the encoder
                # cut frames into slices (1.52 s on the 30 s 1080p BBB loop) and cost nothing where not
                stream.thread_type = "SLICE"
        if decode in ("fast", "sparse"):
            stream.codec_context.options = {"skip_loop_filter": "all"}
        last_t = -math.inf
        for frame in _decode_tolerant(c, stream, report, info.path):
            t = float(frame.time) - info.start_s if frame.time is not None else n / max(info.video.fps, 1e-9)
            if t <= last_t:  # broken timestamps: keep frames ordered
                t = last_t + 1.0 / max(info.video.fps, 1e-9)
            last_t = t
            yield Frame(frame, n, t, _norm_rotation(getattr(frame, "rotation", info.video.rotation)))
            n += 1
    if n == 0:
        reason = f" ({report.first_error})" if report.first_error else ""
        raise MediaError(f"{info.path}: the video stream holds no decodable frames{reason}")


_END = object()


def _prefetched(make_iter, depth: int) -> Iterator:
    """Run an iterator in a daemon thread, ``depth`` items ahead; exceptions reach the consumer;
    closing the consumer stops the producer."""
    q: queue.Queue = queue.Queue(maxsize=depth)
    stop = threading.Event()

    def produce():
        try:
            for item in make_iter():
                while not stop.is_set():
                    try:
                        q.put(item, timeout=0.1)
                        break
                    except queue.Full:
                        continue
                if stop.is_set():
                    return
            q.put(_END)
        except BaseException as exc:  # handed to the consumer, re-raised there
            q.put(exc)

    worker = threading.Thread(target=produce, name="autohaptics-decode", daemon=True)
    worker.start()
    try:
        while True:
            item = q.get()
            if item is _END:
                return
            if isinstance(item, BaseException):
                raise item
            yield item
    finally:
        stop.set()
        while worker.is_alive():
            try:
                q.get(timeout=0.05)
            except queue.Empty:
                pass
        worker.join()


def decode_all(path: str | os.PathLike, *, info: MediaInfo | None = None) -> dict:
    """Bare decode of every audio and video frame, nothing converted: the speed baseline.

    Returns {"video_frames": int, "audio_samples": int}.
    """
    info = info or probe(path)
    counts = {"video_frames": 0, "audio_samples": 0}
    with open_container(info.path) as c:
        streams = []
        if info.video is not None:
            vs = _stream_by_index(c, info.video.index)
            vs.thread_type = "AUTO"
            streams.append(vs)
        if info.audio is not None:
            as_ = _stream_by_index(c, info.audio.index)
            as_.thread_type = "AUTO"
            streams.append(as_)
        report = AudioReport()
        for frame in _decode_tolerant(c, streams, report, info.path):
            if isinstance(frame, av.VideoFrame):
                counts["video_frames"] += 1
            else:
                counts["audio_samples"] += frame.samples
    return counts


def check_truncation(info: MediaInfo, decoded_s: float, stream: str) -> None:
    """Raise MediaError when a stream decodes to clearly less than the declared duration."""
    declared = info.duration_s
    missing = declared - decoded_s
    if missing > max(TRUNCATION_TOLERANCE_S, TRUNCATION_TOLERANCE_FRAC * declared):
        what = f"the {stream} streams decode" if " and " in stream else f"the {stream} stream decodes"
        raise MediaError(
            f"{info.path}: truncated or damaged file: {what} {decoded_s:.2f} s "
            f"of the {declared:.2f} s the container declares")


def check_complete(info: MediaInfo) -> None:
    """Raise MediaError when the file's packets end clearly before its declared duration.

    Demuxes every packet of the audio and video streams once, without decoding (cheap: a few
    ms per minute of film), and applies :func:`check_truncation` to the last packet's end time.
    """
    indices = {s.index for s in (info.video, info.audio) if s is not None}
    end = None
    with open_container(info.path) as c:
        streams = [s for s in c.streams if s.index in indices]
        try:
            for pkt in c.demux(*streams):
                if pkt.pts is None or pkt.time_base is None:
                    continue
                t = float((pkt.pts + (pkt.duration or 0)) * pkt.time_base)
                end = t if end is None else max(end, t)
        except av.error.FFmpegError as exc:
            raise MediaError(f"{info.path}: damaged file, reading stops at "
                             f"{0.0 if end is None else end - info.start_s:.2f} s ({_ffmpeg_reason(exc)})") from None
    if end is None:
        raise MediaError(f"{info.path}: no audio or video packets")
    check_truncation(info, end - info.start_s, "video" if info.video is not None else "audio")


# ------------------------------------------------------------------- private
def _stream_by_index(c, index: int):
    for s in c.streams:
        if s.index == index:
            return s
    raise MediaError(f"stream #{index} vanished")


def _codec_name(s) -> str:
    for attr in ("codec_tag", "name"):
        try:
            value = getattr(s, attr, None) if attr == "codec_tag" else s.codec.name
            if value:
                return str(value)
        except (AttributeError, ValueError):
            continue
    return "unknown codec"


def _is_real_video(s) -> bool:
    # Cover art (attached pictures) is a video stream with one frame; it is not the film.
    disposition = getattr(s, "disposition", None)
    try:
        if disposition is not None and (int(disposition) & int(av.stream.Disposition.attached_pic)):
            return False
    except (AttributeError, TypeError, ValueError):
        pass
    return s.codec_context.width > 0 and s.codec_context.height > 0


def _video_info(s) -> VideoInfo:
    cc = s.codec_context
    rate = s.average_rate or s.guessed_rate or s.base_rate
    fps = float(rate) if rate else 0.0
    dur = float(s.duration * s.time_base) if s.duration and s.time_base else None
    if (not fps or not math.isfinite(fps) or fps <= 0 or fps > 1000) and s.frames and dur:
        fps = s.frames / dur
    if not fps or not math.isfinite(fps) or fps <= 0:
        fps = 25.0
    return VideoInfo(index=s.index, width=cc.width, height=cc.height, fps=fps, codec=cc.name,
                     n_frames=int(s.frames) if s.frames else None, rotation=0, duration_s=dur)


def _first_frame_rotation(c, s) -> int:
    """Display rotation (degrees counter-clockwise, 0/90/180/270) read from the first decoded frame."""
    try:
        for frame in c.decode(s):
            return _norm_rotation(getattr(frame, "rotation", 0))
    except av.error.FFmpegError:
        return 0
    return 0


def _norm_rotation(deg) -> int:
    try:
        return int(round(float(deg or 0) / 90.0)) % 4 * 90
    except (TypeError, ValueError):
        return 0


def _audio_info(s) -> AudioInfo:
    cc = s.codec_context
    dur = float(s.duration * s.time_base) if s.duration and s.time_base else None
    layout = cc.layout
    return AudioInfo(index=s.index, sample_rate=int(cc.sample_rate or 0), channels=int(layout.nb_channels),
                     layout=str(layout.name), codec=cc.name, duration_s=dur)


def _container_start(c) -> float:
    if c.start_time is not None:
        try:
            return max(0.0, float(c.start_time) / av.time_base)
        except (TypeError, OverflowError):
            return 0.0
    return 0.0


def _duration_s(c, streams) -> float | None:
    if c.duration is not None and c.duration > 0:
        return float(c.duration) / av.time_base
    durs = [float(s.duration * s.time_base) for s in streams if s.duration and s.time_base]
    return max(durs) if durs else None


def _scan_duration(c, streams, start_s: float) -> float | None:
    """Last packet end time, read by demuxing only (no decoding)."""
    end = None
    try:
        for pkt in c.demux(*streams):
            if pkt.pts is None or pkt.time_base is None:
                continue
            t = float(pkt.pts * pkt.time_base) + float((pkt.duration or 0) * pkt.time_base)
            end = t if end is None else max(end, t)
    except av.error.FFmpegError:
        pass
    return None if end is None else end - start_s


def _decode_tolerant(c, streams, report: AudioReport, path: str):
    """Decode packets of ``streams``; a damaged packet is counted and skipped, never fatal here."""
    try:
        packets = c.demux(streams)
        while True:
            try:
                pkt = next(packets)
            except StopIteration:
                break
            except av.error.FFmpegError as exc:
                report.decode_errors += 1
                report.first_error = report.first_error or _ffmpeg_reason(exc)
                break  # the demuxer cannot go on after a read error
            try:
                frames = pkt.decode()
            except av.error.FFmpegError as exc:
                report.decode_errors += 1
                report.first_error = report.first_error or _ffmpeg_reason(exc)
                if report.decode_errors > 1000:
                    raise MediaError(f"{path}: undecodable stream ({report.first_error})") from None
                continue
            yield from frames
    except av.error.FFmpegError as exc:
        raise MediaError(f"{path}: cannot decode ({_ffmpeg_reason(exc)})") from None


def _ffmpeg_reason(exc: Exception) -> str:
    msg = getattr(exc, "strerror", None) or str(exc)
    return str(msg).split(":")[-1].strip() or type(exc).__name__


_SAMPLE_DTYPES = {"u8": np.uint8, "s16": np.int16, "s32": np.int32, "s64": np.int64, "flt": np.float32,
                  "dbl": np.float64}


_PACKABLE_LAYOUTS = {"3.0", "quad", "4.0", "5.0", "5.1", "5.0(side)", "5.1(side)", "6.0", "6.1", "7.0", "7.1",
                     "7.1(wide)", "7.1(wide-side)", "octagonal", "hexagonal"}


class _Interleaver:
    """Planar -> packed float at the same rate and layout, through one libswresample context
    (same-rate format conversion holds no samples back)."""

    def __init__(self):
        self.key = None
        self.resampler = None

    def __call__(self, frame: av.AudioFrame) -> av.AudioFrame:
        key = (frame.layout.name, frame.sample_rate)
        if key != self.key:
            self.key = key
            self.resampler = av.AudioResampler(format="flt", layout=frame.layout.name, rate=frame.sample_rate)
        frame.pts = None
        return _join_packed(self.resampler.resample(frame), frame)


def _join_packed(out: list, frame: av.AudioFrame) -> av.AudioFrame:
    if len(out) == 1:
        return out[0]
    if not out:
        packed = av.AudioFrame(format="flt", layout=frame.layout.name, samples=0)
        packed.sample_rate = frame.sample_rate
        return packed
    data = np.concatenate([np.frombuffer(f.planes[0], np.float32, count=f.samples * f.layout.nb_channels)
                           for f in out])
    packed = av.AudioFrame.from_ndarray(data.reshape(1, -1), format="flt", layout=frame.layout.name)
    packed.sample_rate = frame.sample_rate
    return packed


def _samples(frame: av.AudioFrame, interleave: "_Interleaver | None" = None) -> np.ndarray:
    """Decoded samples as [shape=(channels, n)], read straight from the frame's planes.

    (PyAV's ``to_ndarray`` crashes the interpreter on 8-channel planar frames; the planes'
    buffers are read here with numpy instead.)
    """
    if frame.format.is_planar and frame.layout.nb_channels > 2 and frame.layout.name in _PACKABLE_LAYOUTS:
        # Many-channel planar frames: PyAV's plane accessors read past AVFrame.data (8 pointers)
        # for such layouts; let libswresample interleave them first (same rate, same layout).
        frame = (interleave or _Interleaver())(frame)
    name = frame.format.name
    base = name[:-1] if name.endswith("p") else name
    dtype = _SAMPLE_DTYPES.get(base)
    nch = frame.layout.nb_channels
    n = frame.samples
    if dtype is None:
        raise MediaError(f"unsupported audio sample format {name!r}")
    if frame.format.is_planar:
        return np.stack([np.frombuffer(frame.planes[i], dtype=dtype, count=n) for i in range(nch)])
    return np.frombuffer(frame.planes[0], dtype=dtype, count=n * nch).reshape(n, nch).T


def _to_float(x: np.ndarray) -> np.ndarray:
    """Decoded samples (any sample format) -> float64 in digital full scale."""
    if x.dtype.kind == "f":
        return x.astype(np.float64, copy=False)
    if x.dtype == np.uint8:
        return (x.astype(np.float64) - 128.0) / 128.0
    info = np.iinfo(x.dtype)
    return x.astype(np.float64) / float(-info.min)


# FFmpeg channel names for the LFE channel.
_LFE_NAMES = {"LFE", "LFE2", "LOW_FREQUENCY", "LOW_FREQUENCY_2"}


def _channel_roles(layout, n: int) -> tuple[list[int], int | None]:
    """(main channel indices, LFE index or None) for a decoded layout of ``n`` channels."""
    names = [ch.name for ch in layout.channels][:n]
    known = [nm for nm in names if nm and nm.upper() not in ("NONE", "NA", "UNKNOWN", "UNUSED")]
    if len(known) == n:
        lfe = [i for i, nm in enumerate(names) if nm.upper() in _LFE_NAMES]
    elif n in (6, 8):
        lfe = [3]  # FFmpeg's default 5.1 / 7.1 order: FL FR FC LFE ...
    else:
        lfe = []
    lfe_idx = lfe[0] if lfe else None
    main = [i for i in range(n) if i != lfe_idx]
    if not main:  # a lone LFE channel is the whole signal
        return [lfe_idx], None
    return main, lfe_idx


def _frames_to_array(frames) -> np.ndarray:
    if not frames:
        return np.zeros(0, np.float32)
    parts = [f.to_ndarray().reshape(-1) for f in frames]
    return np.concatenate(parts).astype(np.float32, copy=False)
