"""3D films packed in one picture (``media.stereo``, ``media.active.find_picture``, the video pass):
the packing a file declares (Matroska's StereoMode, H.264's frame-packing message) or its pictures show
is found, a 2D film's never is, and the film is read from its first view, at the aspect it is shown,
as its 2D release is (``testing.stereo`` writes the 3D films from 2D ones)."""

from __future__ import annotations

import cv2
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from autohaptics import pipeline
from autohaptics import testing as synth
from autohaptics.bench.matrix import misses, row_figures
from autohaptics.bench.variants import VARIANTS
from autohaptics.media import Frame, find_picture, probe
from autohaptics.media.active import picture_packing, sample_lumas
from autohaptics.media.stereo import halves, view_aspect, view_rect
from autohaptics.params import resolve_params
from autohaptics.testing.scenes import material_scene
from autohaptics.testing.stereo import packed, write_packed
from shared_data import shared_clip


@pytest.fixture(scope="module")
def small(tmp_path_factory):
    d = tmp_path_factory.mktemp("stereo")
    return d, synth.write_scene(d / "small.mp4", material_scene(6.0), width=320, height=180, fps=25)


@pytest.mark.parametrize("packing", ["side_by_side", "top_bottom"])
def test_the_packing_declared_or_shown_is_found_and_one_view_read(small, packing):
    d, src = small
    for declared, suffix in (("container", ".mkv"), ("h264", ".mp4"), ("none", ".mkv")):
        path = write_packed(src, d / f"{packing}_{declared}{suffix}", packing, declared=declared)
        info = probe(path)
        assert info.video.stereo == ("" if declared == "none" else packing)
        rect, found = find_picture(info)
        assert found == packing and rect == view_rect(320, 180, packing)
        assert find_picture(info, "2d") == ((0, 0, 320, 180), "")


def test_a_2d_films_halves_are_not_taken_for_two_views(small):
    """The shared clips (one letterboxed) and the tests' scene: neither packing (their halves' likeness
    stays far under the bar), while the same scene packed is found."""
    d, src = small
    for path in (shared_clip("bbb_opening_30s_1280x720_vp8_vorbis.webm"),
                 shared_clip("sintel_trailer_640x272_vp8_vorbis.webm"), src):
        info = probe(path)
        assert picture_packing(sample_lumas(info)) == ""
        assert find_picture(info) == ((0, 0, *info.video.display_size), "")


def test_views_their_aspect_and_the_proxies_that_keep_it():
    rgb = np.random.default_rng(1).integers(0, 255, (90, 160, 3), dtype=np.uint8)
    for packing, shape in (("side_by_side", (90, 80, 3)), ("top_bottom", (45, 160, 3))):
        left, right = halves(packed(rgb, packing), packing)
        assert left.shape == right.shape == shape
    assert view_aspect(960 / 1080, 16 / 9, "side_by_side") == pytest.approx(16 / 9)  # half width
    assert view_aspect(1920 / 1080, 32 / 9, "side_by_side") == pytest.approx(16 / 9)  # full width: as stored
    assert view_aspect(1920 / 540, 16 / 9, "top_bottom") == pytest.approx(16 / 9)
    assert view_aspect(1920 / 1080, 1920 / 2160, "top_bottom") == pytest.approx(16 / 9)
    assert view_aspect(1.5, 1.5, "") == 1.5
    import av

    frame = av.VideoFrame.from_ndarray(rgb, format="rgb24").reformat(format="yuv420p")
    assert Frame(frame, 0, 0.0, 0, (0, 0, 80, 90)).gray(40).shape == (45, 40)  # as stored: 80 x 90
    assert Frame(frame, 0, 0.0, 0, (0, 0, 80, 90), 16 / 9).gray(40).shape == (22, 40)  # as shown: 16:9


@pytest.fixture(scope="module")
def scene(tmp_path_factory):
    d = tmp_path_factory.mktemp("stereo_scene")
    src = synth.write_scene(d / "scene.mp4", material_scene(), width=640, height=360, fps=25)
    return d, src, pipeline.derive(pipeline.analyse(src))


@pytest.mark.parametrize("packing", ["side_by_side", "top_bottom"])
def test_a_3d_film_gives_what_its_2d_release_gives(scene, packing):
    """Read from its first view the packed film meets the matrix's targets against the 2D film, its fans
    cell for cell (exact IoU 0.9 or more); read whole, both views blow (exact IoU under 0.8 side by side)."""
    d, src, clean = scene
    path = write_packed(src, d / f"{packing}.mkv", packing, declared="none")
    test = pipeline.derive(pipeline.analyse(path))
    fig = row_figures(clean, test, VARIANTS[0])
    assert test.stats["video"]["active_area"]["stereo"] == packing
    assert misses(fig) == [] and fig["fan_iou"] >= 0.9, fig
    if packing == "side_by_side":
        whole = pipeline.derive(pipeline.analyse(path, resolve_params(overrides={"video.stereo": "2d"})[0]))
        assert whole.stats["video"]["active_area"]["stereo"] == "2d"
        assert row_figures(clean, whole, VARIANTS[0])["fan_iou"] < 0.8


def _scenes(seed: int, n: int = 5, size: tuple[int, int] = (320, 180)) -> list[np.ndarray]:
    """``n`` pictures of one random 2D scene (smooth blobs of light over a smooth ground, drifting), RGB uint8."""
    rng = np.random.default_rng(seed)
    w, h = size
    ground = cv2.resize(rng.integers(0, 256, (4, 6, 3), dtype=np.uint8), (w, h), interpolation=cv2.INTER_CUBIC)
    out = []
    for k in range(n):
        pic = ground.copy()
        for _ in range(int(rng.integers(2, 7))):
            x, y = int(rng.integers(0, w)) + 8 * k, int(rng.integers(0, h))
            cv2.circle(pic, (x % w, y), int(rng.integers(6, 40)), tuple(int(v) for v in rng.integers(0, 256, 3)), -1)
        out.append(pic)
    return out


@settings(max_examples=40, deadline=None)
@given(st.integers(0, 2**31 - 1), st.sampled_from(["side_by_side", "top_bottom"]))
def test_random_scenes_are_2d_and_their_packed_views_are_3d(seed, packing):
    """Property: the pictures of a random 2D scene are never taken for a packing; the same pictures with a
    parallax and packed (``testing.stereo.packed``) always are, and only as that packing."""
    scenes = _scenes(seed)
    gray = [cv2.cvtColor(p, cv2.COLOR_RGB2GRAY) for p in scenes]
    assert picture_packing(gray) == ""
    packed_gray = [cv2.cvtColor(packed(p, packing), cv2.COLOR_RGB2GRAY) for p in scenes]
    assert picture_packing(packed_gray) == packing
