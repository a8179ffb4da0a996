"""The benchmarks' bare decode (every frame and sample, counted), the films made of copies of a
clip, and the full-frame film clip's picture (scaled to cover the frame and cropped: no bar left,
unlike the letterboxed one)."""

from __future__ import annotations

import av
import numpy as np
import pytest

from autohaptics.bench.clips import _picture, copied_clip, reencode
from autohaptics.bench.decode import bare_decode
from autohaptics.errors import ParameterError


def test_the_bare_decode_counts_every_frame_and_sample(media_dir):
    path = media_dir / "sintel_trailer_480x204_h264_aac.mp4"
    frames = samples = 0
    with av.open(str(path)) as c:
        for f in c.decode(video=0, audio=0):
            if isinstance(f, av.VideoFrame):
                frames += 1
            else:
                samples += f.samples
    assert bare_decode(path) == {"video_frames": frames, "audio_samples": samples}
    assert frames > 1000 and samples > 44100 * 50  # a 52 s trailer, 44.1 kHz


def _wide_frame(width: int = 64, height: int = 16) -> av.VideoFrame:
    """A 4:1 picture: a white left edge column band, grey elsewhere, a black right band."""
    rgb = np.full((height, width, 3), 128, np.uint8)
    rgb[:, : width // 8] = 255
    rgb[:, -width // 8:] = 0
    return av.VideoFrame.from_ndarray(rgb, format="rgb24")


def test_fill_covers_the_frame_and_crops_the_overhanging_sides():
    frame = _wide_frame()
    boxed = _picture(frame, 32, 20)[:20]
    filled = _picture(frame, 32, 20, fit="fill")[:20]
    assert (boxed[:6] == 16).all() and (boxed[-6:] == 16).all()  # 32 x 8 picture between bars
    assert (filled[:, 8:24] > 100).all()  # the grey middle fills every row: no bar
    # the 80 px wide scaled picture loses 24 px on each side: the white and black bands (10 px) are gone
    assert filled.min() > 100 and filled.max() < 160


def test_reencode_rejects_an_unknown_fit(tmp_path, media_dir):
    with pytest.raises(ParameterError, match="fit"):
        reencode(media_dir / "bbb_1s_1280x720_vp8_vorbis.webm", tmp_path / "x.mp4", fit="stretch")


def test_pad_fits_the_picture_inside_with_even_bars():
    frame = _wide_frame()  # 64 x 16: fits 32 x 20 as 32 x 8, bars above and below
    boxed = _picture(frame, 32, 20, fit="pad")[:20]
    assert (boxed[:6] == 16).all() and (boxed[-6:] == 16).all() and (boxed[6:14, 8:24] > 100).all()
    tall = av.VideoFrame.from_ndarray(np.full((16, 8, 3), 200, np.uint8), format="rgb24")
    pillar = _picture(tall, 32, 16, fit="pad")  # 8 x 16 in 32 x 16: 12 px bars on each side
    y, u = pillar[:16], pillar[16:20].reshape(8, 16)
    assert (y[:, :12] == 16).all() and (y[:, -12:] == 16).all() and (y[:, 12:20] > 150).all()
    assert (u[:, :6] == 128).all() and (u[:, -6:] == 128).all()


@pytest.mark.parametrize("name", ["sintel_trailer_480x204_h264_aac.mp4", "bbb_1s_1280x720_vp8_vorbis.webm"])
def test_copies_play_the_clip_again_and_again_from_its_own_packets(tmp_path, media_dir, name):
    """A film of three copies decodes to three times the clip's frames and its sound, at rising
    times three times its length, and each copy's pictures are the clip's own (the packets are copied)."""
    src = media_dir / name
    film = copied_clip(src, 3, tmp_path)
    assert film.suffix == src.suffix and copied_clip(src, 3, tmp_path) == film
    one, three = bare_decode(src), bare_decode(film)
    assert three["video_frames"] == 3 * one["video_frames"]
    # an overlapped audio codec (Vorbis) may give up to a frame of sound more at each join
    assert 0 <= three["audio_samples"] - 3 * one["audio_samples"] <= 3 * 2048
    with av.open(str(src)) as c:
        clip_s = float(c.duration) / av.time_base
        clip_frames = [f.to_ndarray(format="gray") for f in c.decode(video=0)]
    with av.open(str(film)) as c:
        assert float(c.duration) / av.time_base == pytest.approx(3 * clip_s, abs=0.2)
        times, pictures = [], []
        for f in c.decode(video=0):
            times.append(float(f.time))
            if len(pictures) < 2 * len(clip_frames) + 3:
                pictures.append(f.to_ndarray(format="gray"))
    assert np.all(np.diff(times) > 0)
    n = len(clip_frames)
    for k in (0, 1, n // 2, n - 1):
        np.testing.assert_array_equal(pictures[n + k], clip_frames[k])
    with pytest.raises(ParameterError, match="copies"):
        copied_clip(src, 0, tmp_path)
