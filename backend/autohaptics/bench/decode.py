"""The bare decode every speed figure of the benchmarks is divided by: the plainest PyAV decode of
a file, with nothing of ours around it (no tolerant wrapper, no probe, no thread rule), so a ratio
measured against it says what the analysis costs on top of what any player pays to decode."""

from __future__ import annotations

import os

import av


def bare_decode(path: str | os.PathLike) -> dict:
    """Decode every frame of ``path``'s first video stream (FFmpeg's own threads, ``thread_type``
    AUTO), then every frame of its first audio stream; nothing is converted.

    Returns {"video_frames": int, "audio_samples": int}: what was decoded (0 for a missing stream).
    """
    counts = {"video_frames": 0, "audio_samples": 0}
    with av.open(str(path)) as c:
        if c.streams.video:
            stream = c.streams.video[0]
            stream.thread_type = "AUTO"
            for _ in c.decode(stream):
                counts["video_frames"] += 1
    with av.open(str(path)) as c:
        if c.streams.audio:
            for frame in c.decode(c.streams.audio[0]):
                counts["audio_samples"] += frame.samples
    return counts
