"""Clips the benchmarks write for themselves from the shared clips (nothing large is committed).

:func:`reencode` re-encodes a clip (x264 veryfast crf 20 with its B-frames and long GOP, AAC),
optionally played several times in a row, scaled and letterboxed (or scaled to fill the frame and
cropped), at another frame rate, with the sound upmixed to 5.1; :func:`film_clips` makes the
film-like clips of ``--films``: 1080p at 24 fps with stereo sound (the Sintel trailer upscaled,
letterboxed as the 2.35:1 film it is, and filling the whole 16:9 frame as a 16:9 or 1.85:1 film
does) and 854x480 at 25 fps with 5.1 sound (the Big Buck Bunny opening). ``fit="pad"`` fits the
whole picture inside the frame with bars where it is narrower (a pillarbox) or wider (a letterbox).
:func:`copied_clip` plays a clip several times in a row by copying its packets (a feature-length
film of the same encode). Files are written once and reused.
"""

from __future__ import annotations

import os
from pathlib import Path

from autohaptics.errors import ParameterError

SHARED_ENV = "AUTOHAPTICS_SHARED"
FITS = ("letterbox", "fill", "pad")
# (output name, shared clip, width, height, fps, audio layout, fit: one of FITS)
FILMS = (("film_1080p24_stereo", "sintel_trailer_640x272_vp8_vorbis.webm", 1920, 1080, 24, "stereo", "letterbox"),
         ("film_1080p24_full_frame", "sintel_trailer_640x272_vp8_vorbis.webm", 1920, 1080, 24, "stereo", "fill"),
         ("film_480p25_5.1", "bbb_opening_30s_1280x720_vp8_vorbis.webm", 854, 480, 25, "5.1", "letterbox"))


def shared_media() -> Path:
    """The shared clips: ``$AUTOHAPTICS_SHARED/media`` or ``../shared/media`` next to the repository."""
    env = os.environ.get(SHARED_ENV)
    base = Path(env) if env else Path(__file__).resolve().parents[3].parent / "shared"
    return base / "media"


def film_clips(out_dir: Path) -> list[Path]:
    """The film-like clips of :data:`FILMS`, written into ``out_dir`` from the shared clips."""
    clips = []
    for name, src, width, height, fps, layout, fit in FILMS:
        path = shared_media() / src
        if not path.is_file():
            raise ParameterError(f"{path}: shared clip not found (set {SHARED_ENV} to the shared folder)")
        clips.append(reencode(path, out_dir / f"{name}.mp4", size=(width, height), fps=fps, layout=layout, fit=fit))
    return clips


def looped_clip(src: str | Path, times: int, out_dir: Path) -> Path:
    """``src`` played ``times`` times in a row, at its own size, rate and channels."""
    src = Path(src)
    return reencode(src, out_dir / f"{src.stem}_x{times}.mp4", times=times)


def copied_clip(src: str | Path, times: int, out_dir: Path) -> Path:
    """``src`` played ``times`` times in a row by copying its packets: the same encode (codec, GOP,
    bit rate) at any length, written in seconds where a re-encode of a feature-length film takes
    hours; each copy's packets follow the copy before on each stream's own clock (an overlapped
    audio codec such as Vorbis may give up to a frame of sound more at each join). Written once
    into ``out_dir`` as ``<stem>_copies<times><suffix>`` and reused."""
    import av

    src = Path(src)
    if int(times) < 1:
        raise ParameterError(f"copies must be at least 1, got {times!r}")
    out = out_dir / f"{src.stem}_copies{int(times)}{src.suffix}"
    if out.exists():
        return out
    out_dir.mkdir(parents=True, exist_ok=True)
    tmp = out.with_name(f"{out.stem}.part{out.suffix}")
    with av.open(str(src)) as first, av.open(str(tmp), "w") as dst:
        kept = [s for s in first.streams if s.type in ("video", "audio")]
        if not kept:
            raise ParameterError(f"{src}: no audio or video stream to copy")
        streams = {s.index: dst.add_stream_from_template(s) for s in kept}
        end = dict.fromkeys(streams, 0)  # where each stream's previous copy ended, output timestamps
        for copy in range(int(times)):
            shift = dict.fromkeys(streams, None)  # input time-base units added to this copy's packets
            last = dict.fromkeys(streams, None)
            with av.open(str(src)) as inp:
                for pkt in inp.demux(*(inp.streams[i] for i in streams)):
                    k = pkt.stream.index
                    if pkt.dts is None:
                        continue
                    if shift[k] is None:
                        shift[k] = end[k] - pkt.dts if copy else 0
                    pkt.dts += shift[k]
                    if pkt.pts is not None:
                        pkt.pts += shift[k]
                    if last[k] is not None and pkt.dts <= last[k]:
                        continue  # a muxer takes only rising decoding times
                    last[k] = pkt.dts
                    end[k] = max(end[k], pkt.dts + max(int(pkt.duration or 0), 1))
                    pkt.stream = streams[k]
                    dst.mux(pkt)
    os.replace(tmp, out)
    return out


def reencode(src: Path, out: Path, *, times: int = 1, size: tuple[int, int] | None = None, fps: int | None = None,
             layout: str | None = None, fit: str = "letterbox") -> Path:
    """Write ``src`` re-encoded to ``out`` (H.264 + AAC at 48 kHz), reusing an existing file.

    size : (width, height); the picture is scaled to the width, letterboxed (or cropped) to the height.
    fit : "letterbox" (as ``size`` says), "fill": scaled to cover the whole frame, the overhanging
        sides (or top and bottom) cropped evenly, so no bar is left, or "pad": scaled to fit inside
        the frame, black bars on the sides (pillarbox) or top and bottom (letterbox) evenly.
    fps : output frame rate; each output frame shows the source frame on screen at its time.
    layout : "stereo" or "5.1" (front from left/right, centre and LFE from their mean, surrounds
        at half level); default the source's own (mono, stereo or 5.1).
    """
    import av

    from autohaptics import media

    if fit not in FITS:
        raise ParameterError(f"fit must be one of {FITS}, got {fit!r}")
    if out.exists():
        return out
    out.parent.mkdir(parents=True, exist_ok=True)
    info = media.probe(src)
    tmp = out.with_suffix(".part.mp4")
    with av.open(str(tmp), "w") as dst:
        vs = as_ = None
        if info.video is not None:
            width, height = size or (info.video.width, info.video.height)
            vs = dst.add_stream("libx264", rate=fps or round(info.video.fps))
            vs.width, vs.height, vs.pix_fmt = width, height, "yuv420p"
            vs.options = {"preset": "veryfast", "crf": "20"}
        if info.audio is not None:
            layout = layout or {1: "mono", 2: "stereo", 6: "5.1"}.get(info.audio.channels, "stereo")
            as_ = dst.add_stream("aac", rate=48000, layout=layout)
        counts = [0, 0]  # video frames, audio samples written
        rates = (info.video.fps, fps or round(info.video.fps)) if info.video else (0.0, 0)
        for _ in range(times):
            _copy(src, dst, vs, as_, counts, rates, fit)
        for stream in (vs, as_):
            if stream is not None:
                dst.mux(stream.encode(None))
    tmp.replace(out)
    return out


def _copy(src: Path, dst, vs, as_, counts: list[int], rates: tuple[float, int], fit: str) -> None:
    """One play of ``src`` into ``dst``; ``rates`` = (source fps, output fps); ``fit`` as :func:`reencode`."""
    import av

    resampler = av.AudioResampler(format="fltp", layout="stereo", rate=48000) if as_ is not None else None
    src_fps, fps = rates
    with av.open(str(src)) as s:
        start, i = counts[0], 0
        for frame in s.decode(*(s.streams.video[:1] + s.streams.audio[:1])):
            if isinstance(frame, av.VideoFrame) and vs is not None:
                i += 1
                picture = None
                # the output frames whose time falls on this source frame (the i-th)
                while (counts[0] - start) * src_fps < i * fps:
                    if picture is None:
                        picture = _picture(frame, vs.width, vs.height, fit=fit)
                    f = av.VideoFrame.from_ndarray(picture, format="yuv420p")
                    f.pts = counts[0]
                    counts[0] += 1
                    dst.mux(vs.encode(f))
            elif isinstance(frame, av.AudioFrame) and as_ is not None:
                for r in resampler.resample(frame):
                    _write_audio(dst, as_, r.to_ndarray(), counts)


def _picture(frame, width: int, height: int, *, fit: str = "letterbox"):
    """The frame as a yuv420p array [shape=(height * 3 // 2, width)], placed as ``fit`` says
    (:func:`reencode`): scaled to ``width`` and letterboxed or cropped to ``height``; "fill": scaled
    to cover ``width`` x ``height`` and cropped evenly on the axis that overhangs; "pad": scaled to
    fit inside, with even black bars on the axis that falls short."""
    import numpy as np

    if fit == "fill":
        scale = max(width / frame.width, height / frame.height)
    elif fit == "pad":
        scale = min(width / frame.width, height / frame.height)
    else:
        scale = width / frame.width
    w = width if fit == "letterbox" else max(2, int(round(frame.width * scale / 2)) * 2)
    h = max(2, int(round(frame.height * scale / 2)) * 2)
    yuv = frame.reformat(width=w, height=h, format="yuv420p").to_ndarray()
    y, u, v = yuv[:h], yuv[h:].reshape(-1)[: h * w // 4], yuv[h:].reshape(-1)[h * w // 4:]
    out_y = np.full((height, width), 16, np.uint8)
    out_c = np.full((2, height // 2, width // 2), 128, np.uint8)
    # (source start, destination start, length) per axis, even so the chroma keeps its place
    (sy, dy, rows), (sx, dx, cols) = (_placement(h, height), _placement(w, width))
    out_y[dy:dy + rows, dx:dx + cols] = y[sy:sy + rows, sx:sx + cols]
    for k, c in enumerate((u, v)):
        c = c.reshape(h // 2, w // 2)
        out_c[k, dy // 2:(dy + rows) // 2, dx // 2:(dx + cols) // 2] = \
            c[sy // 2:(sy + rows) // 2, sx // 2:(sx + cols) // 2]
    return np.concatenate([out_y, out_c[0].reshape(-1, width), out_c[1].reshape(-1, width)])


def _placement(size: int, frame: int) -> tuple[int, int, int]:
    """(source start, destination start, length) px of a picture ``size`` long centred in a frame
    ``frame`` long: cropped evenly where longer, padded evenly where shorter (starts even)."""
    offset = (frame - size) // 4 * 2
    return (0, offset, size) if offset >= 0 else (-offset, 0, frame)


def _write_audio(dst, as_, stereo, counts: list[int]) -> None:
    import av
    import numpy as np

    left, right = stereo[0], stereo[1]
    n_out = as_.layout.nb_channels
    if n_out == 6:  # FL FR FC LFE BL BR
        mid = 0.5 * (left + right)
        arr = np.stack([left, right, 0.7 * mid, mid, 0.5 * left, 0.5 * right])
    elif n_out == 1:
        arr = (0.5 * (left + right))[None]
    else:
        arr = np.stack([left, right])
    f = av.AudioFrame.from_ndarray(np.ascontiguousarray(arr, dtype=np.float32), format="fltp",
                                   layout=as_.layout.name)
    f.sample_rate = 48000
    f.pts = counts[1]
    counts[1] += f.samples
    dst.mux(as_.encode(f))

