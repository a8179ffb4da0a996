"""Overlays burnt in over a film as copies carry them (:mod:`autohaptics.media.overlays`' known answers
and the matrix's rows): a screener's or a daily's timecode (a black box at the bottom centre, its white
digits counting the frames from 01:00:00:00), a channel's logo (a ring and letters at 60 % white, top
right) and a watermark (a line of words at 35 % white across the middle); and film grain, which a
scan or a grain-preserving encode carries over the whole picture (the matrix's grain row).
"""

from __future__ import annotations

import os
from fractions import Fraction
from pathlib import Path

import av
import cv2
import numpy as np

from autohaptics.errors import ParameterError
from autohaptics.testing.encode import media_output

OVERLAYS = ("timecode", "logo", "watermark")  # each in its place; grain over the whole picture
KINDS = (*OVERLAYS, "grain")
WATERMARK = "SCREENER  PROPERTY OF ACME"
GRAIN_SD = 8.0  # grey levels: the grain's standard deviation at the picture's own size


def timecode(frame_no: int, fps: float) -> str:
    """SMPTE-style HH:MM:SS:FF of frame ``frame_no`` (0-based) from 01:00:00:00, at ``fps`` whole frames a second."""
    per_s = max(1, int(round(fps)))
    s, ff = divmod(int(frame_no), per_s)
    return f"{1 + s // 3600:02d}:{s // 60 % 60:02d}:{s % 60:02d}:{ff:02d}"


def timecode_box(width: int, height: int) -> tuple[int, int, int, int]:
    """The timecode box (x, y, w, h) px in a picture ``width`` x ``height``: white digits of height
    about 1/15 of the picture on black, centred, its bottom 4 % of the height above the picture's."""
    scale, thick = height / 400.0, max(1, int(round(height / 160)))
    (tw, th), base = cv2.getTextSize("00:00:00:00", cv2.FONT_HERSHEY_SIMPLEX, scale, thick)
    pad = max(2, int(round(height / 45)))
    w, h = tw + 2 * pad, th + base + 2 * pad
    return (width - w) // 2, height - int(round(0.04 * height)) - h, w, h


def burn(rgb: np.ndarray, kind: str, frame_no: int, fps: float) -> np.ndarray:
    """A copy of ``rgb`` (uint8 [shape=(h, w, 3)]) with the overlay ``kind`` (:data:`KINDS`) of frame
    ``frame_no`` at ``fps`` burnt in."""
    if kind not in KINDS:
        raise ParameterError(f"overlay kind must be one of {KINDS}, got {kind!r}")
    img = np.ascontiguousarray(rgb, np.uint8).copy()
    h, w = img.shape[:2]
    if kind == "grain":
        return grain(img, frame_no)
    if kind == "timecode":
        x, y, bw, bh = timecode_box(w, h)
        scale, thick = h / 400.0, max(1, int(round(h / 160)))
        pad = max(2, int(round(h / 45)))
        cv2.rectangle(img, (x, y), (x + bw - 1, y + bh - 1), (0, 0, 0), cv2.FILLED)
        _, base = cv2.getTextSize("0", cv2.FONT_HERSHEY_SIMPLEX, scale, thick)
        cv2.putText(img, timecode(frame_no, fps), (x + pad, y + bh - pad - base), cv2.FONT_HERSHEY_SIMPLEX, scale,
                    (255, 255, 255), thick, cv2.LINE_AA)
        return img
    over = img.copy()
    if kind == "logo":
        r = max(4, int(round(h * 0.07)))
        cx, cy = w - int(round(w * 0.08)), int(round(h * 0.12))
        cv2.circle(over, (cx, cy), r, (255, 255, 255), max(2, r // 6), cv2.LINE_AA)
        cv2.putText(over, "AH1", (cx - int(r * 0.8), cy + int(r * 0.35)), cv2.FONT_HERSHEY_SIMPLEX, r / 30,
                    (255, 255, 255), max(1, r // 12), cv2.LINE_AA)
        return cv2.addWeighted(over, 0.6, img, 0.4, 0)
    cv2.putText(over, WATERMARK, (int(w * 0.12), int(h * 0.5)), cv2.FONT_HERSHEY_SIMPLEX, h / 300,
                (255, 255, 255), 2, cv2.LINE_AA)
    return cv2.addWeighted(over, 0.35, img, 0.65, 0)


def grain(rgb: np.ndarray, frame_no: int, *, sd: float = GRAIN_SD) -> np.ndarray:
    """``rgb`` (uint8 [shape=(h, w, 3)]) with film grain: Gaussian noise in brightness, a little over a
    pixel across (blurred at a 0.7 px standard deviation), of standard deviation ``sd`` grey levels, new
    every frame (drawn from ``frame_no``, so a frame's grain is the same in every copy)."""
    h, w = rgb.shape[:2]
    noise = cv2.GaussianBlur(np.random.default_rng(int(frame_no)).normal(0.0, 1.0, (h, w)).astype(np.float32),
                             (0, 0), 0.7)
    noise *= float(sd) / max(float(noise.std()), 1e-6)
    return np.clip(rgb.astype(np.float32) + noise[..., None], 0, 255).astype(np.uint8)


def with_burn_in(src: str | os.PathLike, dst: str | os.PathLike, kind: str, *, crf: int = 18,
                 gop: int | None = None) -> Path:
    """``src``'s picture with the overlay ``kind`` burnt in, coded again (H.264 veryfast, ``crf``, a
    keyframe every ``gop`` frames or x264's default, each frame on its own time), and its sound's
    packets as they are, into ``dst`` (Matroska)."""
    if kind not in KINDS:
        raise ParameterError(f"overlay kind must be one of {KINDS}, got {kind!r}")
    dst = Path(dst)
    with media_output(dst, f"to burn a {kind} into {src}") as tmp:
        with av.open(str(src)) as inp, av.open(str(tmp), mode="w", format="matroska") as out:
            v_in = inp.streams.video[0]
            fps = float(v_in.average_rate or v_in.guessed_rate or 25)
            v_out = out.add_stream("libx264", rate=Fraction(v_in.average_rate or 25).limit_denominator(1001))
            v_out.width, v_out.height, v_out.pix_fmt = v_in.codec_context.width, v_in.codec_context.height, "yuv420p"
            v_out.time_base = v_in.time_base
            v_out.options = {"preset": "veryfast", "crf": str(int(crf)), **({"g": str(int(gop))} if gop else {})}
            a_in = inp.streams.audio[0] if inp.streams.audio else None
            a_out = out.add_stream_from_template(a_in) if a_in is not None else None
            start = float(v_in.start_time * v_in.time_base) if v_in.start_time is not None else 0.0
            for packet in inp.demux(*[s for s in (v_in, a_in) if s is not None]):
                if packet.stream is a_in:
                    if packet.dts is not None:
                        packet.stream = a_out
                        out.mux(packet)
                    continue
                for frame in packet.decode():
                    n = int(round((float(frame.time) - start) * fps)) if frame.time is not None else 0
                    pic = av.VideoFrame.from_ndarray(burn(frame.to_ndarray(format="rgb24"), kind, n, fps), format="rgb24")
                    pic = pic.reformat(format="yuv420p")
                    pic.pts, pic.time_base = frame.pts, frame.time_base
                    out.mux(v_out.encode(pic))
            out.mux(v_out.encode(None))
    return dst
