"""The tracks are a property of the film, not of its encoding: a generated motion scene, encoded once and
re-encoded the ways a film reaches a user (half size; 25 -> 30 fps by repeated frames; 24 -> 30 fps by
3:2 pulldown; VP9 at a low bit rate; MPEG-2 and HEVC with their B-frames), must give the same fans,
vibration onsets and temperature as the original encode. Also the flow pair's repeated-frame rule on its
own (issue 16, points 3-4).
"""

from __future__ import annotations

from fractions import Fraction

import numpy as np
import pytest

from autohaptics import pipeline
from autohaptics import testing as synth
from autohaptics.params import THESIS_RULES, resolve_params
from autohaptics.testing import Scene, Segment, Texture
from autohaptics.testing.reencode import reencode
from invariance import assert_same_tracks


def tex(seed: int, scale: float = 0.08, contrast: float = 0.35) -> Texture:
    return Texture("noise", scale, contrast, seed=seed)


MOTION = synth.three_motions_scene()

VARIANTS = {
    "half size": (25, dict(width=320, height=180), ".mp4"),
    "25 -> 30 fps, repeated frames": (25, dict(fps=30, conversion="repeat"), ".mp4"),
    "24 -> 30 fps, 3:2 pulldown": (24, dict(fps=30, conversion="pulldown"), ".mp4"),
    "VP9 at 150 kbit/s, Opus": (24, dict(video_codec="libvpx-vp9", video_bit_rate=150_000), ".webm"),
    "VP9 at 150 kbit/s, 25 fps": (25, dict(video_codec="libvpx-vp9", video_bit_rate=150_000), ".webm"),
    # B-frame runs whose skipped frames leave 3-frame gaps (media.video.SKIP_GAP_MAX)
    "MPEG-2, two B-frames (a DVD's)": (25, dict(video_codec="mpeg2video", video_bit_rate=4_000_000,
                                                  video_options={"bf": "2", "g": "15"}), ".mkv"),
    "HEVC, x265 veryfast": (24, dict(video_codec="libx265", video_options={"preset": "veryfast", "crf": "18",
                                                                          "x265-params": "log-level=error"}), ".mp4"),
}


@pytest.fixture(scope="module")
def originals(tmp_path_factory) -> dict:
    d = tmp_path_factory.mktemp("reencode")
    out = {}
    for fps in (24, 25):
        path = synth.write_scene(d / f"motion_{fps}.mp4", MOTION, width=640, height=360, fps=fps)
        out[fps] = (path, pipeline.generate(path))
    return out


@pytest.mark.parametrize("fps, kwargs, suffix", list(VARIANTS.values()), ids=list(VARIANTS))
def test_a_reencode_gives_the_same_fans_vibration_and_temperature(originals, tmp_path, fps, kwargs, suffix):
    src, ref = originals[fps]
    assert_same_tracks(ref, pipeline.generate(reencode(src, tmp_path / f"re{suffix}", **kwargs)))


@pytest.fixture(scope="module")
def repeated_pan(tmp_path_factory):
    """A background panning at 0.2 frame widths/s, 24 fps, converted to 30 fps by repeated frames
    (every fifth frame a repeat: the ticks, three frames apart, meet every phase of the pattern)."""
    d = tmp_path_factory.mktemp("pan")
    # a fine, contrasted texture: every real step of the pan changes enough pixels not to read as
    # a repeat (a smooth one at this speed can: docs/BENCHMARKS.md, "Fans across encodes")
    scene = Scene(2.0, background=(Segment(0, 2.0, (120, 120, 120), texture=tex(4, 0.04, 0.8), pan=(0.2, 0.0)),))
    src = synth.write_scene(d / "pan24.mp4", scene, width=320, height=180, fps=24)
    # no B-frames: every repeat is a reference frame the balanced decode reads (where the encoder puts
    # its B-frames varies between encodes of this libx264, and a skipped B-frame repeat is no repeat)
    return reencode(src, d / "pan30.mp4", fps=30, conversion="repeat", video_options={"bf": "0"})


def test_a_repeat_cadence_times_every_pair_by_its_picture_steps(repeated_pan):
    tl = pipeline.generate(repeated_pan)
    motion = tl.features["motion_fw_per_s"][1:-1]
    # each pair's time counts its steps of the pan, each lasting the mean step (5/4 of an interval), not
    # the frames' intervals (1/24 s of the pan over 1/30 s: 1.25 x its 0.2 frame widths/s); pairs wait
    # for the mean step until enough frames are judged (airflow.cadence.WAIT_S), so from the first tick
    assert np.all(np.abs(motion / 0.2 - 1) < 0.1), motion
    assert tl.stats["video"]["flow"]["cadence_repeats"] > 0
    # without the cadence, a pair two frames apart holds one or two steps of the pan
    params, _ = resolve_params("balanced", {"flow.cadence_ratio": 0.0})
    plain = pipeline.generate(repeated_pan, params=params).features["motion_fw_per_s"][1:-1]
    assert plain.min() < 0.6 * 1.25 * 0.2, plain


PAN = Scene(3.0, background=(Segment(0, 3.0, (120, 120, 120), texture=tex(4, 0.04, 0.8), pan=(0.2, 0.0)),))


@pytest.fixture(scope="module")
def pan24(tmp_path_factory):
    """The pan of ``repeated_pan`` (0.2 frame widths/s), 3 s at 24 fps, as a film's master."""
    d = tmp_path_factory.mktemp("pan24")
    return d, synth.write_scene(d / "pan24.mp4", PAN, width=320, height=180, fps=24)


@pytest.mark.parametrize("fps", [Fraction(60000, 1001), Fraction(120)], ids=["59.94 fps", "120 fps"])
def test_a_24_fps_film_at_a_high_rate_reads_its_own_motion(pan24, fps):
    """A 24 fps film at 59.94 fps (each picture 2 and 3 times in turn, a 720p broadcast) or at 120 fps
    (5 times), coded with x264's B-frames: the pass decodes every frame, since the repeats are told
    from each frame's difference to the one before, and each pair reads its picture steps' own time
    (before: pairs ending on a picture's first frame read up to 2.5 x; the B-frames went undecoded)."""
    d, src = pan24
    tl = pipeline.generate(reencode(src, d / f"pan_{float(fps):.2f}.mp4", fps=fps))
    assert tl.stats["video"]["frames"]["decode"] == "full"
    motion = tl.features["motion_fw_per_s"][1:-1]
    assert np.all(np.abs(motion / 0.2 - 1) < 0.1), motion


def test_a_picture_of_its_own_at_60_fps_skips_the_non_reference_frames(tmp_path):
    tl = pipeline.generate(synth.write_scene(tmp_path / "pan60.mp4", PAN, width=320, height=180, fps=60))
    assert tl.stats["video"]["frames"]["decode"] == "nonref"
    assert tl.stats["video"]["flow"]["cadence_repeats"] == 0
    motion = tl.features["motion_fw_per_s"][1:-1]
    assert np.all(np.abs(motion / 0.2 - 1) < 0.1), motion


def test_a_tick_whose_successor_frame_repeats_still_sees_the_motion(repeated_pan):
    # the pair of the next decoded frame (flow.min_span_frames=0) without the cadence: a successor
    # that repeats the pair's first frame is passed over
    params, _ = resolve_params("balanced", {"flow.min_span_frames": 0.0, "flow.cadence_ratio": 0.0})
    tl = pipeline.generate(repeated_pan, params=params)
    motion = tl.features["motion_fw_per_s"][1:-1]
    # every pair spans one source frame (1/24 s of motion) over its real interval, 1/30 or 2/30 s
    assert motion.min() >= 0.5 * 0.2 and motion.max() <= 1.5 * 0.2, motion
    assert tl.stats["video"]["flow"]["repeats_skipped"] > 0


def test_the_thesis_rule_pairs_the_next_frame_even_when_it_repeats(repeated_pan):
    params, _ = resolve_params("balanced", dict(THESIS_RULES))
    assert params.flow.repeat_wait_s == 0
    tl = pipeline.generate(repeated_pan, params=params)
    motion = tl.features["motion_fw_per_s"][1:-1]
    assert (motion < 0.01).any(), motion  # a tick whose next decoded frame is a repeat reads still
    assert tl.stats["video"]["flow"]["repeats_skipped"] == 0


@pytest.fixture(scope="module")
def fluttering_pan(tmp_path_factory):
    """A fine texture panning 2 px a frame (0.15 frame widths/s at 320 px, 24 fps) that also shakes
    3 px sideways on every other frame, H.264 with one non-reference B-frame between reference frames:
    the balanced decode skips the B-frames (pairs two frames apart), a full decode reads every frame."""
    import av

    path = tmp_path_factory.mktemp("flutter") / "flutter.mp4"
    w, h, fps = 320, 180, 24
    rng = np.random.default_rng(3)
    tex = np.repeat(np.repeat((rng.random((h // 2 + 8, w // 2 + 64)) * 255).astype(np.uint8), 2, 0), 2, 1)
    with av.open(str(path), "w") as out:
        vs = out.add_stream("libx264", rate=fps)
        vs.width, vs.height, vs.pix_fmt = w, h, "yuv420p"
        vs.options = {"crf": "16", "preset": "veryfast",
                      "x264-params": "bframes=1:b-adapt=0:b-pyramid=none:scenecut=0"}
        for i in range(48):
            x = 2 * i + (3 if i % 2 else 0)
            frame = av.VideoFrame.from_ndarray(np.stack([tex[8:8 + h, x:x + w]] * 3, -1), format="rgb24")
            for packet in vs.encode(frame):
                out.mux(packet)
        for packet in vs.encode():
            out.mux(packet)
    return path


def _mean_motion(path, **overrides) -> float:
    params, _ = resolve_params("balanced", overrides)
    return float(pipeline.generate(path, params=params).features["motion_fw_per_s"][1:-1].mean())


def test_a_least_span_reads_the_same_motion_whether_the_decoder_skips_frames_or_not(fluttering_pan):
    # with flow.min_span_frames=1.5 a pair spans two frames whichever frames are decoded, so the
    # flutter between two frames counts alike (docs/BENCHMARKS.md, "Screener encodes", fourth stop)
    full, nonref = (_mean_motion(fluttering_pan, **{"video.decode": d, "flow.min_span_frames": 1.5})
                    for d in ("full", "nonref"))
    assert abs(full / nonref - 1) < 0.15, (full, nonref)
    assert abs(nonref / 0.15 - 1) < 0.25, nonref  # the pan itself: 2 px a frame
    # the thesis's next decoded frame: consecutive frames read the shake as well
    full0, nonref0 = (_mean_motion(fluttering_pan, **{"video.decode": d, "flow.min_span_frames": 0.0})
                      for d in ("full", "nonref"))
    assert full0 > 1.3 * nonref0, (full0, nonref0)
