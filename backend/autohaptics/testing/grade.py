"""HDR grades of an SDR picture, as an HDR release carries the same film: the SDR picture's light
(BT.1886, gamma 2.4) with its white at the HDR reference white (BT.2408: 203 cd/m2), in BT.2020
primaries, coded with the PQ (SMPTE ST 2084) or HLG (ARIB STD-B67, a 1000 cd/m2 display's system gamma
1.2) transfer as 10-bit 4:2:0 BT.2020 non-constant-luminance YCbCr, limited range, and tagged so.
Written from the standards' formulas for the tests and the material matrix (``testing.reencode``),
independently of the decoder's way back (``media.hdr``).
"""

from __future__ import annotations

import av
import numpy as np

TRANSFERS = ("sdr", "pq", "hlg")
_TRC = {"pq": 16, "hlg": 18}  # FFmpeg's AVColorTransferCharacteristic
_BT2020 = 9  # FFmpeg's AVColorPrimaries and AVColorSpace (non-constant luminance) of BT.2020
WHITE_NITS = 203.0
# BT.709 -> BT.2020 primaries on linear light (BT.2087)
_TO_BT2020 = np.array([[0.6274, 0.3293, 0.0433], [0.0691, 0.9195, 0.0114], [0.0164, 0.0880, 0.8956]])
_KR, _KB = 0.2627, 0.0593


def tag(codec_context, transfer: str) -> None:
    """Tag an encoder's output as ``transfer``'s grade (BT.2020, limited range); nothing for "sdr"."""
    if transfer != "sdr":
        codec_context.color_primaries, codec_context.colorspace = _BT2020, _BT2020
        codec_context.color_trc, codec_context.color_range = _TRC[transfer], 1


def _signal(nits: np.ndarray, transfer: str) -> np.ndarray:
    """Displayed light (cd/m2) -> the transfer's signal 0..1: PQ's inverse EOTF, or HLG's inverse
    OOTF (gamma 1.2 on 1000 cd/m2) and OETF."""
    if transfer == "pq":
        m1, m2 = 0.1593017578125, 78.84375
        c1, c2, c3 = 0.8359375, 18.8515625, 18.6875
        y = np.clip(nits / 10000.0, 0.0, 1.0) ** m1
        return ((c1 + c2 * y) / (1.0 + c3 * y)) ** m2
    scene = np.clip(nits / 1000.0, 0.0, 1.0) ** (1.0 / 1.2)
    a = 0.17883277
    b, c = 1.0 - 4.0 * a, 0.5 - a * np.log(4.0 * a)
    return np.where(scene <= 1.0 / 12.0, np.sqrt(3.0 * scene), a * np.log(np.maximum(12.0 * scene - b, 1e-12)) + c)


def hdr_frame(rgb: np.ndarray, transfer: str) -> av.VideoFrame:
    """An SDR BT.709 picture, uint8 [shape=(h, w, 3)] (even h, w), as ``transfer``'s ("pq", "hlg") grade:
    a yuv420p10le frame, tagged."""
    light = (rgb.astype(np.float64) / 255.0) ** 2.4 @ _TO_BT2020.T
    e = _signal(light * WHITE_NITS, transfer)
    y = _KR * e[..., 0] + (1.0 - _KR - _KB) * e[..., 1] + _KB * e[..., 2]
    cb, cr = (e[..., 2] - y) / (2.0 * (1.0 - _KB)), (e[..., 0] - y) / (2.0 * (1.0 - _KR))
    h, w = y.shape
    chroma = [(512.0 + 896.0 * c).reshape(h // 2, 2, w // 2, 2).mean(axis=(1, 3)) for c in (cb, cr)]  # 4:2:0
    planes = [64.0 + 876.0 * y] + chroma
    frame = av.VideoFrame(w, h, "yuv420p10le")
    for plane, values in zip(frame.planes, planes):
        buf = np.zeros((plane.height, plane.line_size // 2), np.uint16)
        buf[:, :values.shape[1]] = np.clip(np.rint(values), 0, 1023)
        plane.update(buf.tobytes())
    frame.color_primaries, frame.colorspace, frame.color_trc, frame.color_range = _BT2020, _BT2020, _TRC[transfer], 1
    return frame
