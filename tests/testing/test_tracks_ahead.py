"""``testing.tracks``: a film whose mix comes last of three sound tracks (a commentary, flagged and titled;
a compatibility stereo, the default; the mix, copied), from which ``media.tracks.sound_stream`` reads the
mix, the same sound as the film's own file."""

from __future__ import annotations

import av
import numpy as np

from autohaptics.media import probe, read_audio
from autohaptics.testing import write_scene
from autohaptics.testing.scenes import material_scene
from autohaptics.testing.tracks import with_tracks_ahead


def test_the_mix_is_read_from_behind_a_commentary_and_a_compatibility_track(tmp_path):
    src = write_scene(tmp_path / "film.mkv", material_scene(4.0), width=160, height=90, fps=25, channels=6)
    path = with_tracks_ahead(src, tmp_path / "tracks.mkv")
    with av.open(str(path)) as c:
        audio = c.streams.audio
        assert [s.codec_context.channels for s in audio] == [2, 2, 6]
        assert audio[0].metadata.get("title") == "Director's commentary"
        assert int(audio[0].disposition) & int(av.stream.Disposition.comment)
        assert int(audio[1].disposition) & int(av.stream.Disposition.default)
        mix = audio[2].index
    info = probe(path)
    assert (info.audio.index, info.audio.channels) == (mix, 6)
    np.testing.assert_allclose(read_audio(path, info=info), read_audio(src), atol=1e-6)
