"""Media decoding behind one small interface (PyAV / FFmpeg); stages never touch FFmpeg.

:mod:`.probe` (what a file holds, tolerant decoding, truncation), :mod:`.audio` (the mono 48 kHz
analysis signal), :mod:`.video` (decoded frames, all or the reference ones only) and :mod:`.frames`
(a frame's small proxies, made only when a stage asks).
"""

from autohaptics.media.audio import iter_audio, read_audio
from autohaptics.media.frames import Frame
from autohaptics.media.probe import (AudioInfo, AudioReport, MediaInfo, VideoInfo, check_complete, check_truncation,
                                     open_container, probe, source_block)
from autohaptics.media.video import DECODE_MODES, SPARSE_MIN_FPS, decode_all, iter_video

__all__ = ["AudioInfo", "AudioReport", "DECODE_MODES", "Frame", "MediaInfo", "SPARSE_MIN_FPS", "VideoInfo",
           "check_complete", "check_truncation", "decode_all", "iter_audio", "iter_video", "open_container", "probe",
           "read_audio", "source_block"]
