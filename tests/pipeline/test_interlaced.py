"""Interlaced video (1080i and 576i broadcasts, a hard-telecined DVD): each frame holds two fields, each a
moment of its own, coded as such (x264 ``interlaced=1``, so the decoder flags the frames). Its small
proxies come from the top field alone (``media.frames``): a frame's two fields side by side show what moves
twice, combed, and the flow between such pictures reads both copies. Known answers on synthetic frames, and
a real 1080p60 clip as a 1080i broadcast against its progressive twin."""

from __future__ import annotations

import av
import numpy as np
import pytest

from autohaptics import media, pipeline
from autohaptics.metrics import compare_timelines
from shared_data import shared_clip
from stress_inputs import write_streams

FPS = 30  # frames a second, fields 60


def _write(path, pictures, *, interlaced: bool):
    """``pictures`` (RGB uint8 frames) as H.264 at ``FPS``, coded interlaced (top field first) or not."""
    coding = {"x264-params": "interlaced=1:tff=1"} if interlaced else {}
    return write_streams(path, frames=pictures, fps=FPS, video_options={"preset": "veryfast", "crf": "14", **coding})


def _flagged(path) -> list[bool]:
    """Whether each decoded frame of ``path`` is flagged interlaced."""
    with av.open(str(path)) as c:
        return [f.interlaced_frame for f in c.decode(c.streams.video[0])]


def _decoded(path) -> list[media.Frame]:
    with av.open(str(path)) as c:
        return [media.Frame(f, i, float(f.time), 0) for i, f in enumerate(c.decode(c.streams.video[0]))]


def test_an_interlaced_frames_small_proxies_are_its_top_field(tmp_path):
    """A bright block on the left in the top field (even rows), on the right in the bottom field: the
    small proxies show the left block alone (a blend of both fields read both blocks at half
    brightness); the full-size copy keeps both fields; the same picture coded progressive is a blend."""
    img = np.full((144, 256, 3), 30, np.uint8)
    img[0::2, 16:96] = 230  # top field
    img[1::2, 160:240] = 230  # bottom field
    for interlaced in (True, False):
        path = _write(tmp_path / f"i{interlaced}.mp4", [img] * 4, interlaced=interlaced)
        assert _flagged(path) == [interlaced] * 4
        frame = _decoded(path)[2]
        gray = frame.gray(64).astype(int)
        rgb = frame.rgb_and_gray(64, 64)[0].astype(int)
        left, right = gray[:, 8:20].mean(), gray[:, 44:56].mean()
        if interlaced:
            assert left > 200 and right < 60, (left, right)
            assert rgb[:, 8:20].mean() > 200 and rgb[:, 44:56].mean() < 60
        else:
            assert 110 < left < 150 and 110 < right < 150, (left, right)
        full = frame.full(fmt="gray").astype(int)
        assert full[0::2, 30:80].mean() > 200 and full[1::2, 30:80].mean() < 60  # both fields, as decoded


@pytest.fixture(scope="module")
def broadcast(tmp_path_factory):
    """The shared 1080p60 clip (2 s) as 1080 lines at 30 frames a second: progressive (its even frames),
    and interlaced from its 60 pictures a second (each frame's top field an even frame's, its bottom
    field the next frame's), as a 1080i broadcast carries it. Returns (progressive, interlaced)."""
    with av.open(str(shared_clip("bbb_1080p60_2s_h264_aac6ch.mp4"))) as c:
        pictures = [f.to_ndarray(format="rgb24") for f in c.decode(c.streams.video[0])]
    woven = []
    for top, bottom in zip(pictures[0::2], pictures[1::2]):
        both = top.copy()
        both[1::2] = bottom[1::2]
        woven.append(both)
    folder = tmp_path_factory.mktemp("broadcast")
    return _write(folder / "p.mp4", pictures[0::2], interlaced=False), _write(folder / "i.mp4", woven, interlaced=True)


def test_an_interlaced_broadcast_blows_the_fans_its_progressive_twin_blows(broadcast):
    """Read from both fields, the combed bunny and butterfly move the fans' cells (tolerant IoU 0.954
    against the progressive twin); from the top field, the same cells blow as the twin's."""
    progressive, interlaced = (pipeline.generate(p) for p in broadcast)
    fans = compare_timelines(progressive, interlaced)["fans"]
    assert (progressive.fans > 0).any(axis=(1, 2)).sum() >= 15
    assert fans["ticks_f1"] >= 0.95 and fans["iou_tolerant"] >= 0.98, fans
