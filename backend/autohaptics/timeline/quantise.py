"""The one 0..255 quantiser: what the editor's binary timeline and the chair's frames carry, so both
show the same step for the same value."""

from __future__ import annotations

import numpy as np

U8_SCALE = 1.0 / 255.0  # value of one step
_CHUNK = 1 << 20  # values quantised at a time (float64 temporaries stay in the cache, not 88 MB)


def to_u8(values: np.ndarray, scale: float = 1.0) -> np.ndarray:
    """floor(clip(v * scale, 0, 1) * 255 + 0.5), uint8 of ``values``' shape (round half up; NaN as 0)."""
    src = np.ascontiguousarray(values).reshape(-1)
    out = np.empty(src.shape, np.uint8)
    for a in range(0, src.size, _CHUNK):
        chunk = src[a:a + _CHUNK].astype(np.float64)
        if scale != 1.0:
            chunk *= scale
        np.clip(np.nan_to_num(chunk, copy=False, nan=0.0), 0.0, 1.0, out=chunk)
        chunk *= 255.0
        chunk += 0.5
        out[a:a + _CHUNK] = np.floor(chunk, out=chunk)
    return out.reshape(np.shape(values))
