"""Pictures of the film at ticks: the decoding (PyAV seeks, :func:`frames_at`) and JPEG encoding
(OpenCV's ``imencode``) that shot posters and filmstrip tiles (:mod:`.pictures`) share, and the
posters themselves: one per shot, the frame at the middle of the shot, named by that tick
(``posters/<tick>.jpg`` in the project's folder), so a split or merge that keeps a shot's middle
keeps its poster. Pictures show the active picture (inside black bars, as the analysis found it)."""

from __future__ import annotations

import json
import math
import os
import threading
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path

import cv2
import numpy as np

from autohaptics import media
from autohaptics.errors import MediaError
from autohaptics.media.stereo import PACKINGS, view_aspect
from autohaptics.timebase import TICK_S

WIDTH = 160  # px: a poster
QUALITY = 80  # JPEG quality
SEEK_AFTER_S = 3.0  # a later frame this far past the last decoded one is reached by a seek, not by decoding on


class Cancelled(Exception):
    """A picture was left unmade: its maker was asked to stop."""


@dataclass(frozen=True)
class Film:
    """What pictures are cut from: the media file, its probe, the active picture ``crop`` (x, y, w,
    h px in display orientation; None: the whole frame; a 3D film's first view) and its ``aspect``
    (w / h on screen, the pixels' own aspect applied: an anamorphic DVD's, a half-width 3D view's)."""

    path: Path
    info: media.MediaInfo
    crop: tuple[int, int, int, int] | None
    aspect: float


def film(media_path: Path, analysis_path: Path) -> Film:
    """The film of a project: the active picture from its analysis's header (only the header is
    read), else the whole frame."""
    info = media.probe(media_path)
    if info.video is None:
        raise MediaError(f"{media_path.name} has no video stream to take pictures from")
    crop, packing = None, ""
    try:
        with np.load(analysis_path, allow_pickle=False) as z:
            header = json.loads(bytes(z["header"]).decode())
        area = header["stats"]["video"]["active_area"]
        packing = area["stereo"] if area.get("stereo") in PACKINGS else ""
        if len(area["rect"]) == 4 and min(area["rect"][2:]) > 0:
            crop = tuple(int(v) for v in area["rect"])
    except (OSError, KeyError, TypeError, ValueError, AttributeError):
        pass
    aspect = info.video.shown_aspect(*crop[2:]) if crop else info.video.shown_aspect()
    return Film(Path(media_path), info, crop, view_aspect(aspect, info.video.shown_aspect(), packing))


def poster_tick(t0: int, t1: int) -> int:
    """The tick whose frame stands for the shot ``[t0, t1)``: its middle."""
    return (int(t0) + int(t1) - 1) // 2


def frames_at(source: Film, ticks: Sequence[int], size: tuple[int, int], *,
              cancel: Callable[[], bool] = lambda: False) -> list[np.ndarray]:
    """The picture on screen at the middle of each tick (ticks increasing), RGB uint8 [shape=(h, w, 3)]
    at ``size`` (w, h): the first frame that is still shown there (the last frame when the film
    ends first). Close ticks are decoded on from one seek; a tick more than ``SEEK_AFTER_S`` past
    the last decoded frame gets its own seek (to the keyframe before it)."""
    period = 1.0 / max(source.info.video.fps, 1e-6)
    out: list[np.ndarray] = []
    stream, frame, pos, tail = None, None, -math.inf, None
    try:
        for tick in ticks:
            want = (int(tick) + 0.5) * TICK_S - period  # a frame after this is on screen at the middle
            if stream is None or want - pos > SEEK_AFTER_S:
                if stream is not None:
                    stream.close()
                start = max(0.0, want - 0.5)
                stream = media.iter_video(source.path, info=source.info, start_s=start, crop=source.crop)
                frame, pos, tail = None, start, None
            while tail is None and (frame is None or frame.time_s <= want):
                if cancel():
                    raise Cancelled()
                nxt = next(stream, None)
                if nxt is None:  # the film ends first: its last frame
                    if frame is None:
                        raise MediaError(f"{source.path.name}: no frame could be decoded near tick {tick}")
                    tail = frame.proxy(*size)
                else:
                    frame, pos = nxt, nxt.time_s
            out.append(tail if tail is not None else frame.proxy(*size))
    finally:
        if stream is not None:
            stream.close()
    return out


def jpeg(rgb: np.ndarray) -> bytes:
    """JPEG bytes of an RGB picture (``QUALITY``)."""
    ok, buf = cv2.imencode(".jpg", cv2.cvtColor(np.ascontiguousarray(rgb), cv2.COLOR_RGB2BGR),
                           [cv2.IMWRITE_JPEG_QUALITY, QUALITY])
    if not ok:
        raise MediaError("a picture could not be encoded as JPEG")
    return buf.tobytes()


def poster_size(source: Film) -> tuple[int, int]:
    """A poster's size (w, h px): ``WIDTH`` wide at the active picture's aspect."""
    return WIDTH, max(2, round(WIDTH / source.aspect))


def picture_jpeg(source: Film, ticks: Sequence[int], size: tuple[int, int], *,
                 cancel: Callable[[], bool] = lambda: False) -> bytes:
    """JPEG of the frames of ``ticks`` at ``size`` side by side: a poster (one tick) or a filmstrip tile."""
    return jpeg(np.hstack(frames_at(source, ticks, size, cancel=cancel)))


def write(path: Path, data: bytes) -> bool:
    """Write a picture file atomically (a temporary file, then a rename); its folder is made, but
    not the project's folder above it: False (nothing written) once the project is gone."""
    tmp = path.with_name(f"{path.name}.{os.getpid()}.{threading.get_ident()}.tmp")
    try:
        path.parent.mkdir(exist_ok=True)
        tmp.write_bytes(data)
        tmp.replace(path)
    except FileNotFoundError:
        return False
    return True
