"""Shot posters: one JPEG per shot, the frame at the middle of the shot, made on demand (a seek to
the keyframe before it, decoded up to it with :func:`autohaptics.media.iter_video`, scaled and
encoded with OpenCV's ``imencode``) and kept in the project's folder (``posters/<tick>.jpg``, named
by the frame's tick, so a split or merge that keeps a shot's middle keeps its poster); the folder
goes with the project."""

from __future__ import annotations

import os
import threading
from pathlib import Path

import cv2

from autohaptics import media
from autohaptics.errors import MediaError
from autohaptics.timebase import TICK_S

WIDTH = 160  # px: a filmstrip cell or a panel thumbnail
QUALITY = 80  # JPEG quality
_locks: dict[Path, threading.Lock] = {}
_guard = threading.Lock()


def poster_tick(t0: int, t1: int) -> int:
    """The tick whose frame stands for the shot ``[t0, t1)``: its middle."""
    return (int(t0) + int(t1) - 1) // 2


def poster(folder: Path, media_path: Path, tick: int) -> Path:
    """The poster file of ``tick`` in ``folder``, made now if it is not there yet (one maker per file)."""
    path = folder / f"{int(tick)}.jpg"
    if path.exists():
        return path
    with _guard:
        lock = _locks.setdefault(path, threading.Lock())
    with lock:
        if not path.exists():
            data = _encode(media_path, tick)
            folder.mkdir(parents=True, exist_ok=True)
            tmp = path.with_suffix(f".{os.getpid()}.{threading.get_ident()}.tmp")
            tmp.write_bytes(data)
            tmp.replace(path)
    return path


def _encode(media_path: Path, tick: int) -> bytes:
    """JPEG bytes, ``WIDTH`` px wide, of the first frame inside ``tick`` (the last frame before it
    when the film ends first)."""
    info = media.probe(media_path)
    if info.video is None:
        raise MediaError(f"{media_path.name} has no video stream to take a poster from")
    at = (tick + 0.5) * TICK_S
    chosen = None
    stream = media.iter_video(media_path, info=info, start_s=max(0.0, at - 0.5))
    try:
        for frame in stream:
            chosen = frame
            if frame.time_s >= at - 0.5 * TICK_S:
                break
    finally:
        stream.close()
    if chosen is None:
        raise MediaError(f"{media_path.name}: no frame could be decoded near {at:.1f} s")
    rgb = chosen.proxy(WIDTH)
    ok, buf = cv2.imencode(".jpg", cv2.cvtColor(rgb, cv2.COLOR_RGB2BGR), [cv2.IMWRITE_JPEG_QUALITY, QUALITY])
    if not ok:
        raise MediaError(f"{media_path.name}: the poster at {at:.1f} s could not be encoded")
    return buf.tobytes()
