"""What the video pass reads of each frame: the rectangle (the active picture inside black bars, a 3D
film's first view) and the aspect on screen its proxies keep."""

from __future__ import annotations

from autohaptics import media
from autohaptics.media.stereo import view_aspect, view_rect
from autohaptics.params import GenerateParams


def active_area(info: media.MediaInfo, params: GenerateParams) -> tuple[tuple[int, int, int, int] | None, str]:
    """The rectangle (x, y, w, h) px, display orientation, that the pass reads of each frame, and the
    3D packing it is read under ("" for 2D; ``video.stereo``, :func:`media.find_picture`): the
    active picture inside black bars of the first view (``video.active_area="auto"``), or the whole
    view ("full"); None for the whole frame as decoded (a 2D film read in full, or no video)."""
    if info.video is None:
        return None, ""
    stereo = params.video.stereo
    if params.video.active_area != "full":
        return media.find_picture(info, stereo)
    if stereo == "auto":
        packing = info.video.stereo or media.find_picture(info)[1]
    else:
        packing = "" if stereo == "2d" else stereo
    return (view_rect(*info.video.display_size, packing), packing) if packing else (None, "")


def shown_aspect(info: media.MediaInfo, area: tuple[int, int, int, int] | None, packing: str) -> float | None:
    """The width / height on screen of what the pass reads (``area``, or the whole frame), its pixels'
    aspect and a half-size 3D view's squeeze applied (:func:`media.stereo.view_aspect`); None without
    video. The proxies keep it, so motion and position read as they are seen."""
    if info.video is None:
        return None
    w, h = area[2:] if area is not None else info.video.display_size
    return view_aspect(info.video.shown_aspect(w, h), info.video.shown_aspect(), packing)
