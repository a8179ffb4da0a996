"""What the video pass reads of each frame: the rectangle (the active picture inside black bars, a 3D
film's first view), the overlays burnt in over it and the aspect on screen its proxies keep; and which
frames it decodes."""

from __future__ import annotations

from dataclasses import dataclass
from itertools import islice

from autohaptics import media
from autohaptics.airflow.cadence import Cadence
from autohaptics.media.overlays import MIN_SHOTS, EdgeTally, Overlays
from autohaptics.media.stereo import view_aspect, view_rect
from autohaptics.params import GenerateParams


SAMPLED_MIN_S = 180.0  # s: a film at least this long is searched for overlays in its samples, each a shot
SAMPLE_EVERY_S = 1.0  # s: a pass that searches for overlays itself samples a shot this often after its first frame


@dataclass(frozen=True)
class Picture:
    """What the pass reads of each frame. area : (x, y, w, h) px, display orientation (None: the whole
    frame as decoded); packing : the 3D packing ("" for 2D); overlays : found before the pass (None:
    none); tally : whether the pass must look for overlays itself, shot by shot."""

    area: tuple[int, int, int, int] | None
    packing: str
    overlays: Overlays | None = None
    tally: bool = False


def read_picture(info: media.MediaInfo, params: GenerateParams) -> Picture:
    """The rectangle the pass reads of each frame and the 3D packing it is read under ("" for 2D;
    ``video.stereo``, :func:`media.find_picture`): the active picture inside black bars of the first
    view (``video.active_area="auto"``), or the whole view ("full"); None for the whole frame as
    decoded (a 2D film read in full, or no video). With ``video.overlays="auto"`` also the overlays
    over that rectangle in the same sampled pictures, each taken as a shot (``SAMPLED_MIN_S`` of film
    and up; a shorter one, or one too few pictures were sampled of, the pass samples shot by shot)."""
    if info.video is None:
        return Picture(None, "")
    stereo, lumas = params.video.stereo, None
    if params.video.active_area != "full":
        lumas = media.sample_lumas(info)
        area, packing = media.find_picture(info, stereo, lumas=lumas)
    else:
        if stereo == "auto":
            packing = info.video.stereo or media.find_picture(info, lumas=(lumas := media.sample_lumas(info)))[1]
        else:
            packing = "" if stereo == "2d" else stereo
        area = view_rect(*info.video.display_size, packing) if packing else None
    if params.video.overlays != "auto":
        return Picture(area, packing)
    if info.duration_s < SAMPLED_MIN_S:  # samples close together may share a shot: the pass tells its shots
        return Picture(area, packing, tally=True)
    lumas = media.sample_lumas(info) if lumas is None else lumas
    x, y, w, h = area if area is not None else (0, 0, *info.video.display_size)
    tally = EdgeTally()
    for luma in lumas:
        tally.add(luma[y:y + h, x:x + w])
    return Picture(area, packing, tally.find(), tally.n < MIN_SHOTS)


class ShotSampler:
    """A pass's own search for overlays: the gray proxy of each shot's first analysed frame, then one
    a second (``SAMPLE_EVERY_S``), into an :class:`~autohaptics.media.overlays.EdgeTally` by shot."""

    def __init__(self):
        self.tally = EdgeTally()
        self.at, self.shot, self.cut_tick = 0.0, 0, -1

    def add(self, k: int, time_s: float, cut: bool, gray) -> None:
        """The analysed frame of tick ``k`` (a cut there: a new shot; time_s: s) and its gray proxy."""
        new_shot = cut and k != self.cut_tick  # the 'every' analysis reads several frames a tick
        if new_shot or time_s >= self.at:
            self.shot, self.cut_tick = self.shot + int(new_shot), k if new_shot else self.cut_tick
            self.tally.add(gray, self.shot)
            self.at = time_s + SAMPLE_EVERY_S

    def found(self) -> Overlays | None:
        """The overlays the samples show (None: none)."""
        return self.tally.find()


def shown_aspect(info: media.MediaInfo, area: tuple[int, int, int, int] | None, packing: str) -> float | None:
    """The width / height on screen of what the pass reads (``area``, or the whole frame), its pixels'
    aspect and a half-size 3D view's squeeze applied (:func:`media.stereo.view_aspect`); None without
    video. The proxies keep it, so motion and position read as they are seen."""
    if info.video is None:
        return None
    w, h = area[2:] if area is not None else info.video.display_size
    return view_aspect(info.video.shown_aspect(w, h), info.video.shown_aspect(), packing)


SAMPLE_AT = (0.25, 0.5, 0.75)  # where the stretches :func:`repeat_share` decodes begin, fractions of the film
SAMPLE_S = 0.5  # each stretch's length, s
CONVERSION_SHARE = 0.3  # repeats among the judged frames from which a stream is a film's conversion
MIN_JUDGED = 24  # judged frames a share needs (still pictures judge none)


def decode_mode(info: media.MediaInfo, params: GenerateParams, need_flow: bool) -> str:
    """``video.decode``, but "full" for a stream of ``media.SPARSE_MIN_FPS`` and up that repeats its
    pictures (a 24 fps film at 50, 59.94 or 120 fps: :func:`repeat_share` at least ``CONVERSION_SHARE``)
    where the fans want motion: the repeats are told from each frame's difference to the one before
    (``airflow.cadence``), which skipping the non-reference frames hides. Below that rate "nonref"
    already decodes every frame of a 29-40 fps stream (``media.video.REPEAT_MIN_FPS``)."""
    decode, v = params.video.decode, info.video
    if not need_flow or decode not in ("nonref", "fast") or v is None or v.variable_rate \
            or v.fps < media.SPARSE_MIN_FPS or params.flow.cadence_ratio <= 0:
        return decode
    return "full" if repeat_share(info, params.flow.cadence_ratio) >= CONVERSION_SHARE else decode


def repeat_share(info: media.MediaInfo, ratio: float) -> float:
    """The share of repeats (``airflow.cadence``, ``ratio``) among the judged frames of ``SAMPLE_S``
    stretches of every frame decoded at ``SAMPLE_AT``; 0 where fewer than ``MIN_JUDGED`` are judged.
    A quarter of a second of decoding at 1080p60."""
    fps = float(info.video.fps)
    found = judged = 0
    for at in SAMPLE_AT:
        cadence = Cadence(1.0 / fps, ratio)
        frames = media.iter_video(info.path, info=info, decode="full", start_s=at * info.duration_s)
        try:
            for frame in islice(frames, max(3, round(SAMPLE_S * fps))):
                cadence.add(frame.time_s, frame.luma_sample())
        finally:
            frames.close()
        found, judged = found + cadence.found, judged + cadence.judged
    return found / judged if judged >= MIN_JUDGED else 0.0
