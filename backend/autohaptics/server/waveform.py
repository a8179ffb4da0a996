"""Audio peaks for the editor's waveform lane: min and max of the mono mix per bucket.

The server computes, the browser renders (peaks.js): the film's audio is decoded once through
:func:`media.iter_audio` (mono, 48 kHz, no LFE boost), split into ``points`` equal buckets over
the declared duration, and each bucket's minimum and maximum sample kept, clipped to -1..1.
"""

from __future__ import annotations

import json
import os
from pathlib import Path

import numpy as np

from autohaptics import media
from autohaptics.errors import ParameterError
from autohaptics.timebase import ANALYSIS_SAMPLE_RATE

_DECIMALS = 4


def compute_peaks(path: str | os.PathLike, *, points: int, info: media.MediaInfo | None = None) -> dict:
    """``{points, duration_s, has_audio, min: [points], max: [points]}`` of a media file.

    Bucket b covers samples [b * N / points, (b + 1) * N / points) with N = duration * 48 kHz;
    samples decoded past the declared duration fall into the last bucket, buckets no sample
    reached are 0. A file without audio gives zeros and ``has_audio`` false.
    """
    if int(points) < 1:
        raise ParameterError(f"points must be >= 1, got {points}")
    points = int(points)
    info = info or media.probe(path)
    lo = np.full(points, np.inf)
    hi = np.full(points, -np.inf)
    if info.audio is not None:
        total = max(1, int(round(info.duration_s * ANALYSIS_SAMPLE_RATE)))
        pos = 0
        for chunk in media.iter_audio(path, info=info, lfe_gain_db=0.0):
            idx = np.minimum((np.arange(pos, pos + chunk.size, dtype=np.int64) * points) // total, points - 1)
            pos += chunk.size
            if not chunk.size:
                continue
            starts = np.flatnonzero(np.r_[True, idx[1:] != idx[:-1]])
            buckets = idx[starts]
            lo[buckets] = np.minimum(lo[buckets], np.minimum.reduceat(chunk, starts))
            hi[buckets] = np.maximum(hi[buckets], np.maximum.reduceat(chunk, starts))
    empty = ~np.isfinite(lo)
    lo[empty] = 0.0
    hi[empty] = 0.0
    lo = np.round(np.clip(lo, -1.0, 1.0), _DECIMALS) + 0.0
    hi = np.round(np.clip(hi, -1.0, 1.0), _DECIMALS) + 0.0
    return {"points": points, "duration_s": round(info.duration_s, 6), "has_audio": info.audio is not None,
            "min": lo.tolist(), "max": hi.tolist()}


def cached_peaks(media_path: Path, cache_path: Path, *, points: int) -> dict:
    """:func:`compute_peaks`, read from / written to ``cache_path`` (JSON, written atomically)."""
    try:
        with open(cache_path, encoding="utf-8") as fh:
            return json.load(fh)
    except (FileNotFoundError, json.JSONDecodeError):
        pass
    peaks = compute_peaks(media_path, points=points)
    tmp = cache_path.with_name(cache_path.name + ".part")
    try:
        with open(tmp, "w", encoding="utf-8") as fh:
            json.dump(peaks, fh, separators=(",", ":"))
        os.replace(tmp, cache_path)
    except FileNotFoundError:  # the project was deleted meanwhile: nothing to cache
        pass
    finally:
        tmp.unlink(missing_ok=True)
    return peaks
