"""Overlays burnt in over a film (``video.overlays``, ``media.overlays``) in the video pass: a timecode
found in the pictures sampled before the pass (a long film) or by the pass itself, shot by shot (a
short one), filled in every proxy, so the film reads as it does without one; a watermark across the
picture unblended; a clean film reads exactly as before, and the saliency a refinement computes is the
pass's own."""

from __future__ import annotations

import numpy as np
import pytest

from autohaptics import media, pipeline
from autohaptics import testing as synth
from autohaptics.bench.clips import reencode
from autohaptics.media.overlays import Overlays
from autohaptics.metrics import compare_tracks, headline
from autohaptics.params import GenerateParams, resolve_params
from autohaptics.pipeline.picture import SAMPLED_MIN_S, read_picture
from autohaptics.pipeline.video import frame_weights
from autohaptics.testing.burnin import timecode_box, with_burn_in
from autohaptics.testing.scenes import material_scene
from shared_data import shared_clip

W, H = 320, 180
KEEP = resolve_params("balanced", {"video.overlays": "keep"})[0]


@pytest.fixture(scope="module")
def films(tmp_path_factory):
    d = tmp_path_factory.mktemp("overlays")
    clean = synth.write_scene(d / "clean.mp4", material_scene(24.0), width=W, height=H, fps=24)
    return {"clean": clean, "short": with_burn_in(clean, d / "short.mkv", "timecode"),
            "keyframes": with_burn_in(clean, d / "keyframes.mkv", "timecode", gop=24),
            "watermark": with_burn_in(clean, d / "watermark.mkv", "watermark")}


def _figures(ref, test) -> dict:
    n = min(ref.n_ticks, test.n_ticks)
    report = compare_tracks(ref.vibration[:n], test.vibration[:n], ref.temperature_c[:n], test.temperature_c[:n],
                            ref.fans[:n], test.fans[:n])
    report["n_ticks"] = {"difference": test.n_ticks - ref.n_ticks}
    return headline(report)


@pytest.mark.parametrize("name", ["short", "keyframes"])
def test_a_timecode_is_found_and_the_film_reads_as_without_it(films, name):
    """24 s: too short to search in samples taken before the pass (they could share a shot), with
    three keyframes or 24: the pass searches its four shots and runs again with the timecode filled."""
    clean = pipeline.analyse(films["clean"])
    burnt = pipeline.analyse(films[name])
    kept = pipeline.analyse(films[name], KEEP)
    found = burnt.video.stats["overlays"]
    assert found["found_by"] == "pass" and len(found["boxes"]) == 1
    (x, y, w, h), (bx, by, bw, bh) = found["boxes"][0], timecode_box(W, H)
    assert x <= bx and y <= by and x + w >= bx + bw and y + h >= by + bh and w * h <= 3 * bw * bh
    static = (int(clean.video.static.sum()), int(burnt.video.static.sum()), int(kept.video.static.sum()))
    assert abs(static[1] - static[0]) <= 6, static
    assert kept.video.stats["overlays"] == {"mode": "keep", "found_by": "", "share": 0.0, "translucent": 0.0,
                                            "boxes": []}
    ref = pipeline.derive(clean)
    got, before = _figures(ref, pipeline.derive(burnt)), _figures(ref, pipeline.derive(kept))
    assert got["onset_f1"] >= 0.9 and got["fan_ticks_f1"] >= 0.9 and got["fan_iou_tolerant"] >= 0.8
    assert got["temperature_mae_c"] <= 0.5
    # read as the film's picture, the digits draw the saliency and move the fans' cells (0.73-0.74, 0.69 here)
    assert before["onset_f1"] < 0.8 and before["fan_iou"] < 0.75 and got["fan_iou"] > 0.83


def test_a_watermark_across_the_picture_is_unblended(films):
    """A line of words at 35 % white across the middle: too wide to fill without taking the film under it;
    unblended, the film reads as without it (read as picture, the words draw the saliency and hold the
    flow: onset F1 0.88, exact fan IoU 0.34 here; unblended 0.93 and 0.48)."""
    clean = pipeline.analyse(films["clean"])
    burnt = pipeline.analyse(films["watermark"])
    kept = pipeline.analyse(films["watermark"], KEEP)
    found = burnt.video.stats["overlays"]
    assert found["found_by"] == "pass" and found["share"] == 0.0 and 0.005 < found["translucent"] < 0.08
    assert found["alpha"] and found["colour"] > 180
    for x, y, w, h in found["boxes"]:
        assert y > 0.3 * H and y + h < 0.7 * H
    ref = pipeline.derive(clean)
    got, before = _figures(ref, pipeline.derive(burnt)), _figures(ref, pipeline.derive(kept))
    assert got["onset_f1"] >= 0.9 and got["fan_ticks_f1"] >= 0.9 and got["fan_iou_tolerant"] >= 0.8
    assert got["temperature_mae_c"] <= 0.5
    assert before["onset_f1"] < 0.9 and got["fan_iou"] > before["fan_iou"] + 0.08


def test_a_clean_film_reads_exactly_as_before(films):
    auto = pipeline.analyse(films["clean"])
    keep = pipeline.analyse(films["clean"], KEEP)
    assert auto.video.stats["overlays"]["found_by"] == "" and auto.video.stats["overlays"]["share"] == 0.0
    a, k = pipeline.derive(auto), pipeline.derive(keep)
    for track in ("vibration", "temperature_c", "fans"):
        assert np.array_equal(getattr(a, track), getattr(k, track)), track


@pytest.fixture(scope="module")
def long_clean(tmp_path_factory):
    return synth.write_scene(tmp_path_factory.mktemp("long") / "long.mp4", material_scene(SAMPLED_MIN_S), width=160,
                             height=90, fps=5, quality="low")


def test_a_long_film_is_searched_before_the_pass(long_clean, tmp_path):
    """Three minutes: the nine pictures sampled for the active area, each its own shot, find it."""
    burnt = with_burn_in(long_clean, tmp_path / "long_tc.mkv", "timecode", gop=10)
    for path, found in ((long_clean, False), (burnt, True)):
        picture = read_picture(media.probe(path), GenerateParams())
        assert (picture.overlays is not None) == found and not picture.tally
    (x, y, w, h), (bx, by, bw, bh) = picture.overlays.boxes(160, 90)[0], timecode_box(160, 90)
    assert x <= bx and y <= by and x + w >= bx + bw and y + h >= by + bh


def test_a_long_films_watermark_is_unblended_from_its_nine_samples(long_clean, tmp_path):
    """Nine samples are enough points for the opacity fit: the line of words is unblended, nothing filled."""
    burnt = with_burn_in(long_clean, tmp_path / "long_wm.mkv", "watermark", gop=10)
    overlays = read_picture(media.probe(burnt), GenerateParams()).overlays
    assert overlays is not None and overlays.share == 0.0 and 0.01 < overlays.translucent < 0.08
    assert overlays.colour > 180
    x, y, w, h = max(overlays.boxes(160, 90), key=lambda b: b[2] * b[3])
    assert w > 0.6 * 160 and 0.3 * 90 < y and y + h < 0.7 * 90  # across the middle


@pytest.mark.parametrize("name", ["short", "watermark"])
def test_the_saliency_of_a_refinement_fills_the_same_overlays(films, name):
    params = GenerateParams()
    analysis = pipeline.analyse(films[name], params)
    video = analysis.video
    ticks = np.flatnonzero(video.saliency_mask & video.frame_mask)[::7][:6]
    assert ticks.size >= 3
    info = media.probe(films[name])
    got = frame_weights(info, analysis.n_ticks, ticks, params=params, need_flow=True, need_colour=True,
                        decode=video.stats["frames"]["decode"], overlays=Overlays.from_stats(video.stats["overlays"]))
    for k in ticks:
        assert np.allclose(got[int(k)], video.beta[k], atol=1e-6), k


def test_a_looped_clip_finds_no_overlay(tmp_path):
    """The shared 2 s clip played 8 times in a row (320 x 180, 16 s): each copy's samples repeat the
    first's and add no evidence, so nothing is found (the code before unblended 0.3 % of it: the scene's
    own edges stood in every copy's shots, the opacity fit ran through its two shots' pictures)."""
    loop = reencode(shared_clip("bbb_1080p60_2s_h264_aac6ch.mp4"), tmp_path / "loop.mp4", times=8, size=(320, 180))
    found = pipeline.analyse(loop).video.stats["overlays"]
    assert (found["found_by"], found["share"], found["translucent"]) == ("", 0.0, 0.0)
