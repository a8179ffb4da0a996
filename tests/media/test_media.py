"""Video proxies (autohaptics.media.Frame): the saliency luma read with the proxies equals the
full frame's area average, in display orientation; the RGB proxy is close to FFmpeg's own scaled
conversion; decoding modes and threads."""

from __future__ import annotations

import itertools

import cv2
import numpy as np
import pytest

from autohaptics import media
from autohaptics import testing as synth
from autohaptics.media.video import REPEAT_MIN_FPS
from shared_data import shared_clip
from stress_inputs import write_streams


def _frames(path, n: int = 4):
    """The first ``n`` decoded frames; the decode is closed after them, not whenever it is collected (an
    open one holds the interpreter's switch interval short, which another test reads)."""
    frames = media.iter_video(path, prefetch=4)
    try:
        yield from itertools.islice(frames, n)
    finally:
        frames.close()


def test_luma_grid_read_with_the_proxies_is_the_full_frame_average():
    """1080p H.264: the 64 x 64 luma made from the 2 x 2-averaged plane in the proxies' read is
    within two grey levels (a mean 0.6) of the area average of the full-resolution luma."""
    for f in _frames(shared_clip("bbb_1080p60_2s_h264_aac6ch.mp4"), 6):
        rgb, gray, luma = f.rgb_and_gray(192, 160, luma_size=(64, 64))
        assert rgb.shape == (108, 192, 3) and gray.shape == (90, 160) and luma.shape == (64, 64)
        assert luma.dtype == np.uint8
        # the proxies themselves are those made without the extra read
        rgb2, gray2 = f.rgb_and_gray(192, 160)
        np.testing.assert_array_equal(gray, gray2)
        np.testing.assert_array_equal(rgb, rgb2)
        direct = f.luma_grid((64, 64))
        assert np.abs(luma.astype(int) - direct.astype(int)).max() <= 2
        full = f.gray(f.width).astype(np.float64)  # the full-resolution luma, full range
        ref = cv2.resize(full, (64, 64), interpolation=cv2.INTER_AREA)
        assert np.abs(luma - ref).max() < 2.5 and np.abs(luma - ref).mean() < 0.6


@pytest.mark.parametrize("rotation", [0, 90, -90, 180])
def test_luma_grid_is_in_display_orientation(tmp_path, rotation):
    """A bright block in the stored frame's top-left corner lands where the viewer sees it."""
    frames = []
    for _ in range(3):
        fr = np.full((72, 128, 3), 30, np.uint8)
        fr[:24, :32] = 230
        frames.append(fr)
    path = write_streams(tmp_path / "r.mp4", frames=frames, fps=10, rotation=rotation)
    f = next(iter(_frames(path, 1)))
    rgb, gray, luma = f.rgb_and_gray(32, 48, luma_size=(16, 8))
    assert luma.shape == (8, 16)
    expected = cv2.resize(cv2.cvtColor(f.full(), cv2.COLOR_RGB2GRAY), (16, 8), interpolation=cv2.INTER_AREA)
    assert np.abs(luma.astype(int) - expected.astype(int)).max() <= 3
    bright = np.argwhere(luma > 128).mean(axis=0) / (8, 16)
    seen = np.argwhere(cv2.cvtColor(f.full(), cv2.COLOR_RGB2GRAY) > 128).mean(axis=0) / f.full().shape[:2]
    assert np.abs(bright - seen).max() < 0.15


@pytest.mark.parametrize("rotation, pixel_aspect, shown", [(0, 1.0, 16 / 9), (0, 64 / 45, 1024 / 576),
                                                          (90, 1.0, 9 / 16), (90, 64 / 45, 576 / 1024)])
def test_the_shown_aspect_applies_the_pixels_aspect_along_the_stored_rows(rotation, pixel_aspect, shown):
    """A 1024 x 576 picture stored as 720 x 576 with pixels 64/45 wide (an anamorphic PAL DVD), or a
    16:9 one; turned by the rotation metadata, the pixels' aspect stretches the shown picture's height."""
    width = 1024 if pixel_aspect == 1.0 else 720
    video = media.VideoInfo(index=0, width=width, height=576, fps=25.0, codec="h264", n_frames=None,
                            rotation=rotation, duration_s=None, pixel_aspect=pixel_aspect)
    assert video.shown_aspect() == pytest.approx(shown)
    w, h = video.display_size
    assert video.shown_aspect(w / 2, h) == pytest.approx(shown / 2)  # a region of it (the active picture)


@pytest.mark.parametrize("size, rotation", [((854, 480), 0), ((854, 480), 90), ((640, 360), 0)])
def test_planes_made_ahead_give_the_same_proxies(tmp_path, size, rotation):
    """Frame.prepare (run in the decoding thread) changes no proxy: gray, rgb_and_gray with and
    without the luma grid, and the signature proxy equal those of a frame made without it, at a
    size with odd chroma planes and rotated."""
    rng = np.random.default_rng(1)
    frames = [cv2.GaussianBlur(rng.integers(0, 256, (size[1], size[0], 3), dtype=np.uint8), (9, 9), 3)
              for _ in range(4)]
    path = write_streams(tmp_path / "p.mp4", frames=frames, fps=25, rotation=rotation)
    fresh = list(_frames(path, 4))
    ahead = list(_frames(path, 4))
    for a, b in zip(fresh, ahead):
        b.prepare(160, 128)
        np.testing.assert_array_equal(a.gray(160), b.gray(160))
        b.prepare(160, 128)
        for x, y in zip(a.rgb_and_gray(128, 160), b.rgb_and_gray(128, 160)):
            np.testing.assert_array_equal(x, y)
        b.prepare(160, 128)
        for x, y in zip(a.rgb_and_gray(128, 160, luma_size=(64, 64)), b.rgb_and_gray(128, 160, luma_size=(64, 64))):
            np.testing.assert_array_equal(x, y)
        b.prepare(160, 128, luma_size=(64, 64))  # the luma grid made ahead too: the plane read once
        assert ("grid", (64, 64)) in b._ready
        for x, y in zip(a.rgb_and_gray(128, 160, luma_size=(64, 64)), b.rgb_and_gray(128, 160, luma_size=(64, 64))):
            np.testing.assert_array_equal(x, y)
        assert not b._ready  # every plane made ahead was taken
        np.testing.assert_array_equal(a.proxy(48), b.proxy(48))


def test_luma_grid_without_the_fast_path(tmp_path):
    """A proxy as wide as the frame has no fast path: the luma comes from the full frame."""
    frames = [np.tile(np.arange(64, dtype=np.uint8)[None, :, None] * 4, (36, 1, 3)) for _ in range(3)]
    path = write_streams(tmp_path / "s.mp4", frames=frames, fps=10)
    f = next(iter(_frames(path, 1)))
    _, _, luma = f.rgb_and_gray(64, 64, luma_size=(16, 16))
    assert luma.shape == (16, 16)
    assert np.all(np.diff(luma.astype(int), axis=1) > 0)  # the ramp survives, left to right


def _decoded(path, decode):
    return [(f.time_s, f.gray(64)) for f in media.iter_video(path, decode=decode)]


def test_sparse_decoding_keeps_only_i_and_p_frames_from_40_fps():
    """The 1080p60 H.264 clip (B-pyramid: I/P, one reference B and two plain B per 4 frames):
    "nonref" decodes half the frames exactly; "sparse" only the I- and P-frames (a quarter),
    in order, with the true timestamps of the same frames, approximate (missing B references)
    but close to the exact ones."""
    path = shared_clip("bbb_1080p60_2s_h264_aac6ch.mp4")
    full = dict(_decoded(path, "full"))
    nonref = _decoded(path, "nonref")
    sparse = _decoded(path, "sparse")
    assert len(full) == 120 and 55 <= len(nonref) <= 65 and 28 <= len(sparse) <= 36
    for t, g in nonref:
        np.testing.assert_array_equal(g, full[t])  # the frames it decodes are exact
    times = [t for t, _ in sparse]
    assert times == sorted(times) and set(times) <= set(full)
    assert max(np.diff(times)) <= 4 / 60 + 1e-6  # still one frame per 100 ms tick and more
    errors = [np.abs(g.astype(int) - full[t].astype(int)).mean() for t, g in sparse]
    assert 0 < max(errors) < 8  # approximate, not garbage


def test_sparse_decoding_below_40_fps_skips_only_non_reference_frames():
    """At 24 fps every B-frame skipped would leave too few frames for the 10 Hz ticks: "sparse"
    decodes what "fast" does (the non-reference frames skipped)."""
    path = shared_clip("sintel_trailer_480x204_h264_aac.mp4")
    assert media.probe(path).video.fps < REPEAT_MIN_FPS <= media.SPARSE_MIN_FPS
    fast = [t for t, _ in _decoded(path, "fast")]
    sparse = [t for t, _ in _decoded(path, "sparse")]
    assert sparse == fast


@pytest.mark.parametrize("codec, options", [("mpeg2video", {"bf": "2", "g": "12"}),
                                            ("libx265", {"preset": "veryfast", "x265-params": "log-level=error"})],
                         ids=["MPEG-2, two B-frames", "HEVC, x265's B-pyramid"])
@pytest.mark.parametrize("prefetch", [0, 4])
def test_skipping_that_would_leave_two_frames_out_decodes_every_frame(tmp_path, codec, options, prefetch):
    """MPEG-2's two B-frames between references (a DVD's) and x265's four (one of them a reference)
    leave 3-frame gaps where the non-reference frames are skipped: "nonref" decodes every frame
    there, the same frames as "full", from the start or from a seek, and x264's stream still skips."""
    import av

    from autohaptics.media.video import SKIP_GAP_MAX
    from autohaptics.testing.reencode import reencode

    texture = cv2.GaussianBlur(np.random.default_rng(5).integers(0, 256, (96, 256, 3), dtype=np.uint8), (7, 7), 2)
    frames = [np.ascontiguousarray(np.roll(texture, 2 * i, axis=1)[:, :128]) for i in range(48)]  # a pan
    h264 = write_streams(tmp_path / "b.mp4", frames=frames, fps=24)
    other = reencode(h264, tmp_path / "o.mkv", video_codec=codec, video_options=options, video_bit_rate=2_000_000)
    with av.open(str(other)) as c:  # the stream itself: gaps of three frames without the non-reference ones
        c.streams.video[0].codec_context.skip_frame = "NONREF"
        times = [f.time for f in c.decode(video=0)]
    assert max(np.diff(times)) * 24 > SKIP_GAP_MAX
    for start_s in (0.0, 0.9):
        full = [(f.time_s, f.gray(64)) for f in media.iter_video(other, decode="full", start_s=start_s)]
        got = [(f.index, f.time_s, f.gray(64)) for f in media.iter_video(other, decode="nonref", prefetch=prefetch,
                                                                          start_s=start_s)]
        assert [i for i, _, _ in got] == list(range(len(full)))
        assert [t for _, t, _ in got] == [t for t, _ in full]
        for (_, _, g), (_, gf) in zip(got, full):
            np.testing.assert_array_equal(g, gf)
    assert len(_decoded(h264, "nonref")) < 0.75 * len(_decoded(h264, "full"))


def test_decoder_threads_leave_the_analysis_a_core(tmp_path, monkeypatch):
    """Frames decoded ahead of the analysis: FFmpeg gets one thread fewer than the cores where it
    skips the non-reference frames of a B-frame stream below 40 fps, its own count otherwise
    (intra-only, above 40 fps, every frame decoded); the frames are the same either way."""
    from autohaptics.media.video import decoder_threads
    from autohaptics.testing.reencode import reencode

    rng = np.random.default_rng(3)
    frames = [cv2.GaussianBlur(rng.integers(0, 256, (96, 128, 3), dtype=np.uint8), (7, 7), 2) for _ in range(30)]
    b_frames = write_streams(tmp_path / "b.mp4", frames=frames, fps=24)
    intra = reencode(b_frames, tmp_path / "i.mp4", video_options={"g": "1"})
    high = reencode(b_frames, tmp_path / "h.mp4", fps=50)

    def threads(path, decode):
        import av
        with av.open(str(path)) as c:
            return decoder_threads(c.streams.video[0], decode, media.probe(path).video.fps)

    monkeypatch.setattr("os.sched_getaffinity", lambda pid: {0, 1, 2, 3}, raising=False)
    assert threads(b_frames, "nonref") == 3 and threads(b_frames, "fast") == 3
    assert threads(b_frames, "full") == threads(b_frames, "sparse") == 0
    assert threads(intra, "nonref") == 0 and threads(high, "nonref") == 0
    monkeypatch.setattr("os.sched_getaffinity", lambda pid: {0}, raising=False)
    assert threads(b_frames, "nonref") == 1
    ahead = [(f.time_s, f.gray(64)) for f in media.iter_video(b_frames, decode="nonref", prefetch=4)]
    in_turn = _decoded(b_frames, "nonref")
    assert len(ahead) == len(in_turn) > 0
    for (ta, ga), (tb, gb) in zip(ahead, in_turn):
        assert ta == tb
        np.testing.assert_array_equal(ga, gb)


def test_a_frame_says_whether_the_decoder_was_ahead_when_it_was_taken(tmp_path):
    """A slow caller finds the decoder's queue full (the caller is the slower side); without a
    decoding thread no frame is ahead."""
    import time

    path = synth.write_scene(tmp_path / "s.mp4", synth.sample_scene(), width=160, height=90, fps=24, audio=False)
    assert not any(f.ahead for f in media.iter_video(path))
    slow = []
    for f in media.iter_video(path, prefetch=8):
        time.sleep(0.01)
        slow.append(f.ahead)
    assert sum(slow) > len(slow) // 2


def test_the_switch_interval_is_short_while_a_decoding_thread_runs_and_restored_after(tmp_path):
    """The decoding thread gets the interpreter lock back from a caller busy in Python within
    ``SWITCH_INTERVAL_S``, not the default 5 ms; the caller's own setting comes back after."""
    import sys

    from autohaptics.media.video import SWITCH_INTERVAL_S

    path = synth.write_scene(tmp_path / "s.mp4", synth.sample_scene(), width=160, height=90, fps=24, audio=False)
    before = sys.getswitchinterval()
    assert before > SWITCH_INTERVAL_S
    seen = [sys.getswitchinterval() for _ in media.iter_video(path, prefetch=4)]
    assert max(seen) <= SWITCH_INTERVAL_S and sys.getswitchinterval() == before
    frames = media.iter_video(path, prefetch=4)
    next(frames)
    frames.close()  # a caller that stops early
    assert sys.getswitchinterval() == before
    assert [sys.getswitchinterval() for _ in media.iter_video(path)][-1] == before  # no decoding thread: untouched


def test_rgb_proxy_is_close_to_ffmpegs_scaled_conversion():
    frame = list(_frames(shared_clip("sintel_trailer_480x204_h264_aac.mp4"), 120))[-1]  # a lit picture (mean 105)
    ours = frame.proxy(160).astype(np.int16)
    w, h = ours.shape[1], ours.shape[0]
    ffmpeg = frame._frame.to_ndarray(width=w, height=h, format="rgb24", interpolation="AREA").astype(np.int16)
    assert float(np.abs(ours - ffmpeg).mean()) < 2.5  # 1.5 measured (area averaging before the conversion, not after)


def test_fields_are_the_even_and_the_odd_rows_of_the_picture():
    frame = list(_frames(shared_clip("sintel_trailer_480x204_h264_aac.mp4"), 120))[-1]
    full = frame.proxy(frame.width, frame.height)
    top, bottom = frame.fields(64)
    assert top.shape == bottom.shape == (14, 64, 3)  # 102 rows of 480 px, 64 px wide
    for got, rows in ((top, full[0::2]), (bottom, full[1::2])):
        want = cv2.resize(rows, (64, 14), interpolation=cv2.INTER_AREA).astype(np.int16)
        assert np.abs(got.astype(np.int16) - want).max() <= 1


@pytest.mark.parametrize("colorspace, color_range", [(1, 1), (0, 1), (1, 2), (0, 2)])  # BT.709/601, limited/full
def test_rgb_conversion_is_the_float32_formula_rounded_half_up(colorspace, color_range):
    from autohaptics.media.frames import _yuv_to_rgb

    frame = type("Tags", (), {"colorspace": colorspace, "color_range": color_range,
                              "format": type("F", (), {"name": "yuv420p"})})()
    y, u, v = (a.reshape(-1, 256) for a in np.meshgrid(np.arange(0, 256, 3, dtype=np.uint8),
                                                         np.arange(256, dtype=np.uint8), np.arange(256, dtype=np.uint8),
                                                         indexing="ij"))
    kr, kb = (0.2126, 0.0722) if colorspace == 1 else (0.299, 0.114)
    kg = 1.0 - kr - kb
    f32 = np.float32
    yy, cb, cr = y.astype(f32), u.astype(f32) - f32(128), v.astype(f32) - f32(128)
    if color_range != 2:
        yy, cb, cr = (yy - f32(16)) * f32(255 / 219), cb * f32(255 / 224), cr * f32(255 / 224)
    want = np.stack([yy + f32(2 * (1 - kr)) * cr, yy - f32(2 * kb * (1 - kb) / kg) * cb - f32(2 * kr * (1 - kr) / kg) * cr,
                     yy + f32(2 * (1 - kb)) * cb], axis=-1)
    want = np.clip(want + f32(0.5), 0, 255).astype(np.uint8)
    np.testing.assert_array_equal(_yuv_to_rgb(y, u, v, frame), want)


@pytest.mark.parametrize("pix_fmt", ["yuv420p10le", "yuv422p10le", "yuv444p12le", "yuva444p10le"])
def test_a_wide_planar_frame_reads_its_planes_as_an_8_bit_one_does(pix_fmt):
    """10- and 12-bit planar YUV (HEVC and H.264 10-bit, ProRes masters) take the planes' own path,
    not FFmpeg's full-frame conversion (7.6x the 8-bit path's proxy time on a 10-bit 1080p film):
    its proxies are as close to FFmpeg's scaled conversion as the 8-bit path's, and to the 8-bit
    frame's proxies of the same picture."""
    import av

    rng = np.random.default_rng(3)
    rgb = cv2.GaussianBlur(rng.integers(0, 256, (270, 480, 3), dtype=np.uint8), (15, 15), 5)
    source = av.VideoFrame.from_ndarray(rgb, format="rgb24")
    wide = media.Frame(source.reformat(format=pix_fmt), 0, 0.0, 0)
    narrow = media.Frame(source.reformat(format="yuv420p"), 0, 0.0, 0)
    assert wide._planes_small(160, 90, colour=True) is not None  # the planes' path was taken
    got = wide.rgb_and_gray(128, 160, luma_size=(64, 64))
    assert [a.dtype for a in got] == [np.uint8] * 3
    want = narrow.rgb_and_gray(128, 160, luma_size=(64, 64))
    for a, b in zip(got, want):
        assert a.shape == b.shape
        assert float(np.abs(a.astype(np.int16) - b).mean()) < 1.5
    (h, w), (gh, gw) = got[0].shape[:2], got[1].shape
    ffmpeg = wide._frame.to_ndarray(width=w, height=h, format="rgb24", interpolation="AREA")
    assert float(np.abs(got[0].astype(np.int16) - ffmpeg).mean()) < 2.5
    ffmpeg_gray = wide._frame.to_ndarray(width=gw, height=gh, format="gray", interpolation="AREA")
    assert int(np.abs(got[1].astype(np.int16) - ffmpeg_gray).max()) <= 2
    luma = wide.luma()
    assert luma.dtype == np.uint8 and luma.shape == (270, 480)
    assert int(np.abs(luma.astype(np.int16) - wide._frame.to_ndarray(format="gray")).max()) <= 2


@pytest.mark.parametrize("pix_fmt", ["yuv420p", "yuv420p10le", "rgb24"])
def test_luma_sample_is_a_grid_of_the_stored_luma_at_8_bit_scale(pix_fmt):
    import av

    y = np.tile(np.arange(16, 232, dtype=np.uint8)[None, :216], (120, 1))[:, :200]  # a ramp across
    frame = av.VideoFrame.from_ndarray(np.stack([y] * 3, -1), format="rgb24")
    frame = frame if pix_fmt == "rgb24" else frame.reformat(format=pix_fmt)
    sample = media.Frame(frame, 0, 0.0, 0).luma_sample(64, 36)
    if pix_fmt == "rgb24":
        assert sample is None  # no planar luma to sample
        return
    assert sample.dtype == np.uint8 and sample.shape == (40, 67)  # every 3rd row and column of 120 x 200
    want = frame.reformat(format="yuv420p").to_ndarray()[:120][1::3, 1::3]
    assert int(np.abs(sample.astype(np.int16) - want).max()) <= 1


def test_a_variable_rate_stream_is_told_and_decoded_whole(tmp_path):
    """A stream that drops one source frame in one to three (a phone's, a converter's) is variable
    rate: every frame decodes in the default mode, since skipping its non-reference frames too left
    pairs 0.1-0.3 s apart (the matrix's Sintel row: tolerant fan IoU 0.595). The same frames at their
    own rate are not, nor is a cut whose first frame is the one on screen at the cut (one short
    interval, which FFmpeg's own rate guess reads as 48 fps)."""
    from autohaptics.testing.reencode import reencode

    rng = np.random.default_rng(5)
    frames = [cv2.GaussianBlur(rng.integers(0, 256, (96, 128, 3), dtype=np.uint8), (7, 7), 2) for _ in range(72)]
    src = write_streams(tmp_path / "src.mp4", frames=frames, fps=24)
    vfr = reencode(src, tmp_path / "vfr.mp4", conversion="vfr")
    cut = reencode(src, tmp_path / "cut.mp4", start_s=0.6)
    assert media.probe(vfr).video.variable_rate
    assert not media.probe(src).video.variable_rate and not media.probe(cut).video.variable_rate
    whole = _decoded(vfr, "full")
    assert len(_decoded(vfr, "nonref")) == len(whole) > 40
    assert len(_decoded(src, "nonref")) < len(frames)  # a regular stream still skips its B-frames


def test_a_stream_at_a_conversion_rate_decodes_every_frame(tmp_path):
    """From ``REPEAT_MIN_FPS`` to ``SPARSE_MIN_FPS`` a stream may show a film by repeated pictures
    (24 -> 30 fps: one in five), which the cadence tells from each frame's difference to the one
    before: "nonref" and "fast" skip no frame there (a skipped B-frame hid the repeats; the matrix's
    Sintel H.264 240p screener read fan-tick F1 0.849), "sparse" still does; at 24 fps "nonref"
    skips its B-frames."""
    from autohaptics.testing.reencode import reencode

    rng = np.random.default_rng(7)
    frames = [cv2.GaussianBlur(rng.integers(0, 256, (96, 128, 3), dtype=np.uint8), (7, 7), 2) for _ in range(48)]
    src = write_streams(tmp_path / "src.mp4", frames=frames, fps=24)
    thirty = reencode(src, tmp_path / "thirty.mp4", fps=30)
    assert len(_decoded(src, "nonref")) < len(frames)
    whole = _decoded(thirty, "full")
    assert len(whole) == 60
    for mode in ("nonref", "fast"):
        assert [t for t, _ in _decoded(thirty, mode)] == [t for t, _ in whole]
    assert len(_decoded(thirty, "sparse")) < len(whole)
