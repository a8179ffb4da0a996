"""HDR pictures (``media.hdr``): the standards' known values of the PQ and HLG transfers, and the
proxies of an HDR grade (``testing.grade``, written from the formulas the other way) against the
SDR picture's own: the same colours and luma within a few grey levels, where read as SDR they lie
tens of levels off (dark and desaturated)."""

from __future__ import annotations

import av
import cv2
import numpy as np
import pytest

from autohaptics import media
from autohaptics.media import hdr
from autohaptics.testing.grade import hdr_frame


@pytest.mark.parametrize("trc, signal, nits", [
    (hdr.PQ, 0.0, 0.0), (hdr.PQ, 0.5806, 203.0), (hdr.PQ, 0.7518, 1000.0), (hdr.PQ, 1.0, 10000.0),
    (hdr.HLG, 0.0, 0.0), (hdr.HLG, 0.75, 203.0), (hdr.HLG, 1.0, 1000.0),
])
def test_the_transfers_give_the_standards_light(trc, signal, nits):
    """ST 2084's code values of 203, 1000 and 10000 cd/m2; BT.2408's HLG reference white at 75 %
    signal on a 1000 cd/m2 display (BT.2100's system gamma 1.2)."""
    got = float(hdr.relative_light(np.array([signal]), trc)[0]) * hdr.REFERENCE_WHITE_NITS
    assert got == pytest.approx(nits, rel=0.01, abs=0.01)


def test_the_luma_table_is_monotone_and_puts_reference_white_at_sdr_white():
    for trc in (hdr.PQ, hdr.HLG):
        for full in (False, True):
            t = hdr.luma_table(trc, full).astype(int)
            assert (np.diff(t) >= 0).all() and t[0] == 0
    pq = hdr.luma_table(hdr.PQ, False)
    assert pq[int(round(16 + 219 * 0.5806))] >= 253  # 203 cd/m2 -> 255
    ten_nits = int(round(16 + 219 * 0.2986))  # ST 2084's code of 10 cd/m2, 5 % of the reference white
    assert abs(int(pq[ten_nits]) - 255 * (10 / 203) ** (1 / 2.4)) <= 2  # where SDR (gamma 2.4) shows 5 %


def _picture() -> np.ndarray:
    """Smooth colour fields and a grey ramp: every hue, dark to white (no clipping in an SDR white)."""
    rng = np.random.default_rng(5)
    rgb = cv2.GaussianBlur(rng.integers(0, 256, (270, 480, 3), dtype=np.uint8), (31, 31), 12)
    rgb = cv2.normalize(rgb, None, 10, 245, cv2.NORM_MINMAX)
    rgb[:40] = np.linspace(0, 255, 480).astype(np.uint8)[None, :, None]
    return rgb


@pytest.mark.parametrize("transfer", ["pq", "hlg"])
def test_an_hdr_grade_gives_the_sdr_pictures_proxies(transfer):
    """RGB, gray and the luma grid from the planes' own path, and the full-resolution luma; an HDR10
    grade read as SDR (its tags dropped) is far off, so the test tells the two apart."""
    rgb = _picture()
    coded = av.VideoFrame.from_ndarray(rgb, format="rgb24").reformat(format="yuv420p", dst_colorspace="ITU709")
    coded.colorspace = 1  # tagged BT.709, as it is coded
    sdr = media.Frame(coded, 0, 0.0, 0)
    graded = hdr_frame(rgb, transfer)
    got = media.Frame(graded, 0, 0.0, 0).rgb_and_gray(128, 160, luma_size=(64, 64))
    want = sdr.rgb_and_gray(128, 160, luma_size=(64, 64))
    errors = [float(np.abs(a.astype(np.int16) - b).mean()) for a, b in zip(got, want)]
    assert errors[0] < 3.0 and max(errors[1:]) < 2.0, errors
    luma = media.Frame(graded, 0, 0.0, 0).luma()
    assert float(np.abs(luma.astype(np.int16) - sdr.luma()).mean()) < 2.0

    untagged = hdr_frame(rgb, transfer)
    untagged.color_trc, untagged.color_primaries = 1, 1
    as_sdr = media.Frame(untagged, 0, 0.0, 0).rgb_and_gray(128, 160)
    assert hdr.transfer(untagged) is None
    assert float(np.abs(as_sdr[1].astype(np.int16) - want[1]).mean()) > 10.0


def test_ffmpegs_conversion_of_an_hdr_frame_is_brought_to_sdr_too():
    """A proxy as large as the frame takes FFmpeg's conversion; it is brought to SDR the same way."""
    rgb = _picture()
    frame = media.Frame(hdr_frame(rgb, "pq"), 0, 0.0, 0)
    full = frame.full()
    assert full.shape == rgb.shape
    assert float(np.abs(full.astype(np.int16) - rgb).mean()) < 6.0  # the SDR frame's own: 2.9
    assert float(np.abs(frame.full(fmt="gray").astype(np.int16) - cv2.cvtColor(rgb, cv2.COLOR_RGB2GRAY)).mean()) < 4.0
