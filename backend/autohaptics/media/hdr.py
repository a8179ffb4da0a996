"""HDR pictures (PQ / SMPTE ST 2084 and HLG / ARIB STD-B67, as HDR10, Dolby Vision base layers and HLG
broadcasts carry them) brought to the SDR proxies every stage reads: BT.709 primaries, BT.1886 gamma
2.4, the HDR reference white (BT.2408: 203 cd/m2, HLG's 75 % signal) at SDR's 100 % white, brighter
highlights clipped there as an SDR grade clips them. Without it an HDR10 release reads dark and
desaturated (its SDR range lies in the lower 58 % of the PQ signal), and its colour temperature and
motion differ from its SDR release's.

Applied to the small proxies (a table per channel and one 3 x 3 matrix), never to a full frame. The
proxies of an HDR frame keep its planes' bits until here: in 8 bits the PQ signal holds SDR's range in
127 levels, and a dark film's motion and colour follow the steps.
"""

from __future__ import annotations

from functools import lru_cache

import av
import cv2
import numpy as np

PQ, HLG = 16, 18  # FFmpeg's AVColorTransferCharacteristic of SMPTE ST 2084 and ARIB STD-B67
BT2020 = 9  # FFmpeg's AVColorPrimaries of BT.2020 (and its matrix: 9 non-constant, 10 constant luminance)
REFERENCE_WHITE_NITS = 203.0  # BT.2408: HDR reference white, shown as SDR's 100 % white
HLG_PEAK_NITS = 1000.0  # the HLG display BT.2100 names as reference (system gamma 1.2)
SDR_GAMMA = 2.4  # BT.1886
# BT.2020 -> BT.709 primaries on linear light (BT.2087), rows R, G, B
BT2020_TO_BT709 = np.array([[1.6605, -0.5876, -0.0728],
                            [-0.1246, 1.1329, -0.0083],
                            [-0.0182, -0.1006, 1.1187]], np.float32)


def transfer(frame: av.VideoFrame) -> int | None:
    """The frame's HDR transfer (:data:`PQ` or :data:`HLG`), None for SDR or untagged pictures."""
    trc = getattr(frame, "color_trc", None)
    return int(trc) if trc in (PQ, HLG) else None


def relative_light(signal: np.ndarray, trc: int) -> np.ndarray:
    """Displayed light relative to the reference white (1.0 = 203 cd/m2, >= 0) of HDR signal values
    0..1 (float): the PQ EOTF, or HLG's inverse OETF and OOTF (gamma 1.2 on a 1000 cd/m2 display,
    applied per channel)."""
    e = np.clip(np.asarray(signal, np.float64), 0.0, 1.0)
    if trc == PQ:
        m1, m2, c1, c2, c3 = 2610 / 16384, 2523 / 4096 * 128, 3424 / 4096, 2413 / 4096 * 32, 2392 / 4096 * 32
        p = e ** (1.0 / m2)
        nits = 10000.0 * (np.maximum(p - c1, 0.0) / (c2 - c3 * p)) ** (1.0 / m1)
    else:
        a, b = 0.17883277, 1.0 - 4 * 0.17883277
        c = 0.5 - a * np.log(4 * a)
        scene = np.where(e <= 0.5, e * e / 3.0, (np.exp((e - c) / a) + b) / 12.0)
        nits = HLG_PEAK_NITS * scene ** 1.2
    return nits / REFERENCE_WHITE_NITS


def _sdr_code(light: np.ndarray) -> np.ndarray:
    """Relative light (1.0 = SDR white) -> SDR signal 0..255 (BT.1886), clipped, float."""
    return 255.0 * np.clip(light, 0.0, 1.0) ** (1.0 / SDR_GAMMA)


_RGB_LEVELS = 1024  # a float R'G'B' signal (from planes of 10 bits or more) is read in this many levels


@lru_cache(maxsize=8)
def _light_table(trc: int, levels: int) -> np.ndarray:
    """float32 [levels]: relative light of each full-range signal level."""
    return relative_light(np.arange(levels) / (levels - 1.0), trc).astype(np.float32)


@lru_cache(maxsize=16)
def luma_table(trc: int, full_range: bool, bits: int = 8) -> np.ndarray:
    """uint8 [2**bits]: an HDR luma sample of ``bits`` as stored (limited 16..235 at 8-bit scale, or
    full range) -> full-range SDR luma."""
    k = np.arange(1 << bits, dtype=np.float64)
    scale = float(1 << (bits - 8))
    signal = k / ((1 << bits) - 1.0) if full_range else (k / scale - 16.0) / 219.0
    return np.rint(_sdr_code(relative_light(signal, trc))).astype(np.uint8)


def sdr_luma(y: np.ndarray, frame: av.VideoFrame, full_range: bool, bits: int = 8) -> np.ndarray:
    """An HDR frame's luma samples (uint8, or uint16 of ``bits``; as stored, or ``full_range``) as
    full-range SDR luma, uint8."""
    table = luma_table(transfer(frame), full_range, bits if y.dtype != np.uint8 else 8)
    return cv2.LUT(y, table) if y.dtype == np.uint8 else np.take(table, np.minimum(y, table.size - 1))


_LIGHT_STEPS = 16384  # linear light 0..1 in this many steps on its way to the SDR signal (14 bits)


@lru_cache(maxsize=1)
def _sdr_table() -> np.ndarray:
    """uint8 [_LIGHT_STEPS]: the SDR signal of each step of linear light (0 .. SDR white)."""
    return np.rint(_sdr_code(np.arange(_LIGHT_STEPS) / (_LIGHT_STEPS - 1.0))).astype(np.uint8)


def sdr_rgb(rgb: np.ndarray, frame: av.VideoFrame) -> np.ndarray:
    """An HDR frame's full-range R'G'B' signal [shape=(h, w, 3)], uint8 or float32 at 8-bit scale
    (0..255, unrounded), as SDR BT.709 R'G'B' (uint8): linear light per channel, BT.2020 primaries to
    BT.709 where the frame is tagged so, then BT.1886."""
    trc = transfer(frame)
    if rgb.dtype == np.uint8:
        light = cv2.LUT(rgb, _light_table(trc, 256))
    else:
        levels = rgb * np.float32((_RGB_LEVELS - 1) / 255.0) + np.float32(0.5)
        np.clip(levels, 0, _RGB_LEVELS - 1, out=levels)
        light = np.take(_light_table(trc, _RGB_LEVELS), levels.astype(np.uint16))
    if getattr(frame, "color_primaries", None) == BT2020:
        light = cv2.transform(light, BT2020_TO_BT709)
    light *= np.float32(_LIGHT_STEPS - 1)
    light += np.float32(0.5)
    np.clip(light, 0, _LIGHT_STEPS - 1, out=light)
    return np.take(_sdr_table(), light.astype(np.uint16))
