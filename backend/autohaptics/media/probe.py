"""Media files behind one small interface (PyAV / FFmpeg): what a file holds, and its packets decoded
tolerantly. Stages never touch FFmpeg.

:func:`probe` -> :class:`MediaInfo` (streams, duration, frame rate, sample rate, channels); a
missing, empty, non-media or stream-less file is a MediaError that names it. A damaged packet is
counted in an :class:`AudioReport` and skipped; a file that decodes clearly shorter than it
declares is truncated (:func:`check_truncation`).
"""

from __future__ import annotations

import math
import os
from dataclasses import asdict, dataclass, field, replace
from pathlib import Path

import av

from autohaptics.errors import MediaError
from autohaptics.media.clock import TRANSPORT_FORMATS, Clock, read_clock
from autohaptics.media.programs import film_programme
from autohaptics.media.stereo import declared_packing
from autohaptics.media.tracks import channel_tracks, sound_stream
from autohaptics.timebase import ANALYSIS_SAMPLE_RATE

# Declared vs decoded duration: beyond this shortfall the file is called truncated.
TRUNCATION_TOLERANCE_S = 0.5
TRUNCATION_TOLERANCE_FRAC = 0.02
VARIABLE_RATE_SHARE = 0.9  # an average frame rate under this share of the stream's own: frames come irregularly
RATE_PACKETS = 48  # the packets whose intervals tell a stream's own frame rate
# how far FFmpeg reads for a stream it found nothing of in its first look (a file is opened so only where every
# audio or every video stream is undetermined, ``_look_further``): 10 minutes, 1 GB
LATE_STREAM_PROBE = {"analyzeduration": str(600 * 1_000_000), "probesize": str(1 << 30)}


def source_block(info: dict, *, sha256: str | None = None, name: str | None = None) -> dict:
    """The timeline's ``source`` object (TIMELINE.md) from a :meth:`MediaInfo.to_dict` form."""
    v, a = info.get("video"), info.get("audio")
    return {
        "name": name if name is not None else os.path.basename(info["path"]), "sha256": sha256,
        "duration_s": round(info["duration_s"], 6), "size_bytes": info.get("size_bytes"),
        "container": info.get("container"),
        "video": None if v is None else {"width": v["width"], "height": v["height"], "fps": round(v["fps"], 6),
                                          "codec": v["codec"], "rotation": v.get("rotation", 0)},
        "audio": None if a is None else {"sample_rate": a["sample_rate"], "channels": a["channels"],
                                          "layout": a["layout"], "codec": a["codec"]},
    }


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
    # frames come irregularly: the average rate under VARIABLE_RATE_SHARE of the stream's own (a
    # phone's or screen recorder's stream, a conversion that drops frames)
    variable_rate: bool = False
    # a stored pixel's width over its height on screen (an anamorphic 16:9 PAL DVD's 720 x 576: 64/45);
    # 1 where the file says nothing (or something outside 0.1..10)
    pixel_aspect: float = 1.0
    # the 3D packing the file declares ("side_by_side", "top_bottom"; "" none: ``media.stereo``)
    stereo: str = ""

    @property
    def display_size(self) -> tuple[int, int]:
        """(width, height) in pixels as shown, after the rotation metadata (the pixels' aspect aside)."""
        return (self.height, self.width) if self.rotation % 180 else (self.width, self.height)

    def shown_aspect(self, width: float | None = None, height: float | None = None) -> float:
        """Width over height on screen of ``width`` x ``height`` px of the picture in display
        orientation (default: the whole frame), its pixels' aspect applied along the stored rows."""
        w, h = self.display_size if width is None or height is None else (width, height)
        stretch = 1.0 / self.pixel_aspect if self.rotation % 180 else self.pixel_aspect
        return float(w) * stretch / max(float(h), 1e-9)


@dataclass(frozen=True)
class AudioInfo:
    index: int
    sample_rate: int  # Hz
    channels: int
    layout: str  # FFmpeg's name of the channel layout ("5.1", "stereo", "6 channels" when unlabelled)
    codec: str
    duration_s: float | None
    # A master that keeps each channel in its own mono track: the streams read as the channels of one
    # sound, in ``layout``'s order (``index`` first); empty for one stream (``media.tracks.channel_tracks``).
    tracks: tuple[int, ...] = ()

    @property
    def streams(self) -> tuple[int, ...]:
        """The indices of the streams the sound is read from."""
        return self.tracks or (self.index,)


@dataclass(frozen=True)
class MediaInfo:
    path: str
    size_bytes: int
    container: str
    duration_s: float  # seconds, > 0
    start_s: float  # container start time; t = 0 of every analysis is this instant
    video: VideoInfo | None
    audio: AudioInfo | None
    # a transport stream's clock (``media.clock``): its jumps, its keyframes; None for other containers
    clock: Clock | None = None

    def source_block(self, *, sha256: str | None = None, name: str | None = None) -> dict:
        """The timeline's ``source`` object (TIMELINE.md)."""
        return source_block(self.to_dict(), sha256=sha256, name=name)

    def to_dict(self) -> dict:
        out = asdict(replace(self, clock=None))
        del out["clock"]
        if self.clock is not None and self.clock.jump_positions:
            out["clock"] = self.clock.to_dict()
        return out


@dataclass
class AudioReport:
    """What :func:`iter_audio` saw; filled in while iterating."""

    samples_out: int = 0  # mono samples at the analysis rate
    nonfinite_samples: int = 0  # input samples replaced by 0
    decode_errors: int = 0
    first_error: str | None = None
    lfe_channel: int | None = None
    main_channels: list[int] = field(default_factory=list)
    downmix_weights: list[float] = field(default_factory=list)  # each channel's weight in the mono signal

    @property
    def duration_s(self) -> float:
        return self.samples_out / ANALYSIS_SAMPLE_RATE


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
        c = av.open(str(p), mode="r", metadata_errors="ignore")
        if _look_further(c):
            c.close()
            c = av.open(str(p), mode="r", metadata_errors="ignore", options=LATE_STREAM_PROBE)
        return c
    except av.error.FFmpegError as exc:
        raise MediaError(f"{p}: not a readable media file ({ffmpeg_reason(exc)})") from None
    except (OSError, ValueError, UnicodeDecodeError) as exc:
        raise MediaError(f"{p}: cannot open ({exc})") from None


def _look_further(c) -> bool:
    """Whether every decodable audio stream, or every decodable video stream, of ``c`` is one whose rate,
    channels or size FFmpeg's first look (5 s of the file) did not find: in a transport stream (a
    recording, a Blu-ray's) nothing but a stream's own packets says them, and its first packets may come
    later. One such stream beside a usable one (a recorder's audio description channel that carries
    nothing) is passed over: looking further would read up to :data:`LATE_STREAM_PROBE` at every open."""
    for kind in ("audio", "video"):
        decodable = [s for s in c.streams if s.type == kind and s.codec_context is not None]
        if decodable and all(_undetermined(s) for s in decodable):
            return True
    return False


def _undetermined(s) -> bool:
    cc = s.codec_context
    if s.type == "audio":
        return not cc.sample_rate or not cc.layout.nb_channels
    return not cc.width


def probe(path: str | os.PathLike) -> MediaInfo:
    """Streams, duration, frame rate, sample rate and channels of a media file.

    Raises MediaError when the file is missing, not media, has neither audio nor video,
    or has no usable duration.
    """
    p = Path(path)
    with open_container(p) as c:
        undecodable = [f"{s.type} stream #{s.index} ({_codec_name(s)})" for s in c.streams
                       if s.type in ("video", "audio") and s.codec_context is None]
        pictures = [s for s in c.streams.video if s.codec_context is not None and _is_real_video(s)]
        among = film_programme(p, c, {s.index for s in pictures})
        vs = next((s for s in pictures if among is None or s.index in among), None)
        as_ = sound_stream(c, among)
        video = _video_info(vs) if vs is not None else None
        audio = _audio_info(as_, c) if as_ is not None else None
        if undecodable and ((video is None and any(u.startswith("video") for u in undecodable))
                            or (audio is None and any(u.startswith("audio") for u in undecodable))):
            raise MediaError(f"{p}: unsupported codec: no decoder for {', '.join(undecodable)}")
        if video is None and audio is None:
            raise MediaError(f"{p}: no audio or video stream (container {c.format.name})")
        if audio is not None and (audio.sample_rate <= 0 or audio.channels <= 0):
            raise MediaError(f"{p}: audio stream #{audio.index} ({audio.codec}) declares no sample rate or channels")
        read = [s for s in (vs, as_) if s is not None]
        start_s = _container_start(c) if among is None else _streams_start(read)
        duration = _duration_s(c, read) if among is None else None
        if duration is None:
            duration = _scan_duration(c, read, start_s)
        if duration is None or not math.isfinite(duration) or duration <= 0:
            raise MediaError(f"{p}: zero-length media (no decodable duration)")
        if video is not None:
            c.seek(0)
            rotation, stereo = _first_frame_facts(c, vs)
            video = replace(video, rotation=rotation, stereo=stereo, variable_rate=_variable_rate(c, vs, video.fps))
        clock = None
        if c.format.name in TRANSPORT_FORMATS:
            clock, end = read_clock(c, read)
            if (clock.jump_positions or among is not None) and end is not None:
                duration = end - start_s
        return MediaInfo(path=str(p), size_bytes=p.stat().st_size, container=c.format.name,
                         duration_s=float(duration), start_s=start_s, video=video, audio=audio, clock=clock)


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
    indices = {info.video.index} if info.video is not None else set()
    indices |= set(info.audio.streams) if info.audio is not None else set()
    end = None
    with open_container(info.path) as c:
        streams = [s for s in c.streams if s.index in indices]
        try:
            for pkt in c.demux(*streams):
                if pkt.pts is None or pkt.time_base is None:
                    continue
                if info.clock is not None:
                    info.clock.fix(pkt)
                t = float((pkt.pts + (pkt.duration or 0)) * pkt.time_base)
                end = t if end is None else max(end, t)
        except av.error.FFmpegError as exc:
            raise MediaError(f"{info.path}: damaged file, reading stops at "
                             f"{0.0 if end is None else end - info.start_s:.2f} s ({ffmpeg_reason(exc)})") from None
    if end is None:
        raise MediaError(f"{info.path}: no audio or video packets")
    check_truncation(info, end - info.start_s, "video" if info.video is not None else "audio")


def stream_by_index(c, index: int):
    """The container's stream with that index; MediaError when it is gone."""
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
    sar = s.sample_aspect_ratio or cc.sample_aspect_ratio
    return VideoInfo(index=s.index, width=cc.width, height=cc.height, fps=fps, codec=cc.name,
                     n_frames=int(s.frames) if s.frames else None, rotation=0, duration_s=dur,
                     pixel_aspect=float(sar) if sar and 0.1 <= float(sar) <= 10 else 1.0)


def _first_frame_facts(c, s) -> tuple[int, str]:
    """Display rotation (degrees counter-clockwise, 0/90/180/270) and the declared 3D packing
    (:func:`~autohaptics.media.stereo.declared_packing`) read from the first decoded frame."""
    try:
        for frame in c.decode(s):
            return norm_rotation(getattr(frame, "rotation", 0)), declared_packing(dict(s.metadata), frame)
    except av.error.FFmpegError:
        pass
    return 0, declared_packing(dict(s.metadata), None)


def _variable_rate(c, s, fps: float) -> bool:
    """Whether the frames come irregularly: the average rate ``fps`` under ``VARIABLE_RATE_SHARE`` of
    the rate of the stream's typical frame interval (the median over its first ``RATE_PACKETS``
    packets; FFmpeg's own rate guess reads one odd interval, e.g. a cut's first frame, as a rate)."""
    times = set()
    try:
        c.seek(0)
        for packet in c.demux(s):
            if packet.pts is not None and packet.time_base:
                times.add(float(packet.pts * packet.time_base))
            if len(times) >= RATE_PACKETS:
                break
    except av.error.FFmpegError:
        return False
    ordered = sorted(times)
    steps = sorted(b - a for a, b in zip(ordered, ordered[1:]))
    if len(steps) < 8:
        return False
    typical = steps[len(steps) // 2]
    return typical > 0 and fps < VARIABLE_RATE_SHARE / typical


def norm_rotation(deg) -> int:
    """A rotation in degrees as 0, 90, 180 or 270 (anything unreadable is 0)."""
    try:
        return int(round(float(deg or 0) / 90.0)) % 4 * 90
    except (TypeError, ValueError):
        return 0


def _audio_info(s, c) -> AudioInfo:
    cc = s.codec_context
    dur = float(s.duration * s.time_base) if s.duration and s.time_base else None
    tracks, layout = channel_tracks(c, s)
    n = len(tracks) if len(tracks) > 1 else int(cc.layout.nb_channels)
    return AudioInfo(index=s.index, sample_rate=int(cc.sample_rate or 0), channels=n, layout=layout,
                     codec=cc.name, duration_s=dur, tracks=tuple(tracks) if len(tracks) > 1 else ())


def _streams_start(streams) -> float:
    """The earliest start of ``streams``, s on their clock (0 when none is timed)."""
    starts = [float(s.start_time * s.time_base) for s in streams if s.start_time is not None and s.time_base]
    return min(starts) if starts else 0.0


def _container_start(c) -> float:
    if c.start_time is not None:
        try:
            start = float(c.start_time) / av.time_base
            # a transport stream's clock is unsigned: a start below 0 is FFmpeg reading it across its wrap
            return start if c.format.name in TRANSPORT_FORMATS else max(0.0, start)
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


def decode_tolerant(c, streams, report: AudioReport, path: str, *, tagged: bool = False, clock: Clock | None = None):
    """Decode packets of ``streams``; a damaged packet is counted and skipped, never fatal here.
    Yields frames, or (stream index, frame) pairs when ``tagged``; with ``clock``, timed on the file's
    continuous clock (``media.clock``)."""
    try:
        packets = c.demux(streams)
        while True:
            try:
                pkt = next(packets)
            except StopIteration:
                break
            except av.error.FFmpegError as exc:
                report.decode_errors += 1
                report.first_error = report.first_error or ffmpeg_reason(exc)
                break  # the demuxer cannot go on after a read error
            if clock is not None:
                clock.fix(pkt)
            try:
                frames = pkt.decode()
            except av.error.FFmpegError as exc:
                report.decode_errors += 1
                report.first_error = report.first_error or ffmpeg_reason(exc)
                if report.decode_errors > 1000:
                    raise MediaError(f"{path}: undecodable stream ({report.first_error})") from None
                continue
            if tagged:
                yield from ((pkt.stream.index, f) for f in frames)
            else:
                yield from frames
    except av.error.FFmpegError as exc:
        raise MediaError(f"{path}: cannot decode ({ffmpeg_reason(exc)})") from None


def ffmpeg_reason(exc: Exception) -> str:
    """The short reason of an FFmpeg error, for a one-line message."""
    msg = getattr(exc, "strerror", None) or str(exc)
    return str(msg).split(":")[-1].strip() or type(exc).__name__
