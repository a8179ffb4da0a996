"""Which audio streams of a file are the film's sound: the stream picked among several (a commentary, an
audio description, a compatibility stereo track beside the mix) and a master's mono tracks read as the
channels of one mix. :func:`~autohaptics.media.probe.probe` asks; stages never do.
"""

from __future__ import annotations

import av

# Dispositions of a track that is not the film's own sound: a commentary, an audio description for the
# blind, a track for the hard of hearing, a karaoke or lyrics version.
_ASIDE = ("comment", "visual_impaired", "hearing_impaired", "descriptions", "karaoke", "lyrics")
# Words in a track's title that set it aside where the container does not flag it (rips seldom do).
_ASIDE_TITLES = ("comment", "kommentar", "description", "descriptive")


def sound_stream(c, among: set[int] | None = None):
    """The audio stream the film's sound is read from, None when no audio stream can be decoded.

    Of the decodable streams (in a transport stream of several programmes, those whose index is in ``among``:
    the programme read, :mod:`~autohaptics.media.programs`) that declare a sample rate and channels (all
    decodable ones when none does), those not set aside (flagged, or titled, as a commentary, an audio
    description, a karaoke or lyrics track, or for the hard of hearing; all of them when every one is); of
    those, the one with the most channels (a master's mono tracks counted as the mix they make,
    :func:`channel_tracks`), then the one flagged as the default, then the first. The most channels is what
    FFmpeg's own command line takes: a compatibility stereo track ahead of the 5.1 mix (HandBrake's and iTunes'
    files) gives way to the mix, whose LFE channel the booming and low-frequency features read."""
    decodable = [s for s in c.streams.audio if s.codec_context is not None and (among is None or s.index in among)]
    usable = [s for s in decodable if s.codec_context.sample_rate and s.codec_context.layout.nb_channels] or decodable
    if not usable:
        return None
    main = [s for s in usable if not _aside(s)] or usable
    return min(main, key=lambda s: (-_channels(c, s), not _flagged(s, ("default",)), s.index))


def _aside(s) -> bool:
    title = str(s.metadata.get("title", "")).lower()
    return _flagged(s, _ASIDE) or any(word in title for word in _ASIDE_TITLES)


def _flagged(s, names) -> bool:
    disposition = getattr(s, "disposition", None)
    try:
        return disposition is not None and any(int(disposition) & int(getattr(av.stream.Disposition, n))
                                               for n in names)
    except (AttributeError, TypeError, ValueError):
        return False


def _channels(c, s) -> int:
    n = int(s.codec_context.layout.nb_channels)
    return len(channel_tracks(c, s)[0]) if n == 1 else n


# Containers whose unlabelled mono tracks are the channels of one mix (broadcast MXF and GXF carry
# each AES3 channel as a track); elsewhere such tracks are versions of the sound (languages, commentary).
_CHANNEL_PER_TRACK = ("mxf", "gxf")
# FFmpeg's names of a channel without a role (an unlabelled layout's channels)
NO_ROLE = ("NONE", "NA", "UNKNOWN", "UNUSED")
# Labels of a stereo downmix (Lt/Rt) beside the discrete channels it is made from.
_DOWNMIX_LABELS = ("DL", "DR")


def channel_tracks(c, first) -> tuple[list[int], str]:
    """The stream indices read as one sound, starting with ``first`` (:func:`sound_stream`), and
    FFmpeg's name of their layout.

    A master often keeps each channel of its mix in a mono track of its own (QuickTime from an
    editing suite, MXF from a broadcast deck). When ``first`` is mono, every later decodable mono
    track at its sample rate and in its language joins it as a channel. QuickTime labels such tracks
    (FL, FR, FC, LFE, ...): then each role is read from its first track, a repeated role being another
    mix, and an Lt/Rt pair (DL, DR) beside discrete channels is left out as their downmix; a plain
    mono track among labelled ones is the centre. Unlabelled tracks are channels only in MXF and GXF
    (:data:`_CHANNEL_PER_TRACK`): one sound of that many unlabelled channels (``media.audio`` reads 6
    or 8 in FFmpeg's 5.1 / 7.1 order, others as their equal mean). Anything else is ``first`` alone.
    """
    layout = first.codec_context.layout
    if layout.nb_channels != 1:
        return [first.index], str(layout.name)
    rate, lang = first.codec_context.sample_rate, first.metadata.get("language")
    same = [s for s in c.streams.audio if s.index >= first.index and s.codec_context is not None
            and s.codec_context.layout.nb_channels == 1 and s.codec_context.sample_rate == rate
            and s.metadata.get("language") == lang]
    labels = [_track_label(s) for s in same]
    if not any(labels):
        if c.format.name not in _CHANNEL_PER_TRACK or len(same) == 1:
            return [first.index], str(layout.name)
        return [s.index for s in same], f"{len(same)} channels"
    discrete = any(lab not in _DOWNMIX_LABELS for lab in labels)
    kept: dict[str, int] = {}
    for s, lab in zip(same, labels):
        role = lab or "FC"
        if role not in kept and not (discrete and role in _DOWNMIX_LABELS):
            kept[role] = s.index
    try:  # FFmpeg's channel order, which the tracks follow
        merged = av.AudioLayout("+".join(kept))
        return [kept[str(ch.name).upper()] for ch in merged.channels], str(merged.name)
    except (ValueError, KeyError, av.error.FFmpegError):  # labels FFmpeg cannot join into one layout
        return [first.index], str(layout.name)


def _track_label(s) -> str:
    """A mono track's channel role from the container ("FL", "LFE", ...); "" when it has none
    (FFmpeg reads an unlabelled QuickTime track as plain mono, an MXF or Matroska one as NONE)."""
    layout = s.codec_context.layout
    name = str(layout.channels[0].name or "").upper() if layout.channels else ""
    return "" if layout.name == "mono" or not name or name in NO_ROLE else name


