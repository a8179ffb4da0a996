"""Media decoding behind one small interface (PyAV / FFmpeg); stages never touch FFmpeg.

:mod:`.probe` (what a file holds, tolerant decoding, truncation), :mod:`.audio` (the mono 48 kHz
analysis signal), :mod:`.video` (decoded frames, all or the reference ones only), :mod:`.frames`
(a frame's small proxies, made only when a stage asks), :mod:`.active` (the active picture
inside black bars) and :mod:`.overlays` (what a copy burns in over the film).
"""

from autohaptics.lazy import lazy_attributes
from autohaptics.media.probe import (AudioInfo, AudioReport, MediaInfo, VideoInfo, check_complete, check_truncation,
                                     open_container, probe, source_block)

# Imported when first used: the video side brings OpenCV (~0.15 s), which the audio pass and
# `autohaptics features` never need.
_LAZY = {"iter_audio": "audio", "read_audio": "audio", "Frame": "frames", "DECODE_MODES": "video",
         "SPARSE_MIN_FPS": "video", "iter_video": "video", "find_active_area": "active",
         "find_picture": "active", "sample_lumas": "active"}

__getattr__ = lazy_attributes(__name__, _LAZY)


__all__ = ["AudioInfo", "AudioReport", "DECODE_MODES", "Frame", "MediaInfo", "SPARSE_MIN_FPS", "VideoInfo",
           "check_complete", "check_truncation", "find_active_area", "find_picture", "iter_audio", "iter_video",
           "open_container", "probe", "read_audio", "sample_lumas", "source_block"]
