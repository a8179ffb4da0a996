"""Shot boundaries on the shared clips against cut lists written by looking at their frames.

How the lists were made: one frame per tick (the frame nearest the tick's centre, decoded with
PyAV) was laid out ten to a row with its tick number, a sheet per 10 s, and each change of
picture was read off the sheets; where the change was unclear, every frame around it was laid out
with its time (Sintel 16.4-17.8 s and 25.5-31.2 s). A boundary is a window of ticks (lo, hi): a
hard cut has lo == hi (the first tick of the new shot); a transition whose middle is ill-defined
(a cut to black followed by a fade in, a title dissolving in while the picture fades out) spans
the black or the blend. A found boundary matches a window when it lies within one tick of it;
DONT_CARE holds stretches where the eye could not tell action from cuts at this size.
"""

from __future__ import annotations

import functools

import numpy as np
import pytest

from autohaptics import media, shots
from autohaptics.params import resolve_params
from autohaptics.pipeline.video import video_pass
from autohaptics.timebase import n_ticks
from shared_data import shared_clip

SINTEL = "sintel_trailer_480x204_h264_aac.mp4"
CUT_LISTS = {
    SINTEL: [
        (52, 53),    # mountains -> white fog -> Sintel in the snow (fade through white)
        (92, 94),    # fade to black, then the "Blender Foundation presents" card
        (116, 118),  # the card fades out; black; the old man fades in
        (140, 140),  # old man -> Sintel's face (hard cut, same dark warm palette)
        (162, 166),  # her face fades to black; cut from black into the snow
        (169, 169), (171, 171),  # the fight in the snow: two short shots
        (176, 181),  # cut to black; the corridor fades in
        (218, 220),  # the corridor fades to black; Sintel fades in
        (239, 239), (259, 259), (275, 275),  # cuts: the city, the dragon in the sky, her face
        (281, 284),  # cut to black; the desert chase fades in
        (322, 322),  # fade through black to the dragon flying
        (355, 357),  # the dragon dissolves into the desert (35.0-36.3 s; half-way at 35.7 s by a
                     # least-squares blend of the frames either side)
        (405, 422),  # the SINTEL title dissolves in while the desert fades out
        (470, 476),  # the title fades out; "coming soon"
        (486, 486), (509, 509),  # the credits card; black
    ],
    "bbb_opening_30s_1280x720_vp8_vorbis.webm": [(118, 118), (157, 157), (230, 230)],  # the tilt down is one shot
    "bbb_1080p60_2s_h264_aac6ch.mp4": [(3, 3)],  # the cut at 0.342 s
    "bbb_1s_1280x720_vp8_vorbis.webm": [],
}
DONT_CARE = {SINTEL: [(296, 310)]}  # the dragon grabbing her: fast action, maybe cuts


def score(found: list[int], windows: list[tuple[int, int]], dont_care=()) -> tuple[int, int, int]:
    """(matched windows, found boundaries left over, windows missed); each window matched once."""
    free = list(windows)
    extra = 0
    for t in found:
        hit = next((w for w in free if w[0] - 1 <= t <= w[1] + 1), None)
        if hit is not None:
            free.remove(hit)
        elif not any(lo <= t <= hi for lo, hi in dont_care):
            extra += 1
    return len(windows) - len(free), extra, len(free)


@functools.lru_cache(maxsize=None)
def clip_boundaries(name: str) -> tuple[int, ...]:
    info = media.probe(shared_clip(name))
    n = n_ticks(info.duration_s)
    v = video_pass(info, n, params=resolve_params()[0], need_saliency=np.zeros(n, bool), need_flow=True,
                   need_colour=True)
    return tuple(shots.detect(cut=v.cut, signature=v.signature, mean_rgb=v.mean_rgb).tick.tolist())


def test_the_scorer_counts_windows_once():
    assert score([52, 53, 140, 300, 400], [(52, 53), (140, 140)], [(296, 310)]) == (2, 2, 0)


@pytest.mark.parametrize("name", [n for n in CUT_LISTS if n != SINTEL])
def test_big_buck_bunny_clips(name):
    hits, extra, missed = score(clip_boundaries(name), CUT_LISTS[name])
    assert (extra, missed) == (0, 0)


@pytest.mark.slow
def test_sintel_trailer_meets_the_target():
    """Measured: 19 of 19 windows found, nothing extra. The dragon-into-desert dissolve (35.0-36.3 s)
    reads as linear only over its end; its span is widened to the contrast dip it sits in, and its
    first half is a haze (both shots' weights well below a half), so it is placed like a fade: at
    355, midway between the dragon half gone and the desert half there (docs/BENCHMARKS.md, "Shots")."""
    hits, extra, missed = score(clip_boundaries(SINTEL), CUT_LISTS[SINTEL], DONT_CARE[SINTEL])
    assert hits / (hits + extra) >= 0.95 and hits / (hits + missed) >= 0.95, clip_boundaries(SINTEL)
