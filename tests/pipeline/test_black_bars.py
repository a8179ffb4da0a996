"""Black bars are not picture: a motion scene encoded bare and inside bars (letterbox, pillarbox,
windowbox) gives the same fans, vibration onsets and temperature (``video.active_area="auto"``),
the active picture is in the stats, and "full" reads the whole frame as before. The real-clip
check letterboxes the Big Buck Bunny opening."""

from __future__ import annotations

import numpy as np
import pytest

from autohaptics import pipeline
from autohaptics import testing as synth
from autohaptics.params import analysis_key, resolve_params
from autohaptics.records import params_to_dict
from invariance import assert_same_tracks
from shared_data import shared_clip

MOTION = synth.three_motions_scene()

# picture (w, h), frame (w, h), picture's place (x, y, w, h) in the frame
BOXES = {"letterbox": ((640, 360), (640, 480), (0, 60, 640, 360)),
         "pillarbox": ((480, 360), (640, 360), (80, 0, 480, 360)),
         "windowbox": ((480, 270), (640, 360), (80, 44, 480, 270)),
         # bars at RGB 22 (a lifted master; video-range black read as full range is 16)
         "grey letterbox": ((640, 360), (640, 480), (0, 60, 640, 360))}


@pytest.mark.parametrize("box", list(BOXES))
def test_a_film_in_bars_gives_the_tracks_of_the_bare_film(tmp_path, box):
    (pw, ph), (fw, fh), rect = BOXES[box]
    bare = synth.write_scene(tmp_path / "bare.mp4", MOTION, width=pw, height=ph, fps=24)
    boxed = synth.write_scene(tmp_path / "boxed.mp4", MOTION, width=fw, height=fh, fps=24, picture=rect,
                              bar_rgb=(22, 22, 22) if box.startswith("grey") else (0, 0, 0))
    ref, test = pipeline.generate(bare), pipeline.generate(boxed)
    assert ref.stats["video"]["active_area"]["rect"] == [0, 0, pw, ph]
    found = test.stats["video"]["active_area"]
    assert found["frame"] == [fw, fh] and found["mode"] == "auto"
    assert max(abs(a - b) for a, b in zip(found["rect"], rect)) <= 2, found
    assert test.stats["video"]["flow"]["proxy_width"] == ref.stats["video"]["flow"]["proxy_width"]
    assert_same_tracks(ref, test)


def test_full_reads_the_whole_frame_and_a_bare_film_is_unchanged(tmp_path):
    boxed = synth.write_scene(tmp_path / "boxed.mp4", MOTION, width=640, height=480, fps=24, picture=(0, 60, 640, 360))
    bare = synth.write_scene(tmp_path / "bare.mp4", MOTION, width=640, height=360, fps=24)
    full, _ = resolve_params(overrides={"video.active_area": "full"})
    whole = pipeline.generate(boxed, full)
    assert whole.stats["video"]["active_area"] == {**whole.stats["video"]["active_area"], "rect": [0, 0, 640, 480],
                                                   "mode": "full"}
    # no bars: "auto" finds the whole frame and reads exactly what "full" reads
    a, b = pipeline.generate(bare), pipeline.generate(bare, full)
    for name in ("vibration", "temperature_c", "fans"):
        np.testing.assert_array_equal(getattr(a, name), getattr(b, name), err_msg=name)
    # the analysis cache tells the two apart
    auto, _ = resolve_params()
    assert analysis_key(params_to_dict(auto)) != analysis_key(params_to_dict(full))


@pytest.mark.slow
def test_the_letterboxed_big_buck_bunny_opening_gives_the_clean_tracks(tmp_path):
    """The shared 1280x720 opening (30 s) re-encoded as it is and letterboxed into 1280x960."""
    from autohaptics.bench.clips import reencode

    src = shared_clip("bbb_opening_30s_1280x720_vp8_vorbis.webm")
    clean = pipeline.generate(reencode(src, tmp_path / "clean.mp4"))
    boxed = pipeline.generate(reencode(src, tmp_path / "letterbox.mp4", size=(1280, 960)))
    assert boxed.stats["video"]["active_area"]["rect"] == [0, 120, 1280, 720]
    assert_same_tracks(clean, boxed)
