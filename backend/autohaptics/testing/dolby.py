"""AC-3 with dynamic range words, as a Dolby encoder writes it (DVDs, Blu-rays, broadcasts): FFmpeg's own
encoder writes none, so a test or a benchmark writes its AC-3 with FFmpeg and sets the words afterwards.

Each syncframe (1536 samples, six audio blocks) gets the dynamic range gain ``dynrng`` in its first block;
the blocks after it keep that gain (ATSC A/52, 7.7.1.2), so the gain changes once a frame (32 ms at 48 kHz).
Inserting the word moves the rest of the frame 8 bits on and drops the last 8 bits before the CRC: the
encoder's padding, or the last mantissas of the frame's last block. The CRCs are left as they are;
FFmpeg's decoder checks them only when asked to (``err_detect``).
"""

from __future__ import annotations

import math
import os
from pathlib import Path

import av
import numpy as np

from autohaptics.errors import ParameterError
from autohaptics.testing.encode import encode_samples

SAMPLES_PER_FRAME = 1536
_FULL_CHANNELS = (2, 1, 2, 3, 3, 4, 4, 5)  # full-bandwidth channels by acmod


def drc_code(gain_db: float) -> int:
    """The ``dynrng`` word (0..255) nearest ``gain_db``, -24..+24 dB: gain = 2^X (32 + Y) / 32, X the top
    three bits (two's complement), Y the low five."""
    g = 10.0 ** (float(np.clip(gain_db, -24.0, 23.9)) / 20.0)
    x = max(-4, min(3, math.floor(math.log2(g))))
    y = int(max(0, round((g / 2.0 ** x - 1.0) * 32.0)))
    if y > 31:  # rounds up to the next power of two
        x, y = (x + 1, 0) if x < 3 else (3, 31)
    return ((x & 7) << 5) | y


def drc_gain_db(code: int) -> float:
    """The gain of a ``dynrng`` word, dB (the inverse of :func:`drc_code`)."""
    x = (code >> 5) - ((code >> 7) << 3)
    return 20.0 * math.log10(2.0 ** x * (32 + (code & 31)) / 32.0)


def _first_block_flag(bits: np.ndarray) -> int:
    """The bit position of the first audio block's ``dynrnge`` flag in a syncframe's bits (A/52 5.4)."""
    pos = 40  # syncinfo: syncword, crc1, fscod, frmsizecod

    def take(n: int) -> int:
        nonlocal pos
        v = int("".join(map(str, bits[pos:pos + n])) or "0", 2)
        pos += n
        return v

    take(8)  # bsid, bsmod
    acmod = take(3)
    take(2 if (acmod & 1) and acmod != 1 else 0)  # cmixlev
    take(2 if acmod & 4 else 0)  # surmixlev
    take(2 if acmod == 2 else 0)  # dsurmod
    take(1)  # lfeon
    for _ in range(2 if acmod == 0 else 1):  # dialnorm, compr, langcod, audprodi (twice for 1+1)
        take(5)
        for length in (8, 8, 7):
            if take(1):
                take(length)
    take(2)  # copyrightb, origbs
    for _ in range(2):  # timecod1/2, or xbsi1/2: 14 bits each
        if take(1):
            take(14)
    if take(1):  # addbsi
        take(8 * (take(6) + 1))
    return pos + 2 * _FULL_CHANNELS[acmod]  # past blksw and dithflag


def with_drc(frame: bytes, code: int) -> bytes:
    """An AC-3 syncframe whose first block carries the ``dynrng`` word ``code`` (module docstring).
    Raises ParameterError for a frame that is not AC-3 or already carries a word there."""
    bits = np.unpackbits(np.frombuffer(frame, np.uint8))
    if bits.size < 128 or frame[:2] != b"\x0b\x77":
        raise ParameterError("not an AC-3 syncframe")
    pos = _first_block_flag(bits)
    if bits[pos]:
        raise ParameterError("the frame carries a dynamic range word already")
    word = np.unpackbits(np.array([code], np.uint8))
    out = np.concatenate([bits[:pos], [1], word, bits[pos + 1:-24], bits[-16:]]).astype(np.uint8)
    return np.packbits(out).tobytes()


def write_ac3(path: str | os.PathLike, samples: np.ndarray, layout: str, *, gains_db=None,
              bit_rate: int = 448_000) -> Path:
    """Raw AC-3 of ``samples`` (float [shape=(channels, n)] at 48 kHz, -1..1, in ``layout``'s order)
    written by FFmpeg, each syncframe k carrying the dynamic range gain ``gains_db[k]`` (None: no words,
    as FFmpeg writes it; a shorter list: the frames after it none)."""
    path, rate = Path(path), 48000
    with av.open(str(path), "w", format="ac3") as out:
        stream = out.add_stream("ac3", rate=rate, layout=layout)
        stream.bit_rate = bit_rate
        x = np.asarray(samples, np.float32)
        whole = np.zeros((x.shape[0], math.ceil(x.shape[1] / SAMPLES_PER_FRAME) * SAMPLES_PER_FRAME), np.float32)
        whole[:, :x.shape[1]] = x  # whole syncframes, the last one padded with silence
        encode_samples(out, stream, whole, step=SAMPLES_PER_FRAME)
    if gains_db is not None:
        data = path.read_bytes()
        size = bit_rate // 1000 * 4  # bytes a frame at 48 kHz
        frames = [data[i:i + size] for i in range(0, len(data), size)]
        frames = [with_drc(f, drc_code(gains_db[k])) if k < len(gains_db) else f for k, f in enumerate(frames)]
        path.write_bytes(b"".join(frames))
    return path


# Dolby's "Film Standard" line-mode profile, levels against the dialogue normalisation: +6 dB below -12 dB,
# 2:1 boost up to 0 dB, no change to +5 dB, 2:1 cut to +15 dB, 20:1 above (at most -24 dB)
def film_standard_gain_db(level_db: np.ndarray) -> np.ndarray:
    """The profile's static gain, dB, at ``level_db`` (dB against the dialogue normalisation)."""
    x = np.asarray(level_db, np.float64)
    gain = np.where(x < -12.0, 6.0, np.where(x < 0.0, -x / 2.0, 0.0))
    gain = np.where(x >= 5.0, -(np.minimum(x, 15.0) - 5.0) / 2.0 - np.maximum(x - 15.0, 0.0) * 19.0 / 20.0, gain)
    return np.maximum(gain, -24.0)


def film_drc_gains(levels_db: np.ndarray, dialnorm_db: float, *, release_s: float = 1.0) -> np.ndarray:
    """Per-frame gains, dB, of the Film Standard profile over frame levels ``levels_db`` (dBFS): a cut
    follows at once, a release (the gain rising) over ``release_s`` (a one-pole smoother in dB)."""
    static = film_standard_gain_db(np.asarray(levels_db, np.float64) - dialnorm_db)
    out = np.empty_like(static)
    a = 1.0 - math.exp(-SAMPLES_PER_FRAME / 48000.0 / release_s)
    g = 0.0
    for k, target in enumerate(static):
        g = target if target < g else g + a * (target - g)
        out[k] = g
    return out


def with_film_drc(src: str | os.PathLike, dst: str | os.PathLike, *, dialnorm_db: float | None = None) -> Path:
    """``src`` (a file with an AC-3 sound, as FFmpeg writes it) with every AC-3 frame carrying the Film
    Standard profile's gain for its level (:func:`film_drc_gains`), the other packets copied. A frame's
    level is its power over the full-bandwidth channels, dBFS; ``dialnorm_db`` (default: the median level
    of the frames that sound, where a film's dialogue and bed sit) is what the profile's levels are
    against."""
    dst = Path(dst)
    with av.open(str(src)) as c:
        a = c.streams.audio[0]
        if a.codec_context.name != "ac3":
            raise ParameterError(f"{src}: the sound is {a.codec_context.name}, not AC-3")
        index = a.index  # a closed container's streams read nonsense
        levels = []
        for frame in c.decode(a):
            lfe = [i for i, ch in enumerate(frame.layout.channels) if ch.name == "LFE"]
            x = np.delete(frame.to_ndarray().astype(np.float64), lfe, axis=0)
            levels.append(10.0 * math.log10(float((x ** 2).sum(axis=0).mean()) + 1e-12))
    levels = np.asarray(levels)
    if dialnorm_db is None:
        sounding = levels[levels > -70.0]
        dialnorm_db = float(np.median(sounding)) if sounding.size else -31.0
    gains = film_drc_gains(levels, dialnorm_db)
    with av.open(str(src)) as c, av.open(str(dst), "w") as out:
        streams = {s.index: out.add_stream_from_template(s) for s in c.streams if s.type in ("video", "audio")}
        k = 0
        for packet in c.demux(*[s for s in c.streams if s.index in streams]):
            if packet.size == 0:  # the demuxer's end of stream
                continue
            target = streams[packet.stream.index]
            if packet.stream.index == index and bytes(packet)[:2] == b"\x0b\x77":
                patched = av.Packet(with_drc(bytes(packet), drc_code(gains[min(k, gains.size - 1)])))
                patched.pts, patched.dts, patched.time_base = packet.pts, packet.dts, packet.time_base
                patched.duration = packet.duration
                packet, k = patched, k + 1
            packet.stream = target
            out.mux(packet)
    return dst
