"""A 3D film made of a 2D one, for the tests and ``bench matrix``: each frame of the source as the left
eye's view and, as the right eye's, the same picture shifted by a parallax that grows towards the bottom
of the frame (the ground nearer than the sky), the two packed in one frame at half width (side by side)
or half height (top and bottom), as a 3D Blu-ray's rip or a 3D broadcast packs them (``media.stereo``).
"""

from __future__ import annotations

import os
from pathlib import Path

import av
import cv2
import numpy as np

from autohaptics.errors import ParameterError
from autohaptics.media.stereo import PACKINGS
from autohaptics.testing.encode import encode_frames

PARALLAX = 0.015  # the right view's largest shift, of the view's width (at the bottom; half that at the top)
_X264_PACKING = {"side_by_side": "3", "top_bottom": "4"}  # H.264 frame-packing arrangement types
_MATROSKA = {"side_by_side": "left_right", "top_bottom": "top_bottom"}


def stereo_pair(rgb: np.ndarray, parallax: float = PARALLAX) -> tuple[np.ndarray, np.ndarray]:
    """(left, right) views of one picture (uint8 [shape=(h, w, 3)]): the right shifted left by
    ``parallax`` x its width at the bottom row, half that at the top."""
    h, w = rgb.shape[:2]
    shift = parallax * w * (0.5 + 0.5 * np.linspace(0.0, 1.0, h, dtype=np.float32))[:, None]
    map_x = (np.arange(w, dtype=np.float32)[None, :] + shift).astype(np.float32)
    map_y = np.repeat(np.arange(h, dtype=np.float32)[:, None], w, axis=1)
    right = cv2.remap(rgb, map_x, map_y, interpolation=cv2.INTER_LINEAR, borderMode=cv2.BORDER_REPLICATE)
    return rgb, right


def packed(rgb: np.ndarray, packing: str, parallax: float = PARALLAX) -> np.ndarray:
    """The two views of ``rgb`` (:func:`stereo_pair`), each squeezed to half the frame, packed in a frame
    of ``rgb``'s size (even width and height)."""
    h, w = rgb.shape[:2]
    left, right = stereo_pair(rgb, parallax)
    if packing == "side_by_side":
        size, axis = (w // 2, h), 1
    elif packing == "top_bottom":
        size, axis = (w, h // 2), 0
    else:
        raise ParameterError(f"packing must be one of {PACKINGS}, got {packing!r}")
    return np.concatenate([cv2.resize(v, size, interpolation=cv2.INTER_AREA) for v in (left, right)], axis=axis)


def write_packed(src: str | os.PathLike, dst: str | os.PathLike, packing: str, *, declared: str = "container",
                 crf: int = 18) -> Path:
    """``src``'s picture as a 3D film packed so (:func:`packed`; H.264, x264 veryfast at ``crf``), its sound's
    packets copied. declared : how the file says it: "container" (Matroska's StereoMode; ``dst`` .mkv),
    "h264" (the frame-packing message in the H.264 stream) or "none" (as many rips are)."""
    if packing not in PACKINGS or declared not in ("container", "h264", "none"):
        raise ParameterError(f"packing {packing!r} or declared {declared!r} unknown")
    dst = Path(dst)
    with av.open(str(src)) as c, av.open(str(dst), "w") as out:
        v_in = c.streams.video[0]
        options = {"preset": "veryfast", "crf": str(int(crf))}
        if declared == "h264":
            options["x264-params"] = f"frame-packing={_X264_PACKING[packing]}"
        v = out.add_stream("libx264", rate=v_in.average_rate, options=options)
        v.width, v.height, v.pix_fmt = v_in.codec_context.width // 2 * 2, v_in.codec_context.height // 2 * 2, "yuv420p"
        v.time_base = v_in.time_base
        if declared == "container":
            v.metadata["stereo_mode"] = _MATROSKA[packing]
        a_in = c.streams.audio[0] if c.streams.audio else None
        a = out.add_stream_from_template(a_in) if a_in is not None else None
        encode_frames(out, v, (_packed_frame(frame, v.width, v.height, packing) for frame in c.decode(v_in)))
        if a is not None:
            with av.open(str(src)) as again:
                for p in again.demux(again.streams.audio[0]):
                    if p.size:
                        p.stream = a
                        out.mux(p)
    return dst


def _packed_frame(frame: av.VideoFrame, width: int, height: int, packing: str) -> av.VideoFrame:
    """``frame`` at ``width`` x ``height`` as its two views packed (:func:`packed`), at its own time."""
    rgb = frame.to_ndarray(format="rgb24", width=width, height=height)
    pic = av.VideoFrame.from_ndarray(np.ascontiguousarray(packed(rgb, packing)), format="rgb24")
    pic.pts, pic.time_base = frame.pts, frame.time_base
    return pic
