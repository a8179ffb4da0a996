"""Stereoscopic (3D) films packed in one picture: the left and right eye's views side by side or one
above the other (a 3D Blu-ray's rip, a 3D broadcast, a 3D cinema's screener). The chair answers to
one scene, so the analysis reads one view, the first (the left eye's, or the right's where the file
says it comes first; they differ by a few pixels of parallax).

The packing is what the file declares (Matroska's StereoMode, an H.264 or HEVC frame-packing message,
which FFmpeg hands on as the frame's stereo side data), else what the picture shows: over the sampled
frames the two halves are one picture but for the parallax (:func:`views_alike`;
:func:`autohaptics.media.active.picture_packing`), which a 2D film's halves are not. A half-width
(half-height) view, the usual packing in a 16:9 frame, is shown stretched back to the frame's aspect; a
full one (a 32:9 or 8:9 frame) as it is stored (:func:`view_aspect`).
"""

from __future__ import annotations

import numpy as np

PACKINGS = ("side_by_side", "top_bottom")
# Matroska's StereoMode names (FFmpeg's "stereo_mode" stream tag) of the two packings
_MATROSKA = {"left_right": "side_by_side", "right_left": "side_by_side", "top_bottom": "top_bottom",
             "bottom_top": "top_bottom"}
# FFmpeg's AVStereo3DType values of the two packings (the side data's first 32-bit field)
_SIDE_DATA = {1: "side_by_side", 2: "top_bottom"}
THUMB = (64, 36)  # px, each half compared at this size
SHIFT = 3  # px of THUMB: the parallax searched, each way (about 5 % of the view's width)
MIN_SPREAD = 4.0  # grey levels: a flatter sample tells nothing
SAME = 0.85  # the median correlation of the halves over the samples from which they are one picture
MIN_SAMPLES = 3  # samples that tell, for the median; fewer (a clip of one or two keyframes) must each reach:
SAME_FEW = 0.95


def declared_packing(stream_tags: dict, frame) -> str:
    """The packing a file declares for its video: "side_by_side", "top_bottom" or "" (none, or one the
    analysis does not read: frame-sequential, interleaved lines, a checkerboard). ``stream_tags``: the
    stream's metadata; ``frame``: its first decoded frame (an ``av.VideoFrame``) or None."""
    named = _MATROSKA.get(str(stream_tags.get("stereo_mode", "")).lower())
    if named:
        return named
    try:
        for sd in frame.side_data if frame is not None else ():
            if "STEREO3D" in str(getattr(sd, "type", "")).upper():
                raw = bytes(sd)
                return _SIDE_DATA.get(int.from_bytes(raw[:4], "little"), "") if len(raw) >= 4 else ""
    except (AttributeError, TypeError, ValueError):
        return ""
    return ""


def halves(picture: np.ndarray, packing: str) -> tuple[np.ndarray, np.ndarray]:
    """The two views of ``picture`` (any [shape=(h, w, ...)]) under ``packing``, equal sizes."""
    h, w = picture.shape[:2]
    if packing == "side_by_side":
        return picture[:, :w // 2], picture[:, w // 2:2 * (w // 2)]
    return picture[:h // 2], picture[h // 2:2 * (h // 2)]


def views_alike(a: np.ndarray, b: np.ndarray) -> float | None:
    """How alike two luma pictures (two halves of a frame) are: the largest zero-mean correlation (-1..1)
    of their ``THUMB`` thumbnails over horizontal shifts up to ``SHIFT`` px (the parallax); None for a
    picture flatter than ``MIN_SPREAD``."""
    import cv2  # here: the probe reads this module's declared packing, and needs no OpenCV

    a, b = (cv2.resize(np.ascontiguousarray(x, dtype=np.float32), THUMB, interpolation=cv2.INTER_AREA)
            for x in (a, b))
    if min(a.std(), b.std()) < MIN_SPREAD:
        return None
    best = -1.0
    for s in range(-SHIFT, SHIFT + 1):
        x = a[:, max(s, 0):a.shape[1] + min(s, 0)]
        y = b[:, max(-s, 0):b.shape[1] + min(-s, 0)]
        x, y = x - x.mean(), y - y.mean()
        den = float(np.sqrt((x * x).sum() * (y * y).sum()))
        if den > 0:
            best = max(best, float((x * y).sum()) / den)
    return best


def view_rect(width: int, height: int, packing: str) -> tuple[int, int, int, int]:
    """The first view's rectangle (x, y, w, h) px of a ``width`` x ``height`` picture under
    ``packing`` (the whole picture for "")."""
    if packing == "side_by_side":
        return 0, 0, width // 2, height
    if packing == "top_bottom":
        return 0, 0, width, height // 2
    return 0, 0, width, height


def view_aspect(view_shown: float, frame_shown: float, packing: str) -> float:
    """A view's width / height on screen: ``view_shown`` (its own pixels', as stored) stretched back
    by 2 where it was squeezed into half the frame (side by side in a frame shown narrower than 2.5:1,
    one above the other in one wider than 1:1), as it is otherwise."""
    if packing == "side_by_side" and frame_shown < 2.5:
        return view_shown * 2.0
    if packing == "top_bottom" and frame_shown > 1.0:
        return view_shown / 2.0
    return view_shown
