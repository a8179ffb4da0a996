"""A decoded picture and its proxies: small, colour-converted copies in display orientation, made
only when a stage asks (converting every 1080p frame to RGB costs as much as decoding it).

For planar YUV (8-bit, and 9-16 bits in 16-bit words: 10-bit encodes, ProRes masters) the planes are
area-averaged in place (OpenCV's area averaging, :mod:`.area`; a wide plane brought to 8-bit scale
after its first halving) and converted on the small proxy (BT.709 or BT.2020 for frames tagged so,
BT.601 otherwise, as FFmpeg's scaler does), within about 2 grey levels of FFmpeg's scaled conversion of the
full frame and about 3x cheaper. HDR frames (PQ, HLG) give SDR proxies, luma and colour (:mod:`.hdr`).

An interlaced frame (two fields, each a moment of its own: 1080i and 576i broadcasts, a hard-telecined
DVD) gives its small proxies from its top field alone: both fields together show whatever moves twice,
combed, and optical flow between such pictures reads the two copies (docs/BENCHMARKS.md, "Stop 57").
Full-size copies (:meth:`Frame.full`, :meth:`Frame.fields`) keep both fields.

A frame may be cropped to a rectangle (the active picture inside black bars,
:mod:`autohaptics.media.active`): its size, proxies and copies are then those of the rectangle,
read as a view of the decoded planes (a letterboxed film's bars are never read).
"""

from __future__ import annotations

import av
import cv2
import numpy as np

from autohaptics.media import hdr
from autohaptics.media.area import area_resize

_PLANAR_YUV8 = {"yuv420p", "yuvj420p", "yuv422p", "yuvj422p", "yuv444p", "yuvj444p", "yuv440p", "yuvj440p"}
# planar YUV stored in 16-bit words (10-bit H.264/HEVC, ProRes and DNxHR masters): name -> bits
_PLANAR_YUV_WIDE = {f"yuv{a}{s}p{bits}le": bits for a in ("", "a") for s in ("420", "422", "444", "440")
                    for bits in (9, 10, 12, 14, 16)}


class Frame:
    """One decoded picture. It holds its own reference to the decoded planes, so it can be read after
    later frames are decoded (the video pass reads a flow pair's successor a few frames on)."""

    __slots__ = ("_frame", "index", "time_s", "rotation", "width", "height", "_crop", "_ready", "_luma_kept", "ahead",
                 "_stretch")

    def __init__(self, frame: av.VideoFrame, index: int, time_s: float, rotation: int,
                 crop: tuple[int, int, int, int] | None = None, shown_aspect: float | None = None,
                 size: tuple[int, int] | None = None):
        """crop : (x, y, width, height) px in display orientation, even: the frame is that
        rectangle of the decoded picture (None, or a rectangle that does not fit inside it: the
        whole picture).
        shown_aspect : that picture's width / height on screen, where its pixels are not square (an
        anamorphic DVD, a 3D film's half-width view): a proxy's height keeps it (None: as stored).
        size : the stream's stored (width, height) px (``VideoInfo``): a picture decoded at another
        size (a stream whose size changes mid-file: an adaptive stream's recording, a channel's SD
        and HD programmes) is scaled to it, so crops, proxies and the frames compared with each
        other keep one geometry (None: as decoded)."""
        if size is not None and min(size) > 0 and (frame.width, frame.height) != tuple(size):
            frame = frame.reformat(width=int(size[0]), height=int(size[1]))
        self._frame = frame
        self.index = index  # decoded frame number, 0-based
        self.time_s = time_s  # presentation time relative to the container start, seconds
        self.rotation = rotation
        self.width, self.height = (frame.height, frame.width) if rotation % 180 else (frame.width, frame.height)
        self._crop = None  # (x, y, w, h) of the decoded (stored) picture, None: all of it
        if crop is not None and tuple(crop) != (0, 0, self.width, self.height):
            self._crop = _stored_rect(crop, rotation, frame.width, frame.height)
            if self._crop is not None:
                self.width, self.height = int(crop[2]), int(crop[3])
        self._ready: dict = {}  # planes made ahead by prepare(), each taken once
        self._luma_kept: tuple | None = None  # (w, h, luma plane as stored) of the last gray proxy read
        # decoded ahead in a thread that still held half its queue when the caller took this frame:
        # the caller's analysis, not the decoder, is the slower side then (media.video.iter_video)
        self.ahead = False
        stretch = float(shown_aspect) * self.height / max(1, self.width) if shown_aspect else 1.0
        self._stretch = stretch if abs(stretch - 1.0) > 1e-6 else None  # shown width / stored width

    def prepare(self, gray_width: int, rgb_width: int, luma_size: tuple[int, int] | None = None) -> None:
        """Make ahead the small planes that ``gray(gray_width)`` and ``rgb_and_gray(rgb_width,
        gray_width, luma_size=luma_size)`` read, e.g. in the decoding thread while the caller
        analyses an earlier frame (OpenCV runs without the GIL): those calls then return the same
        arrays sooner, and the full luma plane is read once."""
        gw, gh = self._size(gray_width, None)
        rw, rh = self._size(rgb_width, None)
        grid: list = []
        ys = self._planes_small(gw, gh, colour=False, grid=luma_size, grid_out=grid)
        if ys is not None:
            self._ready[(gw, gh, False, True)] = ys
            self._ready[(rw, rh, True, False)] = self._planes_small(rw, rh, colour=True, luma=False)
            if grid:
                self._ready[("grid", tuple(luma_size))] = grid[0]

    def _size(self, width: int, height: int | None) -> tuple[int, int]:
        width = max(1, int(width))
        if height is None and self._stretch is not None:
            height = max(1, int(round(width * self.height / (max(1, self.width) * self._stretch))))
        elif height is None:
            height = max(1, int(round(width * self.height / max(1, self.width))))
        return width, max(1, int(height))

    def proxy(self, width: int, height: int | None = None, *, fmt: str = "rgb24",
              interpolation: str = "AREA") -> np.ndarray:
        """Scaled, colour-converted copy in display orientation.

        width, height : proxy size in pixels (height defaults to keep the aspect shown on screen).
        fmt : "rgb24" -> uint8 [shape=(h, w, 3)]; "gray" -> uint8 [shape=(h, w)] (luma).

        For planar YUV smaller than the frame (nearly every film) the planes are area-averaged
        in place (:mod:`.area`) and converted on the small proxy (BT.709 or BT.2020 matrix for frames
        tagged so, BT.601 otherwise, as FFmpeg's scaler does): about 3x cheaper than FFmpeg's
        scaled conversion of the full frame, within about 2 grey levels of it. An HDR frame's
        proxies are SDR ones (:mod:`.hdr`).
        """
        width, height = self._size(width, height)
        planes = self._planes_small(width, height, colour=fmt == "rgb24") if fmt in ("rgb24", "gray") else None
        if planes is not None and fmt == "rgb24":
            return _yuv_to_rgb(*planes, self._frame)
        if planes is not None:
            self._luma_kept = (width, height, planes[0])  # for rgb(): the plane is not read again
            return _luma_full_range(planes[0], self._frame)
        w, h = (height, width) if self.rotation % 180 else (width, height)
        if self._crop is not None:  # the whole picture converted, the rectangle taken and scaled
            x, y, cw, ch = self._crop
            arr = self._frame.to_ndarray(format=fmt)[y:y + ch, x:x + cw]
            if (cw, ch) != (w, h):
                arr = cv2.resize(arr, (max(1, w), max(1, h)),
                                 interpolation=cv2.INTER_AREA if w <= cw and h <= ch else cv2.INTER_LINEAR)
        else:
            arr = self._frame.to_ndarray(width=max(1, w), height=max(1, h), format=fmt,
                                         interpolation=interpolation)
        if self.rotation:
            arr = np.ascontiguousarray(np.rot90(arr, k=self.rotation // 90))
        if hdr.transfer(self._frame) is not None and fmt in ("rgb24", "gray"):  # FFmpeg's full-range signal
            arr = hdr.sdr_rgb(arr, self._frame) if fmt == "rgb24" else hdr.sdr_luma(arr, self._frame, True)
        return arr

    def fields(self, width: int) -> tuple[np.ndarray, np.ndarray]:
        """The picture's two fields (its even rows, its odd rows) as RGB proxies ``width`` px wide, uint8
        [shape=(h, w, 3)] each: a telecined or interlaced frame holds two moments, or at a cut two shots."""
        full = self.proxy(self.width, self.height)
        out = []
        for field in (full[0::2], full[1::2]):
            h = max(1, int(round(width * field.shape[0] / max(1, field.shape[1]))))
            out.append(cv2.resize(field, (max(1, int(width)), h), interpolation=cv2.INTER_AREA))
        return out[0], out[1]

    def gray(self, width: int) -> np.ndarray:
        """Luma proxy ``width`` px wide (aspect kept), uint8 [shape=(h, w)], display orientation."""
        return self.proxy(width, fmt="gray")

    def rgb(self, width: int, gray_width: int) -> np.ndarray:
        """The RGB proxy of ``rgb_and_gray(width, gray_width)`` alone (the same array), its luma
        taken from the gray proxy's plane when :meth:`gray` has read it: a frame first read for its
        gray proxy is not read again."""
        gw, gh = self._size(gray_width, None)
        rw, rh = self._size(width, None)
        kept = self._luma_kept
        if kept is not None and kept[:2] == (gw, gh):
            y_raw = kept[2]
        else:
            ys = self._planes_small(gw, gh, colour=False)
            y_raw = ys[0] if ys is not None else None
        chroma = self._planes_small(rw, rh, colour=True, luma=False) if y_raw is not None else None
        if chroma is None:
            return self.proxy(width)
        return self._rgb_from(y_raw, (gw, gh), (rw, rh), chroma)

    def _rgb_from(self, y_raw: np.ndarray, gray_size: tuple[int, int], size: tuple[int, int], chroma) -> np.ndarray:
        """The RGB proxy of ``size`` (w, h) from the luma plane at ``gray_size`` and the chroma
        planes at ``size`` (as :meth:`_planes_small` returns them)."""
        y_rgb = y_raw if gray_size == size else cv2.resize(
            y_raw, size, interpolation=cv2.INTER_AREA if size[0] < gray_size[0] else cv2.INTER_LINEAR)
        return _yuv_to_rgb(y_rgb, chroma[1], chroma[2], self._frame)

    def rgb_and_gray(self, width: int, gray_width: int, *, luma_size: tuple[int, int] | None = None):
        """An RGB proxy ``width`` px wide and a luma proxy ``gray_width`` px wide from ONE read of
        the luma plane (reading a 1080p plane costs more than everything done to the proxy).

        The luma proxy is bit-identical to :meth:`gray` (optical flow compares it with the next
        frame's :meth:`gray`); the RGB proxy's luma is resampled from it.
        luma_size : (w, h) px: also return the luma area-averaged to exactly that size (aspect not
            kept) from the full-resolution plane in the same read, whatever the proxies' sizes;
            the third item of the result (uint8 [shape=(h, w)], full range, display orientation).
        Returns (rgb, gray) or, with ``luma_size``, (rgb, gray, luma).
        """
        gw, gh = self._size(gray_width, None)
        rw, rh = self._size(width, None)
        grid: list = []
        ys = self._planes_small(gw, gh, colour=False, grid=luma_size, grid_out=grid)
        chroma = self._planes_small(rw, rh, colour=True, luma=False) if ys is not None else None
        if ys is None or chroma is None:
            rgb, gray = self.proxy(width), self.gray(gray_width)
            if luma_size is None:
                return rgb, gray
            return rgb, gray, self.luma_grid(luma_size)
        y_raw = ys[0]
        rgb, gray = self._rgb_from(y_raw, (gw, gh), (rw, rh), chroma), _luma_full_range(y_raw, self._frame)
        if luma_size is None:
            return rgb, gray
        return rgb, gray, _luma_full_range(grid[0], self._frame)

    def luma_grid(self, size: tuple[int, int]) -> np.ndarray:
        """The luma area-averaged to exactly ``size`` (w, h) px from the full frame (aspect not
        kept), full range, display orientation: uint8 [shape=(h, w)]."""
        full = self.proxy(self.width, self.height, fmt="gray")
        return area_resize(full, (max(1, int(size[0])), max(1, int(size[1]))))

    def luma(self) -> np.ndarray:
        """The full-resolution luma, full range, display orientation: uint8 [shape=(h, w)], a
        copy. For planar YUV the decoded plane itself (at 8-bit scale), range-converted as
        :meth:`gray` does (at 1080p about 10x cheaper than FFmpeg's gray conversion of :meth:`full`);
        else that."""
        f = self._frame
        arr = _plane(f, 0)
        if arr is None:
            return self.full(fmt="gray")
        if self._crop is not None:
            x, y, w, h = self._crop
            arr = arr[y:y + h, x:x + w]
        arr = _to_8_bit(arr, f)
        full = _luma_full_range(arr, f)
        arr = full.copy() if full is arr else full
        k = self.rotation // 90
        return np.ascontiguousarray(np.rot90(arr, k=k)) if k else arr

    def luma_sample(self, cols: int = 64, rows: int = 36) -> np.ndarray | None:
        """About ``cols`` x ``rows`` luma samples taken on a grid of the decoded plane as stored, 8-bit
        scale: uint8 (None for a pixel format without planar luma). Microseconds at any size: the
        repeat test of :mod:`autohaptics.airflow.cadence`, which needs no scaling."""
        f = self._frame
        arr = _plane(f, 0)
        if arr is None:
            return None
        sy, sx = max(1, arr.shape[0] // max(1, rows)), max(1, arr.shape[1] // max(1, cols))
        grid = arr[sy // 2::sy, sx // 2::sx]
        bits = _stored_bits(f)
        return (grid >> (bits - 8)).astype(np.uint8) if bits > 8 else grid.copy()

    def full(self, *, fmt: str = "rgb24") -> np.ndarray:
        """Full-resolution copy in display orientation (the reference preset)."""
        return self.proxy(self.width, self.height, fmt=fmt)

    def _planes_small(self, width: int, height: int, *, colour: bool, luma: bool = True,
                      grid: tuple[int, int] | None = None, grid_out: list | None = None):
        """(Y, U, V) area-averaged to (height, width) in display orientation, uint8 (None for a
        plane not asked for); None when the pixel format has no fast path or the proxy is not
        smaller than the frame. ``grid`` (w, h): the luma is also area-averaged to that size
        (display orientation, limited range as stored) and appended to ``grid_out``."""
        if self._ready:
            key = (width, height, colour, luma)
            if grid is None and key in self._ready:
                return self._ready.pop(key)
            made = ("grid", tuple(grid)) if grid is not None else None
            if made in self._ready and key in self._ready and grid_out is not None:
                grid_out.append(self._ready.pop(made))
                return self._ready.pop(key)
        f = self._frame
        if _stored_bits(f) is None or width >= self.width or height >= self.height:
            return None
        k = self.rotation // 90
        dw, dh = (height, width) if k % 2 else (width, height)  # target (w, h) before rotation
        field = f.interlaced_frame and 2 * dh <= f.height  # the top field alone (module docstring)
        out = []
        for i in range(3 if colour else 1):
            if i == 0 and not luma:
                out.append(None)
                continue
            arr = _plane(f, i)[0::2] if field else _plane(f, i)
            ph, pw = arr.shape
            if self._crop is not None:  # a view of the rectangle, at the plane's own sub-sampling
                x, y, cw_, ch_ = self._crop
                sx, sy = pw / f.width, ph / f.height
                arr = arr[round(y * sy):round((y + ch_) * sy), round(x * sx):round((x + cw_) * sx)]
                ph, pw = arr.shape
            if i == 0 and pw >= 4 * dw and ph >= 4 * dh:
                # 4x or more: average 2 x 2 blocks first (cv2.pyrDown-like), then area-scale: half
                # the memory traffic of one big area pass, the same proxy within a grey level
                arr = cv2.resize(arr, (pw // 2, ph // 2), interpolation=cv2.INTER_AREA)
            arr = _to_8_bit(arr, f)  # a wide plane: the fractional area passes below are 8-bit ones
            # chroma too straight to the proxy's size at its own scale, as FFmpeg's scaler does (4:2:0
            # 1080p to 240 px: two exact halvings)
            small = _shrink(arr, (dw, dh))
            if i == 0 and grid is not None and grid_out is not None:
                gw_, gh_ = (int(grid[1]), int(grid[0])) if k % 2 else (int(grid[0]), int(grid[1]))
                g = area_resize(arr, (gw_, gh_))
                grid_out.append(np.ascontiguousarray(np.rot90(g, k=k)) if k else g)
            out.append(np.ascontiguousarray(np.rot90(small, k=k)) if k else small)
        return out if colour else (out[0], None, None)


def _stored_rect(rect, rotation: int, width: int, height: int) -> tuple[int, int, int, int] | None:
    """A rectangle (x, y, w, h) in display orientation as the same rectangle of the decoded
    picture (``width`` x ``height``), which display orientation rotates by ``rotation`` degrees
    counter-clockwise (``np.rot90``); None when it does not fit inside."""
    x, y, w, h = (int(v) for v in rect)
    k = rotation // 90 % 4
    sx, sy, sw, sh = [(x, y, w, h), (width - y - h, x, h, w), (width - x - w, height - y - h, w, h),
                      (y, height - x - w, h, w)][k]
    if min(sx, sy) < 0 or min(sw, sh) <= 0 or sx + sw > width or sy + sh > height:
        return None
    return sx, sy, sw, sh


def _stored_bits(frame: av.VideoFrame) -> int | None:
    """Bits per sample of a planar YUV frame (8 in bytes, 9-16 in 16-bit words), None for any other
    pixel format (those are converted by FFmpeg's scaler)."""
    name = frame.format.name
    return 8 if name in _PLANAR_YUV8 else _PLANAR_YUV_WIDE.get(name)


def _plane(frame: av.VideoFrame, i: int) -> np.ndarray | None:
    """Plane ``i`` of a planar YUV frame as stored, a view: uint8, or uint16 for 9-16 bits; None
    for another pixel format."""
    bits = _stored_bits(frame)
    if bits is None:
        return None
    plane = frame.planes[i]
    dtype = np.dtype(np.uint8) if bits == 8 else np.dtype("<u2")
    return np.frombuffer(plane, dtype).reshape(-1, plane.line_size // dtype.itemsize)[:plane.height, :plane.width]


def _to_8_bit(arr: np.ndarray, frame: av.VideoFrame) -> np.ndarray:
    """Samples of ``frame``'s planes at 8-bit scale, rounded (the array itself when 8-bit already, or
    when the frame is HDR: its planes keep their bits until its transfer, :mod:`.hdr`)."""
    if arr.dtype == np.uint8 or hdr.transfer(frame) is not None:
        return arr
    return cv2.convertScaleAbs(arr, alpha=1.0 / (1 << (_stored_bits(frame) - 8)))


def _shrink(arr: np.ndarray, size: tuple[int, int]) -> np.ndarray:
    """Area-scale uint8 ``arr`` to ``size`` (w, h) for a proxy: halve by 2 x 2 averaging while 4x or
    more remains on both axes, then :func:`area_resize`. A pyramid, not one exact area pass: on
    1080p luma 960x540 -> 128x72 costs 0.4 instead of 1.2 ms (OpenCV's fractional-ratio area);
    measured on 1080p frames, up to about 5 grey levels off the exact area average, at edges."""
    w, h = int(size[0]), int(size[1])
    while arr.shape[1] >= 4 * w and arr.shape[0] >= 4 * h:
        arr = cv2.resize(arr, (arr.shape[1] // 2, arr.shape[0] // 2), interpolation=cv2.INTER_AREA)
    return area_resize(arr, (w, h))


def _full_range(frame: av.VideoFrame) -> bool:
    return frame.format.name.startswith("yuvj") or getattr(frame, "color_range", 0) == 2


def _luma_full_range(y: np.ndarray, frame: av.VideoFrame) -> np.ndarray:
    """Limited-range luma 16..235 -> 0..255, as FFmpeg's gray conversion does; an HDR frame's as SDR
    luma (:mod:`.hdr`)."""
    if hdr.transfer(frame) is not None:
        return hdr.sdr_luma(y, frame, _full_range(frame), _stored_bits(frame) or 8)
    if _full_range(frame):
        return y
    return cv2.convertScaleAbs(y, alpha=255.0 / 219.0, beta=-16.0 * 255.0 / 219.0)


def _yuv_to_rgb(y: np.ndarray, u: np.ndarray, v: np.ndarray, frame: av.VideoFrame) -> np.ndarray:
    """Y, U, V planes of one size (uint8; an HDR frame's uint16 as stored) -> uint8 RGB [shape=(h, w, 3)],
    float32 arithmetic rounded half up (BT.709, BT.2020 or BT.601 by the frame's tag, limited or full
    range), each channel computed in place in a plane of its own and interleaved by OpenCV (fewer passes
    than channel slices); an HDR frame's brought to SDR (:mod:`.hdr`)."""
    kr, kb = _LUMA_WEIGHTS.get(getattr(frame, "colorspace", 0), (0.299, 0.114))
    kg = 1.0 - kr - kb
    yy, cb, cr = y.astype(np.float32), u.astype(np.float32), v.astype(np.float32)
    if y.dtype != np.uint8:  # an HDR frame's planes as stored (:func:`_to_8_bit`): to 8-bit scale, unrounded
        for c in (yy, cb, cr):
            c *= np.float32(1.0 / (1 << (_stored_bits(frame) - 8)))
    cb -= np.float32(128.0)
    cr -= np.float32(128.0)
    if not _full_range(frame):
        yy -= np.float32(16.0)
        yy *= np.float32(255.0 / 219.0)
        cb *= np.float32(255.0 / 224.0)
        cr *= np.float32(255.0 / 224.0)
    rgb = np.empty((3,) + y.shape, np.float32)
    tmp = np.empty(y.shape, np.float32)
    np.add(yy, np.multiply(cr, np.float32(2.0 * (1.0 - kr)), out=rgb[0]), out=rgb[0])
    np.subtract(yy, np.multiply(cb, np.float32(2.0 * kb * (1.0 - kb) / kg), out=tmp), out=rgb[1])
    np.subtract(rgb[1], np.multiply(cr, np.float32(2.0 * kr * (1.0 - kr) / kg), out=tmp), out=rgb[1])
    np.add(yy, np.multiply(cb, np.float32(2.0 * (1.0 - kb)), out=rgb[2]), out=rgb[2])
    if hdr.transfer(frame) is not None:
        np.clip(rgb, 0.0, 255.0, out=rgb)
        return hdr.sdr_rgb(cv2.merge(list(rgb)), frame)
    rgb += np.float32(0.5)
    np.clip(rgb, 0.0, 255.0, out=rgb)
    return cv2.merge([c.astype(np.uint8) for c in rgb])


# (Kr, Kb) of the YCbCr matrix by FFmpeg's AVColorSpace tag: BT.709, BT.2020 (non-constant and constant
# luminance, the latter read as the former); any other tag BT.601, as FFmpeg's scaler reads it
_LUMA_WEIGHTS = {1: (0.2126, 0.0722), 9: (0.2627, 0.0593), 10: (0.2627, 0.0593)}
