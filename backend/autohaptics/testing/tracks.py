"""A film whose own mix comes last of three sound tracks, as a rip or a HandBrake file holds them: first a
director's commentary (flagged and titled so: a voice over the film's mix turned down), then a
compatibility stereo track flagged as the default (FFmpeg's stereo downmix of the mix, AAC), then the
mix itself, its packets copied (``media.tracks.sound_stream`` must find it).
"""

from __future__ import annotations

import os
from pathlib import Path

import av
import numpy as np

from autohaptics.errors import ParameterError
from autohaptics.testing.encode import encode_samples

RATE = 48000
VOICE_DBFS = -18.0  # the commentary's voice, rms
UNDER_DB = -12.0  # the film's mix under the commentary
SYLLABLES_HZ = 4.0  # the voice's syllable rate


def _voice(n: int, seed: int = 7) -> np.ndarray:
    """A voice-like noise [shape=(n,)] at ``VOICE_DBFS``: speech-band noise in syllables, pauses between
    phrases."""
    rng = np.random.default_rng(seed)
    t = np.arange(n) / RATE
    band = np.convolve(rng.standard_normal(n), np.hanning(24), mode="same")  # about 300 Hz-2 kHz
    envelope = np.clip(np.sin(2 * np.pi * SYLLABLES_HZ * t), 0.0, None) * (np.sin(2 * np.pi * 0.2 * t) > -0.3)
    x = band * envelope
    rms = float(np.sqrt(np.mean(x * x))) or 1.0
    return (x / rms * 10.0 ** (VOICE_DBFS / 20.0)).astype(np.float32)


def with_tracks_ahead(src: str | os.PathLike, dst: str | os.PathLike) -> Path:
    """``src`` (a film with sound) as a Matroska file (module docstring): its picture's packets copied,
    then the commentary (Opus), the compatibility stereo (AAC) and the mix (copied)."""
    dst = Path(dst)
    with av.open(str(src)) as c:
        if not c.streams.audio or not c.streams.video:
            raise ParameterError(f"{src}: a film with picture and sound is needed")
        stereo = []
        down = av.AudioResampler(format="flt", layout="stereo", rate=RATE)
        for frame in c.decode(c.streams.audio[0]):
            stereo += [f.to_ndarray().reshape(-1, 2).T for f in down.resample(frame)]
        stereo += [f.to_ndarray().reshape(-1, 2).T for f in down.resample(None)]
    mix = np.concatenate(stereo, axis=1) if stereo else np.zeros((2, 0), np.float32)
    commentary = np.clip(mix * 10.0 ** (UNDER_DB / 20.0) + _voice(mix.shape[1])[None, :], -1.0, 1.0)
    with av.open(str(src)) as c, av.open(str(dst), "w", format="matroska") as out:
        video = out.add_stream_from_template(c.streams.video[0])
        talk = out.add_stream("libopus", rate=RATE, layout="stereo")
        talk.disposition, talk.metadata["title"] = av.stream.Disposition.comment, "Director's commentary"
        compat = out.add_stream("aac", rate=RATE, layout="stereo")
        compat.bit_rate, compat.disposition = 160_000, av.stream.Disposition.default
        own = out.add_stream_from_template(c.streams.audio[0])
        own.disposition = 0
        for stream, x in ((talk, commentary), (compat, mix)):
            encode_samples(out, stream, x, step=960)
        for packet in c.demux(c.streams.video[0], c.streams.audio[0]):
            if packet.size:
                packet.stream = video if packet.stream.type == "video" else own
                out.mux(packet)
    return dst

