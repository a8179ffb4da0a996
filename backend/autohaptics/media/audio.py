"""Decoding the audio stream into the analysis signal: float32 mono chunks at 48 kHz in digital
full scale (calibration to pascal is the loudness stage's parameter); memory stays constant in the
length of the film.

Downmix (ALGORITHM.md section 2): mono is the MEAN of the two channels of the stereo downmix that
FFmpeg makes by default (ITU-R BS.775: centre and surrounds at -3 dB), plus the LFE channel at its
cinema gain of +10 dB over one of the n main channels: weights front L/R 1/2, centre 1/sqrt(2), back
centre 1/2, surrounds (sides, backs, any other role) 1/(2 sqrt(2)) (:data:`DOWNMIX_WEIGHTS`), LFE
``10**(lfe_gain_db/20) / n_main``. Why: a film's stereo version and every screener made with FFmpeg
are that downmix, so a 5.1 film and its stereo copy read as the same sound at the same level (the
equal mean of the channels read a stereo sound upmixed to 5.1 8 dB quieter). The LFE keeps the
equal mean's share: the stereo downmix leaves it out, and a larger share sets a 5.1 film further from
its stereo copy. Mono and stereo files are the mean of their channels. Channel roles come from the
layout; 6 or 8 unlabelled channels are read in FFmpeg's default 5.1 / 7.1 order; any other unlabelled
layout is the equal mean of its channels, no LFE. Non-finite samples are replaced by 0 and counted.
"""

from __future__ import annotations

import os
from collections.abc import Iterator

import av
import numpy as np

from autohaptics.errors import MediaError
from autohaptics.media.mix import Mix, Sink
from autohaptics.media.probe import (AudioReport, MediaInfo, decode_tolerant, open_container, probe,
                                     stream_by_index)
from autohaptics.media.tracks import NO_ROLE
from autohaptics.timebase import ANALYSIS_SAMPLE_RATE


def iter_audio(path: str | os.PathLike, *, info: MediaInfo | None = None, lfe_gain_db: float = 10.0,
               chunk_s: float = 2.0, report: AudioReport | None = None) -> Iterator[np.ndarray]:
    """Decode the sound :func:`probe` chose (``info.audio``: the first audio stream FFmpeg can decode,
    with the mono tracks that hold the other channels of its mix, :func:`~autohaptics.media.tracks.channel_tracks`)
    as float32 mono chunks at 48 kHz (digital full scale).

    Time 0 is the container start (``info.start_s``): gaps in the stream's timestamps are
    zero-filled and overlaps dropped so audio stays aligned with the picture, where the next frame's
    time confirms them (:class:`AudioClock`). ``chunk_s`` bounds the chunk length (seconds); memory is
    constant in the film length. Raises MediaError when there is no audio stream or nothing
    decodes; a decode error in the middle of a file is counted in ``report`` and skipped.
    """
    info = info or probe(path)
    if info.audio is None:
        raise MediaError(f"{info.path}: no audio stream")
    report = report if report is not None else AudioReport()
    sr_in = info.audio.sample_rate
    out = _Chunks(max(1, int(chunk_s * ANALYSIS_SAMPLE_RATE)), report, sr_in)
    lfe_gain = 10.0 ** (lfe_gain_db / 20.0)
    with open_container(info.path) as c:
        streams = [stream_by_index(c, i) for i in info.audio.streams]
        start_s = info.start_s + unmarked_priming_s(c, streams[0])
        mix = None
        if len(streams) == 1:
            tracks = {streams[0].index: _Track(streams[0], start_s, sr_in, out, report)}
        else:  # the channels of one mix in mono tracks: each weighted by its role, then summed
            weights = _mapping(report, av.AudioLayout(info.audio.layout), len(streams), lfe_gain)
            mix = Mix(len(streams), sr_in, out)
            tracks = {s.index: _Track(s, start_s, sr_in, mix.lane(k), report, weights[k:k + 1])
                      for k, s in enumerate(streams)}
        for index, frame in decode_tolerant(c, streams, report, info.path, tagged=True, clock=info.clock):
            if tracks[index].add(frame, lfe_gain):
                yield from out.drain(False)
        for track in tracks.values():
            track.close()
        if mix is not None:
            mix.close()
        yield from out.finish()
    if report.samples_out == 0:
        reason = f" ({report.first_error})" if report.first_error else ""
        raise MediaError(f"{info.path}: the audio stream holds no decodable samples{reason}")


def _mapping(report: AudioReport, layout, n: int, lfe_gain: float) -> np.ndarray:
    """The downmix weights of ``n`` channels in ``layout`` (:func:`downmix_weights`), noted in ``report``."""
    report.main_channels, report.lfe_channel = _channel_roles(layout, n)
    weights = downmix_weights(layout, n, lfe_gain)
    report.downmix_weights = [round(float(w), 6) for w in weights]
    return weights


# Decoders that apply the dynamic range compression a Dolby encoder writes into the stream (DVDs, Blu-rays,
# broadcasts, streaming services): FFmpeg applies all of it unless told not to, a home player's "night
# mode" (loud passages cut, quiet ones raised). The film's own mix is read: none of it applied.
_NO_DRC = {"ac3": {"drc_scale": "0"}, "ac3_fixed": {"drc_scale": "0"}, "eac3": {"drc_scale": "0"}}


class _Track:
    """One audio stream's frames placed on the container's clock (:class:`AudioClock`) and downmixed
    into ``sink``, with ``weights`` or, when None, the weights of each frame's layout (a channel's sound
    changes layout where a programme does: stereo advertisements, then a film in 5.1), each frame at the
    stream's first ``rate`` (an inserted sound keeps its own rate: resampled from it)."""

    def __init__(self, stream, start_s: float, rate: int, sink: Sink, report: AudioReport,
                 weights: np.ndarray | None = None):
        stream.thread_type = "AUTO"
        options = _NO_DRC.get(stream.codec_context.name)
        if options:
            stream.codec_context.options = {**stream.codec_context.options, **options}
        self.clock = AudioClock(start_s, rate, timestamp_slack_s(stream.time_base, rate))
        self.sink, self.report, self.limit = sink, report, max(1, int(_DOWNMIX_S * rate))
        self.held = None if weights is None else _Held(self.limit, weights, report)
        self.layout = None if weights is None else ()  # the layout the weights are of; () fixed weights
        self.interleave = _Interleaver()
        self.to_rate = _Interleaver(rate)
        self.pending = None  # (time, samples) of the frame placed when the next one's time is known

    def add(self, frame: av.AudioFrame, lfe_gain: float) -> bool:
        """Take one decoded frame; True when the output may hold chunks ready."""
        frame_time = frame.time  # before _samples: interleaving clears the frame's pts
        if frame.sample_rate != self.clock.rate:
            frame = self.to_rate(frame)
        else:
            self.to_rate.key = None  # a later change of rate starts without this one's held samples
        x = _samples(frame, self.interleave)
        layout = (frame.layout.name, x.shape[0])
        if self.held is None:
            self.held, self.layout = _Held(self.limit, _mapping(self.report, frame.layout, x.shape[0], lfe_gain),
                                           self.report), layout
        ready = self.pending is not None and _place(self.clock, *self.pending, frame_time, self.held, self.sink)
        if self.layout != () and layout != self.layout:  # this frame on: the weights of its layout
            self.held.reweigh(_mapping(self.report, frame.layout, x.shape[0], lfe_gain))
            self.layout = layout
        self.pending = (frame_time, x)
        return ready

    def close(self) -> None:
        """Place the last frame and downmix what is held."""
        if self.pending is not None:
            _place(self.clock, *self.pending, None, self.held, self.sink)
        if self.held is not None:
            self.sink.emit(self.held.downmix())


# AAC-LC encoders start with at least this many samples of priming (FFmpeg's and most others: 1024;
# some 2048-2112). MP4 and Matroska mark it and FFmpeg's decoder leaves it out; a raw ADTS stream has
# no field for it, and it decodes as near-silence with the sound's faint pre-echo (128 ms at 8 kHz).
ADTS_PRIMING_SAMPLES = 1024


def unmarked_priming_s(container, stream) -> float:
    """The encoder's priming that ``stream`` decodes but no container field marks, s: the first
    ``ADTS_PRIMING_SAMPLES`` of AAC in a raw ADTS file (format "aac"), else 0. Time 0 of the
    analysis is where it ends, as for the same sound in MP4."""
    if container.format.name == "aac" and stream.codec_context.name == "aac" and stream.sample_rate:
        return ADTS_PRIMING_SAMPLES / float(stream.sample_rate)
    return 0.0


def timestamp_slack_s(time_base, sample_rate: int) -> float:
    """How far a decoded audio frame's time may lie from the end of the samples before it and still
    be the same instant, s: one tick of the stream's ``time_base`` (a frame's time is rounded to it,
    and so was the first frame's the samples count from) plus two samples. Matroska and WebM count
    in milliseconds: a 44.1 kHz frame of 1024 samples (23.22 ms) reads 0.2-0.8 ms off its place,
    which is no gap to fill with silence and no overlap to cut."""
    tick = float(time_base) if time_base else 0.0
    return tick + 2.0 / float(sample_rate)


class AudioClock:
    """Where the analysis signal has reached on the container's clock, s (``next_s``; 0 = ``start_s``),
    and whether a frame lies off it. A frame's time more than ``slack`` s (:func:`timestamp_slack_s`)
    from where the samples before it end is a gap (silence) or an overlap (cut) only when the frame
    after it lies off the same way: Vorbis stamps the frame at a block-size switch up to 10 ms off
    and the next one on its place again, the sound itself running on without a break."""

    def __init__(self, start_s: float, rate: int, slack: float):
        self.start_s, self.rate, self.slack = start_s, rate, slack
        self.next_s = 0.0

    def offset(self, t: float | None, n: int, t_next: float | None) -> int:
        """Samples of silence (> 0) to put before a frame of ``n`` samples at time ``t``, or to cut
        from its start (< 0), given the next frame's time ``t_next`` (None: unknown); advances."""
        shift = 0
        if t is not None:
            gap = t - self.start_s - self.next_s
            after = None if t_next is None else t_next - self.start_s - (self.next_s + n / self.rate)
            if abs(gap) > self.slack and after is not None and abs(after) > self.slack and (gap > 0) == (after > 0):
                shift = max(-n, int(round(gap * self.rate)))
        self.next_s += (max(shift, 0) + n + min(shift, 0)) / self.rate
        return shift


def _place(clock: AudioClock, t: float | None, x: np.ndarray, t_next: float | None, held: "_Held",
           out: Sink) -> bool:
    """Add one decoded frame's samples at their place (``clock``); True when ``out`` has chunks ready."""
    shift = clock.offset(t, x.shape[1], t_next)
    if shift > 0:
        out.emit(held.downmix())
        out.emit(np.zeros(shift, np.float32))
    elif shift < 0:
        x = x[:, -shift:]
    if held.add(x):
        out.emit(held.downmix())
        return True
    return False


# Decoded frames are downmixed together, up to this many seconds at a time: an AAC frame holds
# 21 ms, and the per-call cost of the conversions outweighs their work on so few samples.
_DOWNMIX_S = 0.25


class _Held:
    """Decoded samples waiting for the downmix: [shape=(channels, n)] arrays, downmixed together
    per run of one sample format and channel count."""

    def __init__(self, limit: int, weights: np.ndarray, report: AudioReport):
        self.limit, self.weights, self.report = limit, weights, report
        self.parts: list[np.ndarray] = []
        self.mono: list[np.ndarray] = []  # runs already downmixed (the format changed after them)
        self.n = 0

    def add(self, x: np.ndarray) -> bool:
        """Hold ``x``; True once the held samples should be downmixed."""
        if self.parts and (x.dtype, x.shape[0]) != (self.parts[0].dtype, self.parts[0].shape[0]):
            self.mono.append(self._run())
        self.parts.append(x)
        self.n += x.shape[1]
        return self.n >= self.limit

    def reweigh(self, weights: np.ndarray) -> None:
        """Downmix the samples added from now on with ``weights`` (those held keep theirs)."""
        if self.parts:
            self.mono.append(self._run())
        self.weights = weights

    def _run(self) -> np.ndarray:
        x = self.parts[0] if len(self.parts) == 1 else np.concatenate(self.parts, axis=1)
        self.parts = []
        return _downmix(x if x.dtype.kind == "f" else _to_float(x), self.weights, self.report)

    def downmix(self) -> np.ndarray:
        """The mono signal of every held sample, in order (empty when none are held)."""
        out = self.mono + ([self._run()] if self.parts else [])
        self.mono, self.n = [], 0
        return np.concatenate(out) if len(out) > 1 else (out[0] if out else np.zeros(0, np.float32))


def _downmix(x: np.ndarray, weights: np.ndarray, report: AudioReport) -> np.ndarray:
    """The mono analysis signal of float samples [shape=(channels, n)] in digital full scale:
    ``weights`` [shape=(channels,)] (:func:`downmix_weights`) times the channels, summed in float64;
    non-finite samples become 0 and are counted in ``report``."""
    bad = ~np.isfinite(x)
    if bad.any():
        report.nonfinite_samples += int(bad.sum())
        x = np.where(bad, 0.0, x)
    used = np.flatnonzero(weights)
    return (weights[used] @ x[used].astype(np.float64)).astype(np.float32)


class _Chunks:
    """Mono samples at the input rate in, chunks of ``chunk_n`` samples at 48 kHz out."""

    def __init__(self, chunk_n: int, report: AudioReport, sr_in: int):
        self.chunk_n, self.report, self.sr_in = chunk_n, report, sr_in
        self.pending: list[np.ndarray] = []
        self.pending_n = 0
        self.resampler = None
        if sr_in != ANALYSIS_SAMPLE_RATE:
            self.resampler = av.AudioResampler(format="flt", layout="mono", rate=ANALYSIS_SAMPLE_RATE)

    def emit(self, mono: np.ndarray) -> None:
        if self.resampler is not None and mono.size:
            frame = av.AudioFrame.from_ndarray(mono[None, :], format="flt", layout="mono")
            frame.sample_rate = self.sr_in
            mono = _frames_to_array(self.resampler.resample(frame))
        self._add(mono)

    def _add(self, x: np.ndarray) -> None:
        if x.size:
            self.pending.append(x)
            self.pending_n += x.size

    def drain(self, final: bool) -> Iterator[np.ndarray]:
        while self.pending_n >= self.chunk_n or (final and self.pending_n):
            buf = np.concatenate(self.pending) if len(self.pending) > 1 else self.pending[0]
            out, rest = buf[:self.chunk_n], buf[self.chunk_n:]
            self.pending = [rest] if rest.size else []
            self.pending_n = rest.size
            self.report.samples_out += out.size
            yield out.astype(np.float32, copy=False)

    def finish(self) -> Iterator[np.ndarray]:
        if self.resampler is not None:
            self._add(_frames_to_array(self.resampler.resample(None)))
        yield from self.drain(True)


def read_audio(path: str | os.PathLike, **kwargs) -> np.ndarray:
    """The whole mono 48 kHz track as one float32 array (tests and short clips only)."""
    chunks = list(iter_audio(path, **kwargs))
    return np.concatenate(chunks) if chunks else np.zeros(0, np.float32)


_SAMPLE_DTYPES = {"u8": np.uint8, "s16": np.int16, "s32": np.int32, "s64": np.int64, "flt": np.float32,
                  "dbl": np.float64}


_PACKABLE_LAYOUTS = {"3.0", "quad", "4.0", "5.0", "5.1", "5.0(side)", "5.1(side)", "6.0", "6.1", "7.0", "7.1",
                     "7.1(wide)", "7.1(wide-side)", "octagonal", "hexagonal"}


class _Interleaver:
    """-> packed float in the same layout, through one libswresample context per layout and rate:
    at the frame's own rate (``rate`` None; same-rate format conversion holds no samples back), or
    resampled to ``rate`` (its filter holds back a few samples, which the clock takes for a gap)."""

    def __init__(self, rate: int | None = None):
        self.rate = rate
        self.key = None
        self.resampler = None

    def __call__(self, frame: av.AudioFrame) -> av.AudioFrame:
        key = (frame.layout.name, frame.sample_rate)
        rate = self.rate or frame.sample_rate
        if key != self.key:
            self.key = key
            self.resampler = av.AudioResampler(format="flt", layout=frame.layout.name, rate=rate)
        frame.pts = None
        return _join_packed(self.resampler.resample(frame), frame, rate)


def _join_packed(out: list, frame: av.AudioFrame, rate: int) -> av.AudioFrame:
    if len(out) == 1:
        return out[0]
    if not out:
        packed = av.AudioFrame(format="flt", layout=frame.layout.name, samples=0)
        packed.sample_rate = rate
        return packed
    data = np.concatenate([np.frombuffer(f.planes[0], np.float32, count=f.samples * f.layout.nb_channels)
                           for f in out])
    packed = av.AudioFrame.from_ndarray(data.reshape(1, -1), format="flt", layout=frame.layout.name)
    packed.sample_rate = rate
    return packed


def _samples(frame: av.AudioFrame, interleave: "_Interleaver | None" = None) -> np.ndarray:
    """Decoded samples as [shape=(channels, n)], read straight from the frame's planes.

    (PyAV's ``to_ndarray`` crashes the interpreter on 8-channel planar frames; the planes'
    buffers are read here with numpy instead.)
    """
    if frame.format.is_planar and frame.layout.nb_channels > 2 and frame.layout.name in _PACKABLE_LAYOUTS:
        # Many-channel planar frames: PyAV's plane accessors read past AVFrame.data (8 pointers)
        # for such layouts; let libswresample interleave them first (same rate, same layout).
        frame = (interleave or _Interleaver())(frame)
    name = frame.format.name
    base = name[:-1] if name.endswith("p") else name
    dtype = _SAMPLE_DTYPES.get(base)
    nch = frame.layout.nb_channels
    n = frame.samples
    if dtype is None:
        raise MediaError(f"unsupported audio sample format {name!r}")
    if frame.format.is_planar:
        return np.stack([np.frombuffer(frame.planes[i], dtype=dtype, count=n) for i in range(nch)])
    return np.frombuffer(frame.planes[0], dtype=dtype, count=n * nch).reshape(n, nch).T


def _to_float(x: np.ndarray) -> np.ndarray:
    """Decoded samples (any sample format) -> float64 in digital full scale."""
    if x.dtype.kind == "f":
        return x.astype(np.float64, copy=False)
    if x.dtype == np.uint8:
        return (x.astype(np.float64) - 128.0) / 128.0
    info = np.iinfo(x.dtype)
    return x.astype(np.float64) / float(-info.min)


# FFmpeg channel names for the LFE channel.
_LFE_NAMES = {"LFE", "LFE2", "LOW_FREQUENCY", "LOW_FREQUENCY_2"}
_UNLABELLED = {6: "5.1", 8: "7.1"}  # FFmpeg's default order for so many channels without a layout
# A channel's weight in the mean of FFmpeg's default stereo downmix (module docstring); any other role
# (sides, backs, tops, wides) counts as a surround.
FRONT_WEIGHT = 0.5
DOWNMIX_WEIGHTS = {"FL": FRONT_WEIGHT, "FR": FRONT_WEIGHT, "FLC": FRONT_WEIGHT, "FRC": FRONT_WEIGHT,
                   "FC": 0.5 ** 0.5, "BC": 0.5}
SURROUND_WEIGHT = 0.5 ** 1.5


def _channel_names(layout, n: int) -> list[str] | None:
    """The role names of a decoded layout's ``n`` channels, upper case; None where any is unknown
    (6 or 8 such channels: FFmpeg's default 5.1 / 7.1 order)."""
    names = [str(ch.name or "").upper() for ch in layout.channels][:n]
    if len(names) == n and all(nm and nm not in NO_ROLE for nm in names):
        return names
    if n in _UNLABELLED:
        return [ch.name.upper() for ch in av.AudioLayout(_UNLABELLED[n]).channels]
    return None


def _channel_roles(layout, n: int) -> tuple[list[int], int | None]:
    """(main channel indices, LFE index or None) for a decoded layout of ``n`` channels."""
    names = _channel_names(layout, n) or [""] * n
    lfe = [i for i, nm in enumerate(names) if nm in _LFE_NAMES]
    lfe_idx = lfe[0] if lfe else None
    main = [i for i in range(n) if i != lfe_idx]
    if not main:  # a lone LFE channel is the whole signal
        return [lfe_idx], None
    return main, lfe_idx


def downmix_weights(layout, n: int, lfe_gain: float) -> np.ndarray:
    """Each of a decoded layout's ``n`` channels' weight in the mono analysis signal (module
    docstring), float64 [shape=(n,)], >= 0. lfe_gain : the LFE's linear gain (10 dB: 3.16)."""
    main, lfe = _channel_roles(layout, n)
    names = _channel_names(layout, n)
    w = np.zeros(n)
    if names is None or len(main) <= 2:  # no roles, mono or stereo: the equal mean
        w[main] = 1.0 / len(main)
    else:
        w[main] = [DOWNMIX_WEIGHTS.get(names[i], SURROUND_WEIGHT) for i in main]
    if lfe is not None:  # the equal mean's share (module docstring)
        w[lfe] = lfe_gain / len(main)
    return w


def _frames_to_array(frames) -> np.ndarray:
    if not frames:
        return np.zeros(0, np.float32)
    parts = [f.to_ndarray().reshape(-1) for f in frames]
    return np.concatenate(parts).astype(np.float32, copy=False)
