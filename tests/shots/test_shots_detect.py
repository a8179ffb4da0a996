"""Shot detection as pure functions over per-tick arrays: the packed signatures, the vectorised cut
rule, flashes and dips inside a shot, caches without signatures, and the analysis cache that
stores the boundaries (or finds them from an older cache's arrays)."""

from __future__ import annotations

import numpy as np
import pytest

from autohaptics import shots
from autohaptics import testing as synth
from autohaptics.airflow import cuts
from autohaptics.errors import ParameterError
from autohaptics.pipeline import Analysis, VideoAnalysis
from autohaptics.shots import blend

W, H = 48, 27


def frame(seed: int, rgb, gain: float = 1.0) -> np.ndarray:
    """A textured frame in colour ``rgb``, brightness times ``gain``."""
    scene = synth.Scene(1.0, background=(synth.Segment(0, 1, rgb, texture=synth.Texture("noise", 0.15, 0.5, seed)),))
    return np.clip(synth.render_frame(scene, 0.0, width=W, height=H) * gain, 0, 255).astype(np.uint8)


def packed(frames) -> np.ndarray:
    return np.stack([cuts.pack_signature(cuts.frame_signature(f)) for f in frames])


def flags(frames) -> np.ndarray:
    """The video pass's cut flags between consecutive frames."""
    sigs = [cuts.frame_signature(f) for f in frames]
    return np.array([False] + [cuts.is_cut(a, b) for a, b in zip(sigs, sigs[1:])])


def test_packed_signatures_round_trip_within_rounding():
    sig = cuts.frame_signature(frame(1, (60, 90, 160)))
    back = cuts.unpack_signatures(cuts.pack_signature(sig)[None])[0]
    np.testing.assert_allclose(back, sig, atol=0.5 / (3 * 255) + 1e-6, rtol=0, err_msg="histogram")
    np.testing.assert_allclose(back[48:], sig[48:], atol=0.5)
    assert cuts.pack_signature(cuts.frame_signature(frame(1, (60, 90, 160))[..., 0])) is None  # gray


def test_vectorised_cut_rule_equals_the_scalar_one():
    frames = [frame(1, (60, 90, 160)), frame(2, (170, 120, 60)), frame(1, (60, 90, 160), 0.05),
              np.zeros((H, W, 3), np.uint8), frame(3, (60, 95, 150)), np.full((H, W, 3), 200, np.uint8)]
    sigs = np.stack([cuts.frame_signature(f) for f in frames])
    i, j = np.triu_indices(len(frames), 1)
    want = [cuts.cut_score(sigs[a], sigs[b]) for a, b in zip(i, j)]
    np.testing.assert_allclose(cuts.cut_scores(sigs[i], sigs[j]), want, atol=1e-9)
    with pytest.raises(ParameterError):
        cuts.cut_scores(sigs[:2], sigs[:3])


def test_a_flash_inside_a_shot_is_not_a_boundary_and_a_cut_is():
    a, b = frame(1, (60, 90, 160)), frame(2, (170, 120, 60))
    white = np.full((H, W, 3), 250, np.uint8)
    seq = [a] * 10 + [white, white] + [a] * 10 + [b] * 10
    got = shots.detect(cut=flags(seq), signature=packed(seq))
    assert got.tick.tolist() == [22] and shots.KINDS[got.kind[0]] == "cut"
    assert got.span.tolist() == [[22, 23]]


def test_a_fade_through_black_is_one_boundary_at_its_middle():
    a, b = (1, (60, 90, 160)), (2, (170, 120, 60))
    gains = np.linspace(1, 0, 6)
    seq = [frame(*a)] * 10 + [frame(*a, g) for g in gains] + [frame(*a, 0)] * 3 + \
          [frame(*b, g) for g in gains[::-1]] + [frame(*b)] * 10
    got = shots.detect(cut=flags(seq), signature=packed(seq))
    flat = [k for k, f in enumerate(seq) if f.std() < 4]
    assert got.tick.tolist() == [(flat[0] + flat[-1] + 2) // 2]
    assert shots.KINDS[got.kind[0]] == "fade"
    s0, s1 = got.span[0]
    assert s0 <= 11 and s1 >= len(seq) - 11


def test_a_dip_to_black_and_back_into_the_same_shot_is_not_a_boundary():
    a = (1, (60, 90, 160))
    gains = np.linspace(1, 0, 5)
    seq = [frame(*a)] * 10 + [frame(*a, g) for g in gains] + [frame(*a, g) for g in gains[::-1]] + [frame(*a)] * 10
    assert shots.detect(cut=flags(seq), signature=packed(seq)).tick.size == 0


def test_a_cross_dissolve_is_one_boundary_at_its_middle():
    a, b = frame(1, (60, 90, 160)).astype(float), frame(2, (170, 120, 60)).astype(float)
    seq = [a] * 12 + [(1 - s) * a + s * b for s in np.linspace(0, 1, 11)[1:-1]] + [b] * 12
    seq = [np.rint(f).astype(np.uint8) for f in seq]
    got = shots.detect(cut=flags(seq), signature=packed(seq))
    assert shots.KINDS[got.kind[0]] == "dissolve" and got.tick.size == 1
    assert abs(int(got.tick[0]) - 16.5) <= 1  # the 50/50 picture sits between ticks 16 and 17


def test_a_dissolve_through_a_haze_is_placed_between_the_shots_halves():
    """The first shot fades into a bright haze before the second shows (ticks 12-22 out, 18-28
    in): neither dominates in between, so the boundary is midway between where the first is half
    gone (row 17) and where the second is half there (row 23), as for a fade through a flat picture
    (the blend weight toward the second alone placed it at tick 14)."""
    a, b = frame(1, (60, 90, 160)).astype(float), frame(2, (170, 120, 60)).astype(float)
    haze = np.full_like(a, 215.0)
    out, into = np.clip((np.arange(40) - 12) / 10, 0, 1), np.clip((np.arange(40) - 18) / 10, 0, 1)
    seq = [np.rint((1 - o) * a + i * b + (o - i) * haze).astype(np.uint8) for o, i in zip(out, into)]
    got = shots.detect(cut=flags(seq), signature=packed(seq))
    assert [shots.KINDS[k] for k in got.kind] == ["dissolve"], got.tick
    assert abs(int(got.tick[0]) - 20.5) <= 1, got.tick  # the row-20 picture is half-way: tick 20 or 21
    s0, s1 = got.span[0]
    assert s0 <= 13 and s1 >= 28, got.span  # the span covers both halves


def test_a_dissolve_found_by_its_end_is_widened_to_its_contrast_dip():
    """Only the end of a dissolve read as linear (rows 22-26): its span grows to the last steady row
    before the contrast falls toward the dip (row 9) and the first after it rises out (row 27), not
    into the steady shots, and stops at a row that is not usable (a cut)."""
    level = np.concatenate([np.full(10, 50.0), np.linspace(50, 20, 11)[1:], np.linspace(20, 35, 9)[1:],
                            np.full(10, 35.0)]) + 0.05 * np.sin(np.arange(38))  # steady shots: noise only
    usable = np.ones(level.size, bool)
    assert blend.widened(level, usable, 22, 27, 30) == (9, 28)
    usable[14] = False
    assert blend.widened(level, usable, 22, 27, 30) == (15, 28)
    assert blend.widened(level, usable, 22, 27, 3) == (16, 27)  # at most max_ramp rows a side


def test_ticks_without_a_frame_of_their_own_hold_and_boundaries_land_between():
    """Below 10 fps every other tick holds the one before (the video pass's rule): detection runs on
    the analysed ticks, and a boundary lands between the last old and the first new frame."""
    a, b = (1, (60, 90, 160)), (2, (170, 120, 60))
    gains = np.linspace(1, 0, 4)
    seq = [frame(*a)] * 10 + [frame(*a, g) for g in gains] + [frame(*b, g) for g in gains[::-1]] + \
          [frame(*b)] * 10 + [frame(1, (40, 160, 60))] * 10
    held_cut, held_sig = np.repeat(flags(seq), 2), np.repeat(packed(seq), 2, axis=0)
    held_cut[1::2] = False  # a held tick is never flagged
    mask = np.arange(held_cut.size) % 2 == 0
    got = shots.detect(cut=held_cut, signature=held_sig, frame_mask=mask)
    whole = shots.detect(cut=flags(seq), signature=packed(seq))
    assert [shots.KINDS[k] for k in got.kind] == [shots.KINDS[k] for k in whole.kind] == ["fade", "cut"]
    assert np.abs(got.tick - 2 * whole.tick).max() <= 1, (got.tick, whole.tick)
    assert got.tick[1] in (55, 56)  # between the last old frame (tick 54) and the first new (56)


def test_without_signatures_cuts_and_dark_dips_still_make_boundaries():
    n = 60
    cut = np.zeros(n, bool)
    cut[20] = True
    rgb = np.full((n, 3), 120.0)  # the cut joins shots of the same mean colour: one flag is enough
    rgb[36:44] = np.linspace(120, 0, 8)[:, None]
    rgb[44:46] = 0
    rgb[46:54] = np.linspace(0, 120, 8)[:, None] * [1.0, 0.5, 0.2]
    rgb[54:] = [120, 60, 24]
    got = shots.detect(cut=cut, mean_rgb=rgb)
    assert got.tick[0] == 20 and 45 <= got.tick[1] <= 46  # the middle of the dark ticks (43..47)
    assert [shots.KINDS[k] for k in got.kind] == ["cut", "fade"]
    assert shots.detect(cut=cut).tick.tolist() == [20]
    rgb[46:54] = np.linspace(0, 120, 8)[:, None]  # back into the same colour: a dip, not a boundary
    rgb[54:] = 120
    assert shots.detect(cut=cut, mean_rgb=rgb).tick.tolist() == [20]
    flash = cut.copy()
    flash[[30, 32]] = True  # two flags, the same colour either side: a flash
    rgb[30:32] = 250
    assert shots.detect(cut=flash, mean_rgb=rgb).tick.tolist() == [20]


def test_boundaries_keep_the_shortest_shot_and_the_film_ends():
    cut = np.zeros(30, bool)
    cut[[0, 5, 6, 29]] = True
    got = shots.detect(cut=cut, params=shots.ShotParams(min_shot=2))
    assert got.tick.tolist() == [6]  # 5 and 6 are one run; 0 starts the film; 29 leaves a 1-tick shot
    with pytest.raises(ParameterError):
        shots.detect(cut=cut, signature=np.zeros((3, 192), np.uint8))


def _video(n: int, cut_at: int) -> VideoAnalysis:
    v = VideoAnalysis.empty(n)
    v.cut[cut_at] = True
    v.mean_rgb[:] = 100
    v.frame_mask[:] = True
    return v


def test_the_analysis_cache_stores_the_boundaries(tmp_path):
    v = _video(40, 17)
    an = Analysis(info={}, sha256="0" * 64, n_ticks=40, params={}, audio=None, video=v)
    assert an.shots.tick.tolist() == [17]
    an.save(tmp_path / "a.npz")
    with np.load(tmp_path / "a.npz") as z:
        assert z["shots_tick"].tolist() == [17] and z["video_signature"].shape == (40, 192)
    back = Analysis.load(tmp_path / "a.npz")
    assert back.shots.tick.tolist() == [17] and back.shots.kind.tolist() == [shots.detect.__globals__["CUT"]]


def test_a_cache_written_before_shots_gets_them_from_its_own_arrays(tmp_path):
    an = Analysis(info={}, sha256="0" * 64, n_ticks=40, params={}, audio=None, video=_video(40, 23))
    an.save(tmp_path / "a.npz")
    with np.load(tmp_path / "a.npz") as z:  # rewrite without the new arrays, as an older version did
        old = {k: z[k] for k in z.files if not k.startswith("shots_") and k != "video_signature"}
    np.savez(tmp_path / "old.npz", **old)
    back = Analysis.load(tmp_path / "old.npz")
    assert back.video.signature is None and back.shots.tick.tolist() == [23]
    back.save(tmp_path / "again.npz")  # and it saves without the missing array
    assert Analysis.load(tmp_path / "again.npz").shots.tick.tolist() == [23]
    audio_only = Analysis(info={}, sha256="0" * 64, n_ticks=40, params={}, audio={}, video=None)
    assert audio_only.shots.tick.size == 0
