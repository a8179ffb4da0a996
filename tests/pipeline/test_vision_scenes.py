"""The vision path end to end: synthetic scenes with known answers through pipeline.generate
(default parameters), resolution and frame-rate invariance, and the real clips in ../shared/media
(slow tier: five whole clips).

Scenes are written with synth.write_scene (H.264 + AAC, 320x180 @ 24 fps unless stated) into a
temporary folder. Ticks are 100 ms: tick k covers [0.1 k, 0.1 (k + 1)) s.
"""

from __future__ import annotations

import math

import cv2
import numpy as np
import pytest

from autohaptics import airflow, pipeline
from autohaptics import testing as synth
from autohaptics.params import resolve_params
from autohaptics.airflow import cuts
from autohaptics.imaging import resized
from autohaptics.pipeline import video as vision
from autohaptics.pipeline.ticks import centre_frames
from autohaptics.errors import ParameterError
from autohaptics.layout import ACTUATOR_IDS, FAN_COLS
from autohaptics.testing import Noise, Scene, Segment, Shape, Texture, Tone
from autohaptics.timebase import tick_of_time
from autohaptics.timeline import Timeline
from shared_data import SHARED_CLIPS, shared_clip

IDX = {a: i for i, a in enumerate(ACTUATOR_IDS)}
LEFT = [IDX[a] for a in ("A1", "A3", "A4", "A8")]
RIGHT = [IDX[a] for a in ("A2", "A6", "A7", "A9")]
FLOOR = airflow.AirflowParams().floor


def tex(seed: int, scale: float = 0.08, contrast: float = 0.3) -> Texture:
    return Texture("noise", scale, contrast, seed=seed)


# The approaching object: a textured disc growing from 8 % to 36 % of the frame width in 2 s.
APPROACH = Shape("circle", (235, 140, 40), t_on=0.5, t_off=2.5, xy0=(0.78, 0.5), size0=(0.08, 0.14),
                 size1=(0.36, 0.64), texture=Texture("noise", 0.25, 0.5, seed=6))

SCENES = {
    # (1) a bright disc in the left third; a 50 Hz burst at 1.0-2.0 s
    "left_object_boom": Scene(3.0, background=(Segment(0, 3, (45, 50, 65), texture=tex(1)),),
                              shapes=(Shape("circle", (255, 255, 245), t_on=0.3, t_off=2.7, xy0=(0.17, 0.5),
                                            size0=(0.15, 0.27)),),
                              audio=(Tone(1.0, 2.0, 50.0, level_dbfs=-14.0, ramp_s=0.02),)),
    # (2) black picture, loud white noise at 0.5-1.5 s
    "dark_loud": Scene(2.0, background=(Segment(0, 2, (0, 0, 0)),), audio=(Noise(0.5, 1.5, level_dbfs=-10.0, seed=3),)),
    # (3) red, grey, green shots of one second each
    "colours": Scene(3.0, background=(Segment(0, 1, (220, 30, 30), texture=tex(2)),
                                      Segment(1, 2, (128, 128, 128), texture=tex(3)),
                                      Segment(2, 3, (30, 200, 40), texture=tex(4)))),
    # (4) something rushing at the camera in the right half, with a whoosh
    "approach_right": Scene(3.0, background=(Segment(0, 3, (110, 110, 115), texture=tex(5, 0.05)),), shapes=(APPROACH,),
                            audio=(Noise(0.5, 2.5, level_dbfs=-20.0, colour="pink", seed=7, ramp_s=0.3),)),
    # (5) a hard cut at 1.52 s between two static shots: inside the flow pair of tick 15
    #     (frames at 1.500 and 1.542 s)
    "cut_static": Scene(3.0, background=(Segment(0, 1.52, (60, 90, 160), texture=tex(8, 0.15, 0.5)),
                                         Segment(1.52, 3, (170, 120, 60), texture=tex(9, 0.15, 0.5)))),
    # (6) one static shot
    "static": Scene(2.0, background=(Segment(0, 2, (90, 120, 80), texture=tex(10, 0.1, 0.4)),),
                    shapes=(Shape("rect", (240, 230, 90), xy0=(0.3, 0.6), size0=(0.2, 0.2)),)),
}


@pytest.fixture(scope="module")
def generated(tmp_path_factory) -> dict[str, tuple[Scene, Timeline]]:
    d = tmp_path_factory.mktemp("scenes")
    out = {}
    for name, scene in SCENES.items():
        path = synth.write_scene(d / f"{name}.mp4", scene)
        out[name] = (scene, pipeline.generate(path))
    return out


def active(tl: Timeline) -> np.ndarray:
    return np.flatnonzero(tl.vibration.max(axis=1) > 0)


# ---------------------------------------------------------------- (1) .. (6)
def test_bright_object_on_the_left_with_a_low_burst_drives_the_left_actuators(generated):
    _, tl = generated["left_object_boom"]
    ticks = active(tl)
    assert set(range(10, 20)) <= set(ticks) and set(ticks) <= set(range(10, 22))  # the burst, plus its release
    vib = tl.vibration[10:20]
    assert vib.max() >= 0.9  # the only sound of the clip: full intensity
    peak = vib.max(axis=1)
    np.testing.assert_allclose(vib[:, LEFT].max(axis=1), peak)  # a left actuator leads every tick
    assert (vib[:, RIGHT].max(axis=1) < 0.3 * peak).all(), vib.round(2)
    assert tl.stats["video"]["saliency"]["ticks_computed"] == ticks.size  # saliency only where it vibrates


def test_dark_frame_with_a_loud_sound_vibrates_a5_only(generated):
    _, tl = generated["dark_loud"]
    ticks = active(tl)
    assert set(range(5, 15)) <= set(ticks)
    vib = tl.vibration[ticks]
    assert vib[:, IDX["A5"]].min() > 0.5
    np.testing.assert_array_equal(np.delete(vib, IDX["A5"], axis=1), 0.0)


def test_red_is_hotter_than_neutral_is_hotter_than_green(generated):
    _, tl = generated["colours"]
    t = tl.features["temperature_target_c"]  # the mapping, before the chair's slew limit
    red, grey, green = t[1:9], t[11:19], t[21:29]  # away from the cuts at 1 s and 2 s
    assert red.min() > grey.max() and grey.min() > green.max()
    np.testing.assert_allclose(grey, 33.0, atol=1.0)  # grey is skin-neutral
    assert red.min() > 37.0 and green.max() < 29.0
    assert np.abs(np.diff(tl.temperature_c)).max() <= 0.1 + 2e-4  # the chair's curve: 1 C/s


def test_object_rushing_at_the_camera_on_the_right_blows_only_right_fans(generated):
    _, tl = generated["approach_right"]
    on = np.flatnonzero(tl.fans.max(axis=(1, 2)) > 0)
    assert on.size >= 5 and on.min() >= 5 and on.max() <= 25  # while the disc grows (0.5-2.5 s)
    cols = np.flatnonzero(tl.fans.max(axis=(0, 1)) > 0)
    assert cols.min() >= 9, cols  # column 9 starts at x = 9/17 = 0.53: the right half only
    assert tl.fans.max() == 1.0


@pytest.mark.parametrize("overrides, width", [({}, 160), ({"flow.proxy_fraction": "0.5"}, 320),
                                              ({"flow.proxy_fraction": "0"}, 160)])
def test_the_flow_proxy_follows_the_picture_width(tmp_path, overrides, width):
    # 640 px wide: 1/8 of it is 80 px, so the default keeps its 160 px; half of it is 320 px
    path = synth.write_scene(tmp_path / "approach.mp4", SCENES["approach_right"], width=640, height=360)
    params, _ = resolve_params("balanced", overrides)
    tl = pipeline.generate(path, params)
    assert tl.stats["video"]["flow"]["proxy_width"] == width
    assert tl.generator["params"]["flow"]["proxy_width"] == 160  # the knob as set; the stats say what ran
    cols = np.flatnonzero(tl.fans.max(axis=(0, 1)) > 0)
    assert cols.size and cols.min() >= 9, cols  # the same answer at any proxy: the right half


def test_no_airflow_at_a_hard_cut_between_two_static_shots(generated, tmp_path):
    scene, tl = generated["cut_static"]
    assert tl.stats["video"]["cuts"]["cuts"] >= 1 and tl.stats["airflow"]["ticks_at_cuts"] >= 1
    assert tl.stats["video"]["flow"]["ticks_computed"] == 0  # static pairs skipped, the cut pair too
    assert not tl.fans.any()
    assert tl.features["motion_fw_per_s"][15] == 0.0
    # Not vacuous: flow across the cut pair reads as strong motion, which would have blown (the
    # adaptive threshold of a clip whose only moving tick this is would be the floor).
    g0, g1 = (cv2.cvtColor(synth.render_frame(scene, t, width=160, height=90), cv2.COLOR_RGB2GRAY)
              for t in (1.5, 1.5 + 1 / 24))
    across = airflow.motion_score(airflow.motion_magnitude(airflow.optical_flow(g0, g1), dt_s=1 / 24, width_px=160))
    assert across > 10 * FLOOR


def test_a_change_spread_over_the_frames_between_two_ticks_is_not_a_cut_and_a_hard_cut_is(tmp_path):
    """At 40 fps the ticks' frames are 4 intervals apart (1.05, 1.15 s, ...) and each flow pair ends on the
    frame half-way (1.10 s). A dark wing half the frame wide sweeps in between 1.05 and 1.15 s, as
    fast action does between the analysed frames of a decode that skips frames: each step changes the
    picture by half, no cut; the shot changes at 2.075 s, within one step: a cut (tick 21, and tick
    20, whose pair crosses it). With ``cuts.in_one_step=False`` (the rule before) the wing is a cut."""
    w = 0.5
    scene = Scene(3.0, background=(Segment(0, 2.075, (70, 110, 170), texture=tex(1, 0.1, 0.4)),
                                   Segment(2.075, 3.0, (170, 120, 60), texture=tex(2, 0.1, 0.4))),
                  shapes=(Shape("rect", (110, 80, 60), t_off=2.075, xy0=(-w / 2, 0.5), xy1=(w / 2, 0.5),
                                size0=(w, 1.0), move_t0=1.05, move_t1=1.15, texture=tex(3, 0.2, 0.5)),))
    path = synth.write_scene(tmp_path / "wing.mp4", scene, fps=40)
    flagged, spread = {}, {}
    for one_step in (True, False):
        params, _ = resolve_params(overrides={"video.decode": "full", "cuts.in_one_step": one_step})
        video = pipeline.analyse(path, params).video
        flagged[one_step], spread[one_step] = np.flatnonzero(video.cut).tolist(), video.stats["cuts"]["spread"]
    assert flagged[True] == [20, 21] and spread[True] == 1
    assert flagged[False] == [11, 20, 21] and spread[False] == 0
    sig = [cuts.frame_signature(resized(synth.render_frame(scene, t, width=320, height=180), 48))
           for t in (1.05, 1.10, 1.15)]  # the premise, on the pictures as drawn
    assert cuts.cut_score(sig[0], sig[2]) >= 0.55
    assert max(cuts.cut_score(sig[0], sig[1]), cuts.cut_score(sig[1], sig[2])) <= 0.45


def test_a_cut_through_a_telecined_frame_is_a_cut(tmp_path):
    """3:2 pulldown puts a cut's two shots into one frame, one in each field. At 30 fps the ticks' frames
    are 3 intervals apart (1.033, 1.133 s) and the flow pair ends on the frame between (1.1 s): here that
    frame is the combed one, so each step changes the picture by half (below the cut bar, as drawn), its
    two fields by all of it: a cut (tick 11), as under the rule before (``cuts.in_one_step=false``)."""
    import av

    w, h = 320, 180

    def shot(rgb, seed):
        grain = cv2.resize((np.random.default_rng(seed).random((h // 8, w // 8)) * 120).astype(np.float32), (w, h))
        return np.clip(np.array(rgb, np.float32) + grain[..., None] - 60, 0, 255).astype(np.uint8)

    a, b = shot((60, 90, 160), 1), shot((170, 120, 60), 2)
    combed = a.copy()
    combed[1::2] = b[1::2]
    path = tmp_path / "telecined.mp4"
    with av.open(str(path), "w") as out:
        vs = out.add_stream("libx264", rate=30)
        vs.width, vs.height, vs.pix_fmt = w, h, "yuv420p"
        vs.options = {"crf": "16", "preset": "veryfast", "x264-params": "bframes=0:scenecut=0"}
        for picture in [a] * 33 + [combed] + [b] * 26:
            for packet in vs.encode(av.VideoFrame.from_ndarray(picture, format="rgb24")):
                out.mux(packet)
        for packet in vs.encode():
            out.mux(packet)
    for one_step in (True, False):
        params, _ = resolve_params(overrides={"video.decode": "full", "cuts.in_one_step": one_step})
        video = pipeline.analyse(path, params).video
        assert np.flatnonzero(video.cut).tolist() == [11] and video.stats["cuts"]["spread"] == 0
    sig = [cuts.frame_signature(resized(picture, 48)) for picture in (a, combed, b)]
    assert cuts.cut_score(sig[0], sig[2]) >= 0.9
    assert max(cuts.cut_score(sig[0], sig[1]), cuts.cut_score(sig[1], sig[2])) <= 0.4


def test_a_fade_in_of_a_still_picture_has_no_motion_even_in_the_reference(tmp_path):
    """A still textured picture fading in from black over 2 s: the reference (no skipping, every
    frame) reads no motion and blows no fan. Not vacuous: with the fade check switched off the
    same reference run reads the brightness ramp as motion."""
    scene = Scene(2.5, background=(Segment(0, 2.0, (2, 2, 2), rgb_end=(200, 190, 170), texture=tex(11, 0.05, 0.5)),
                                   Segment(2.0, 2.5, (200, 190, 170), texture=tex(11, 0.05, 0.5))))
    path = synth.write_scene(tmp_path / "fade.mp4", scene, width=320, height=180, fps=24, audio=False)
    params, _ = resolve_params("reference")
    tl = pipeline.generate(path, params, preset="reference")
    assert not tl.fans.any()
    assert float(np.max(tl.features["motion_fw_per_s"])) == 0.0
    off, _ = resolve_params("reference", {"airflow.flat_std": 0, "airflow.fade_min_step": 255})
    unguarded = pipeline.analyse(path, off).video
    assert float(unguarded.motion.max()) > FLOOR, unguarded.motion


def test_static_shot_computes_no_flow(generated):
    _, tl = generated["static"]
    n = tl.vibration.shape[0]
    flow = tl.stats["video"]["flow"]
    assert flow["ticks_skipped"] == n and flow["ticks_computed"] == 0
    assert tl.stats["video"]["static"]["ticks_static"] == n
    assert tl.stats["video"]["depth"]["ticks_computed"] == 0
    assert not tl.fans.any() and not tl.features["motion_fw_per_s"].any()


# ---------------------------------------------------------------- invariance
INVARIANT = Scene(
    5.0,
    background=(Segment(0, 1.5, (200, 40, 35), texture=tex(1)), Segment(1.5, 2.5, (40, 170, 60), texture=tex(2)),
                Segment(2.5, 5.0, (110, 110, 115), texture=tex(3, 0.05))),
    shapes=(Shape("circle", (255, 255, 245), t_on=0.2, t_off=1.4, xy0=(0.2, 0.45), size0=(0.16, 0.28)),
            Shape("circle", (235, 140, 40), t_on=2.8, t_off=4.8, xy0=(0.76, 0.5), size0=(0.08, 0.14),
                  size1=(0.4, 0.7), texture=Texture("noise", 0.25, 0.5, seed=6))),
    audio=(Tone(0.3, 1.2, 50.0, level_dbfs=-14.0, ramp_s=0.02), Tone(1.8, 2.0, 2000.0, level_dbfs=-22.0),
           Noise(3.0, 4.6, level_dbfs=-18.0, colour="pink", seed=7, ramp_s=0.2)),
    name="invariance",
)


def agreement(a: Timeline, b: Timeline) -> dict:
    """Vibration MAE, temperature MAE (C) and fan-cell IoU over the common ticks. The IoU is over
    the sets of (tick, row, col) cells that are on, on ticks where either side has a fan on."""
    n = min(a.vibration.shape[0], b.vibration.shape[0])
    fa, fb = a.fans[:n] > 0, b.fans[:n] > 0
    either = fa.any(axis=(1, 2)) | fb.any(axis=(1, 2))
    union = int((fa | fb)[either].sum())
    return {
        "ticks": n,
        "vibration_mae": float(np.abs(a.vibration[:n] - b.vibration[:n]).mean()),
        "temperature_mae": float(np.abs(a.temperature_c[:n] - b.temperature_c[:n]).mean()),
        "fan_iou": float((fa & fb)[either].sum() / union) if union else 1.0,
        "fan_ticks": (int(fa.any(axis=(1, 2)).sum()), int(fb.any(axis=(1, 2)).sum())),
        "fan_cells": union,
    }


@pytest.fixture(scope="module")
def invariance_pair(tmp_path_factory) -> tuple[Timeline, Timeline]:
    d = tmp_path_factory.mktemp("invariance")
    small = synth.write_scene(d / "small.mp4", INVARIANT, width=320, height=180, fps=24)
    large = synth.write_scene(d / "large.mp4", INVARIANT, width=1280, height=720, fps=30)
    return pipeline.generate(small), pipeline.generate(large)


def test_resolution_and_frame_rate_invariance(invariance_pair):
    small, large = invariance_pair
    r = agreement(small, large)
    print("320x180@24 vs 1280x720@30:", r)
    # not vacuous: both vibrate, change temperature and blow
    for tl in (small, large):
        assert active(tl).size >= 15
        assert np.ptp(tl.features["temperature_target_c"]) > 5.0  # the mapping before the chair's 1 C/s
        assert np.ptp(tl.temperature_c) > 1.0
        assert tl.fans.any(axis=(1, 2)).sum() >= 5
    assert r["vibration_mae"] <= 0.02
    assert r["temperature_mae"] <= 0.5
    targets = [tl.features["temperature_target_c"] for tl in (small, large)]
    assert np.abs(targets[0][:r["ticks"]] - targets[1][:r["ticks"]]).mean() <= 0.5


def test_resolution_and_frame_rate_invariance_of_the_fans(invariance_pair):
    r = agreement(*invariance_pair)
    assert r["fan_iou"] >= 0.9


# ---------------------------------------------------------------- real clips
@pytest.fixture(scope="module")
def clip_timelines() -> dict[str, Timeline]:
    return {}


def clip_timeline(cache: dict, name: str) -> Timeline:
    if name not in cache:
        cache[name] = pipeline.generate(shared_clip(name))
    return cache[name]


@pytest.mark.slow
@pytest.mark.parametrize("name", SHARED_CLIPS)
def test_every_shared_clip_generates_a_valid_timeline(clip_timelines, name):
    tl = clip_timeline(clip_timelines, name)
    n = math.ceil(tl.source["duration_s"] / 0.1 - 1e-6)
    assert tl.vibration.shape == (n, 9) and tl.fans.shape == (n, 9, FAN_COLS) and tl.temperature_c.shape == (n,)
    for arr, lo, hi in ((tl.vibration, 0, 1), (tl.fans, 0, 1), (tl.temperature_c, 18, 40)):
        assert np.isfinite(arr).all() and arr.min() >= lo and arr.max() <= hi
    assert tl.generator["mode"] == "multimodal"
    Timeline.from_json(tl.to_json()).validate()
    if tl.source["duration_s"] >= 10.0:
        assert active(tl).size > 0  # every clip of some length has sound that vibrates
    else:  # the 2 s excerpts start inside their sound: their start is no event (issue 31)
        assert not tl.vibration[:5].any()


SINTEL = ("sintel_trailer_640x272_vp8_vorbis.webm", "sintel_trailer_480x204_h264_aac.mp4")


@pytest.fixture(scope="module")
def sintel(clip_timelines) -> dict:
    a, b = (clip_timeline(clip_timelines, name) for name in SINTEL)
    r = agreement(a, b)
    print("Sintel VP8 640x272 vs H.264 480x204 over the common ticks:", r)
    return r


@pytest.mark.slow
def test_sintel_encodes_agree_on_vibration_and_temperature(sintel):
    assert sintel["ticks"] >= 520  # 52.2 s in common (the VP8 encode runs 0.5 s longer)
    assert sintel["vibration_mae"] <= 0.02
    assert sintel["temperature_mae"] <= 0.5


@pytest.mark.slow
@pytest.mark.parametrize("name", SINTEL)
def test_sintel_temperature_uses_the_device_range_without_sitting_at_a_limit(clip_timelines, name):
    """Snow and fire: the chair's curve spans >= 4 C with < 10 % of ticks within 0.1 C of 18 or 40 C."""
    t = clip_timeline(clip_timelines, name).temperature_c
    at_limit = float(np.mean((t <= 18.1) | (t >= 39.9)))
    print(name, f"{t.min():.2f}..{t.max():.2f} C, {100 * at_limit:.1f} % of ticks at a limit")
    assert np.ptp(t) >= 4.0 and at_limit < 0.10


@pytest.mark.slow
def test_sintel_encodes_agree_on_which_ticks_blow(sintel, clip_timelines):
    a, b = (clip_timelines[name] for name in SINTEL)
    n = sintel["ticks"]
    on_a, on_b = a.fans[:n].any(axis=(1, 2)), b.fans[:n].any(axis=(1, 2))
    assert on_a.sum() >= 20
    assert (on_a != on_b).sum() <= 0.05 * (on_a | on_b).sum()


@pytest.mark.slow
def test_sintel_encodes_agree_on_fan_cells(sintel):
    """Fan cells of the two encodes (exact IoU); they agree since the tick rule judges motion
    smoothed over the shot (airflow.motion_sigma_ticks; docs/BENCHMARKS.md, "Screener encodes")."""
    assert sintel["fan_iou"] >= 0.9


# ---------------------------------------------------------------- stride (the fast preset)
class _Timed:
    """A decoded frame as :func:`centre_frames` sees it: its time only."""

    def __init__(self, t: float):
        self.time_s = t


@pytest.mark.parametrize("fps,stride,n", [(60, 2, 20), (24, 2, 25), (30, 3, 10), (60, 1, 7), (5, 2, 8), (15, 4, 9)])
def test_each_group_of_ticks_gets_the_frame_nearest_its_centre(fps, stride, n):
    frames = [_Timed(i / fps) for i in range(int(n * 0.1 * fps) + 3)]  # a few past the last tick
    out = list(centre_frames(iter(frames), n, stride))
    assert [f for f, _ in out] == frames  # every frame once, in order
    chosen = {k: f.time_s for f, k in out if k is not None}
    expected = {}
    for g in range(0, n, stride):
        inside = [f.time_s for f in frames if min(tick_of_time(f.time_s), n - 1) // stride * stride == g]
        if inside:
            centre = (g + 0.5 * min(stride, n - g)) * 0.1
            expected[g] = min(inside, key=lambda t: abs(t - centre))
    assert chosen == expected


@pytest.mark.parametrize("stride", [2, 3])
def test_a_stride_analyses_one_tick_per_group_and_the_group_shares_its_values(generated, tmp_path, stride):
    path = synth.write_scene(tmp_path / "boom.mp4", SCENES["left_object_boom"])
    params, _ = resolve_params("balanced", {"video.stride": str(stride)})
    analysis = pipeline.analyse(path, params)
    v = analysis.video
    n = v.motion.size
    assert n == 30 and v.frame_mask[0::stride].all()
    for j in range(1, stride):
        assert not v.frame_mask[j::stride].any()
        for name in ("mean_rgb", "beta", "saliency_mask", "motion", "cell_motion", "nearness", "static"):
            arr = getattr(v, name)
            np.testing.assert_array_equal(arr[j::stride], arr[0::stride], err_msg=name)
    stats = analysis.stats["video"]
    for stage, mask in (("flow", v.flow_mask), ("saliency", v.saliency_mask), ("depth", v.depth_mask)):
        # a held tick counts as held where its group's analysed tick computed the stage, else skipped
        analysed = np.flatnonzero(v.frame_mask)
        computed = mask[analysed]
        held = sum(int(mask[g]) * (min(stride, n - g) - 1) for g in analysed)
        assert stats[stage]["ticks_computed"] == computed.sum(), stage
        assert stats[stage]["ticks_held"] == held, stage
        assert stats[stage]["ticks_computed"] + stats[stage]["ticks_skipped"] + held == n, stage
    # not vacuous: saliency is held, and the scene's still stretches skip the flow of ticks that
    # would all count as held if a held tick did not look at what its analysed tick computed
    assert stats["saliency"]["ticks_held"] > 0 and stats["flow"]["ticks_held"] < n - n // stride
    tl = pipeline.derive(analysis, params)
    assert tl.generator["params"]["video"]["stride"] == stride
    # the same answer as every tick read: the bright disc on the left leads the burst
    _, every = generated["left_object_boom"]
    vib = tl.vibration[10:20]
    np.testing.assert_allclose(vib[:, LEFT].max(axis=1), vib.max(axis=1))
    assert float(np.abs(tl.vibration - every.vibration).mean()) < 0.02
    np.testing.assert_allclose(tl.temperature_c, every.temperature_c, atol=0.5)


def test_the_fast_preset_reads_the_picture_for_every_third_tick():
    params, _ = resolve_params("fast", {})
    assert params.video.stride == 3 and params.video.decode == "sparse"
    assert resolve_params("fast", {"video.stride": "1"})[0].video.stride == 1  # still overridable


@pytest.mark.parametrize("overrides", [{"video.stride": "0"}, {"video.stride": "11"}, {"video.stride": "1.5"},
                                       {"video.stride": "2", "video.analysis": "every"}])
def test_stride_out_of_range_or_with_every_frame_analysis_is_refused(overrides):
    with pytest.raises(ParameterError, match="video.stride"):
        resolve_params("balanced", overrides)
