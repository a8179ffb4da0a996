"""Shot boundaries on generated films with known answers (hard cuts, fades through black, cross-
dissolves, between panning shots and into and out of a hazy one, a flash and a partial flash that
are not cuts, a slow pan that is not a cut; title cards of a few pixels of text) at 24, 25, 30
and 60 fps and three sizes: precision and recall >= 0.95 within one tick, the kinds right.

A boundary at t seconds is the tick round(t / 0.1): the first tick that is mostly the new shot; a
fade's or a dissolve's is its middle. Films are written with synth.write_scene (H.264) and run
through the video pass with default parameters.
"""

from __future__ import annotations

import numpy as np
import pytest

from autohaptics import media, shots
from autohaptics import testing as synth
from autohaptics.params import resolve_params
from autohaptics.pipeline.video import video_pass
from autohaptics.testing import Scene, Segment, Shape, Texture
from autohaptics.timebase import n_ticks

BLACK = (0, 0, 0)


def tex(seed: int, scale: float = 0.08, contrast: float = 0.4) -> Texture:
    return Texture("noise", scale, contrast, seed=seed)


CRAWLER = Shape("circle", (250, 240, 200), t_on=0.0, t_off=2.03, xy0=(0.2, 0.6), xy1=(0.7, 0.4), size0=(0.12, 0.2))
FLASH = Shape("rect", (255, 255, 255), t_on=9.70, t_off=9.78, size0=(1.0, 1.0))  # two frames at 24 fps, all white
BURST = Shape("circle", (255, 250, 220), t_on=18.2, t_off=18.32, xy0=(0.4, 0.5), size0=(0.5, 0.8))  # a muzzle flash

FILM = Scene(20.0, name="shots", shapes=(CRAWLER, FLASH, BURST), background=(
    Segment(0.0, 2.03, (60, 90, 160), texture=tex(1)),
    Segment(2.03, 3.87, (170, 120, 60), texture=tex(2)),                       # cut 2.03
    Segment(3.87, 5.0, (40, 160, 60), texture=tex(3)),                         # cut 3.87
    Segment(5.0, 5.6, (40, 160, 60), rgb_end=BLACK, texture=tex(3)),            # fade out ...
    Segment(5.6, 5.8, BLACK),
    Segment(5.8, 6.4, BLACK, rgb_end=(200, 90, 90), texture=tex(4)),            # ... fade in: middle 5.7
    Segment(6.4, 8.62, (200, 90, 90), texture=tex(4)),
    Segment(8.62, 10.9, (110, 70, 170), texture=tex(5), dissolve_s=0.8),        # dissolve centred 8.62
    Segment(10.9, 14.33, (150, 150, 150), texture=tex(6, 0.1), pan=(0.08, 0.0)),  # cut 10.9; a slow pan
    Segment(14.33, 16.48, (200, 180, 70), texture=tex(7), dissolve_s=1.6),      # dissolve centred 14.33
    Segment(16.48, 16.68, (200, 180, 70), rgb_end=BLACK, texture=tex(7)),       # a fast fade through black,
    Segment(16.68, 16.88, BLACK, rgb_end=(60, 190, 190), texture=tex(8)),       # middle 16.68
    Segment(16.88, 20.0, (60, 190, 190), texture=tex(8)),
))
TRUTH = {20: "cut", 39: "cut", 57: "fade", 86: "dissolve", 109: "cut", 143: "dissolve", 167: "fade"}
NOT_CUTS = {"flash": range(96, 99), "pan": range(112, 141), "burst": range(181, 185)}


def text(t_on: float, t_off: float, x: float, y: float) -> tuple[Shape, Shape]:
    """Two lines of grey 'text' on a title card, bars a few pixels high: the 16 x 9 thumbnail is flat
    (standard deviation about 4 grey levels, as the Sintel trailer's cards)."""
    return (Shape("rect", (120, 120, 120), t_on=t_on, t_off=t_off, xy0=(x, y), size0=(0.2, 0.02)),
            Shape("rect", (90, 90, 90), t_on=t_on, t_off=t_off, xy0=(x, y + 0.05), size0=(0.15, 0.015)))


# Title cards and low-detail pictures, where the cut rule sees little but brightness: a picture that
# dims (not to black) and cuts to a card, a card cut to black and a picture fading in, a picture cut
# to a card, a card cut to another card, a card cut to black for the rest of the film.
CARDS = Scene(12.0, name="cards", shapes=(*text(2.6, 4.6, 0.5, 0.45), *text(7.0, 9.0, 0.3, 0.2),
                                          *text(9.0, 10.5, 0.65, 0.75)), background=(
    Segment(0.0, 2.0, (60, 90, 160), texture=tex(1)),
    Segment(2.0, 2.6, (60, 90, 160), rgb_end=(12, 12, 12), texture=tex(1)),  # dims, cut 2.6 to a card
    Segment(2.6, 4.6, BLACK),                                                 # the card; black from 4.6
    Segment(4.6, 5.0, BLACK),
    Segment(5.0, 5.6, BLACK, rgb_end=(200, 90, 90), texture=tex(4)),          # fade in: middle of the black 4.8
    Segment(5.6, 7.0, (200, 90, 90), texture=tex(4)),
    Segment(7.0, 12.0, BLACK),                                                # cards at 7.0 and 9.0, black at 10.5
))
CARDS_TRUTH = {26: "cut", 48: "fade", 70: "cut", 90: "cut", 105: "cut"}


# Cross-dissolves between shots that both pan (different directions and speeds): the middle is where
# the blend is half-way, though neither end holds still.
PANS = Scene(10.0, name="pans", background=(
    Segment(0.0, 3.37, (150, 110, 70), texture=tex(11), pan=(0.15, 0.0)),
    Segment(3.37, 7.04, (70, 120, 170), texture=tex(12), pan=(-0.1, 0.06), dissolve_s=1.2),
    Segment(7.04, 10.0, (90, 160, 90), texture=tex(13, 0.1), pan=(0.05, -0.12), dissolve_s=1.6),
))
PANS_TRUTH = {34: "dissolve", 70: "dissolve"}


# Cross-dissolves into and out of a hazy shot (pale, low contrast: 16 x 9 thumbnail standard deviation
# about 10 against 17-21 for the others, as the Sintel trailer's desert against its dragon), the shots
# panning: the blend's contrast dips less than between two shots of like contrast.
HAZE = Scene(10.0, name="haze", background=(
    Segment(0.0, 3.0, (190, 120, 70), texture=tex(21, 0.08, 0.45), pan=(0.04, 0.0)),
    Segment(3.0, 6.5, (170, 176, 185), texture=tex(22, 0.25, 0.16), pan=(0.0, 0.03), dissolve_s=1.6),
    Segment(6.5, 10.0, (50, 120, 60), texture=tex(23, 0.08, 0.5), pan=(-0.05, 0.0), dissolve_s=1.2),
))
HAZE_TRUTH = {30: "dissolve", 65: "dissolve"}


def matched(found: np.ndarray, truth: list[int], tol: int = 1) -> tuple[int, list[int]]:
    """Greedy one-to-one matching within ``tol`` ticks: (matches, unmatched found ticks)."""
    free = list(truth)
    extra = []
    for t in found.tolist():
        near = [u for u in free if abs(u - t) <= tol]
        if near:
            free.remove(min(near, key=lambda u: abs(u - t)))
        else:
            extra.append(t)
    return len(truth) - len(free), extra


def film_boundaries(tmp_path, fps: float, size: tuple[int, int], film: Scene = FILM) -> shots.Boundaries:
    path = synth.write_scene(tmp_path / f"{film.name}_{fps}_{size[0]}.mp4", film, width=size[0], height=size[1],
                             fps=fps, audio=False)
    info = media.probe(path)
    n = n_ticks(info.duration_s)
    v = video_pass(info, n, params=resolve_params()[0], need_saliency=np.zeros(n, bool), need_flow=True,
                   need_colour=True)
    return shots.detect(cut=v.cut, signature=v.signature, mean_rgb=v.mean_rgb)


def test_the_dissolves_are_not_hard_cuts():
    assert {2.03, 3.87, 10.9} <= set(FILM.cut_times()) and not {8.62, 14.33} & set(FILM.cut_times())


@pytest.mark.parametrize("fps", [24, 25, 30, 60])
@pytest.mark.parametrize("size", [(160, 90), (320, 180), (640, 360)])
def test_boundaries_known_answers(tmp_path, fps, size):
    b = film_boundaries(tmp_path, fps, size)
    hits, extra = matched(b.tick, sorted(TRUTH))
    precision, recall = hits / max(1, b.tick.size), hits / len(TRUTH)
    assert precision >= 0.95 and recall >= 0.95, (b.tick.tolist(), extra)
    for name, ticks in NOT_CUTS.items():
        assert not set(b.tick.tolist()) & set(ticks), f"{name} made a boundary: {b.tick.tolist()}"
    kinds = {int(t): shots.KINDS[k] for t, k in zip(b.tick, b.kind)}
    for t, kind in TRUTH.items():
        got = [kinds[u] for u in (t - 1, t, t + 1) if u in kinds]
        assert got == [kind], (t, kind, kinds)
    for (s0, s1), t in zip(b.span.tolist(), b.tick.tolist()):
        assert s0 <= t < s1


@pytest.mark.parametrize("fps", [24, 25, 30, 60])
@pytest.mark.parametrize("size", [(160, 90), (320, 180), (640, 360)])
def test_title_cards_known_answers(tmp_path, fps, size):
    b = film_boundaries(tmp_path, fps, size, CARDS)
    hits, extra = matched(b.tick, sorted(CARDS_TRUTH))
    assert hits == len(CARDS_TRUTH) and not extra, (b.tick.tolist(), extra)
    kinds = {int(t): shots.KINDS[k] for t, k in zip(b.tick, b.kind)}
    for t, kind in CARDS_TRUTH.items():
        assert [kinds[u] for u in (t - 1, t, t + 1) if u in kinds] == [kind], (t, kind, kinds)


@pytest.mark.parametrize("fps", [24, 25, 30, 60])
@pytest.mark.parametrize("size", [(160, 90), (320, 180), (640, 360)])
@pytest.mark.parametrize("film, truth", [(PANS, PANS_TRUTH), (HAZE, HAZE_TRUTH)], ids=["panning", "hazy_shot"])
def test_dissolves_between_moving_or_hazy_shots_known_answers(tmp_path, fps, size, film, truth):
    b = film_boundaries(tmp_path, fps, size, film)
    hits, extra = matched(b.tick, sorted(truth))
    assert hits == len(truth) and not extra, (b.tick.tolist(), extra)
    assert [shots.KINDS[k] for k in b.kind] == ["dissolve", "dissolve"]
