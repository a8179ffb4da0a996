"""``testing.dolby``: the dynamic range words it writes into AC-3 are the ones FFmpeg's decoder reads
(tests/media/test_dynamic_range.py decodes them), its Film Standard profile is Dolby's, and a file given
the profile's words keeps everything else as it was."""

from __future__ import annotations

import av
import numpy as np
import pytest

from autohaptics.errors import ParameterError
from autohaptics.testing import write_scene
from autohaptics.testing.dolby import (drc_code, drc_gain_db, film_drc_gains, film_standard_gain_db, with_drc,
                                       with_film_drc)
from autohaptics.testing.reencode import reencode
from autohaptics.testing.scenes import material_scene


def test_drc_words_round_trip_within_a_step():
    assert all(drc_code(drc_gain_db(c)) == c for c in range(256))
    for g in np.linspace(-24.0, 23.9, 500):
        assert abs(drc_gain_db(drc_code(g)) - g) < 0.14
    assert drc_code(0.0) == 0 and drc_code(-6.02) == 0xE0 and drc_code(-40.0) == drc_code(-24.0)


def test_the_film_standard_profile():
    """Against the dialogue normalisation: +6 dB boost below -12 dB, 2:1 to 0, null to +5, 2:1 cut to +15,
    20:1 above, at most -24 dB; a cut follows at once, the release takes its time."""
    levels = np.array([-40.0, -12.0, -6.0, 0.0, 3.0, 5.0, 10.0, 15.0, 20.0, 35.0, 60.0])
    np.testing.assert_allclose(film_standard_gain_db(levels), [6, 6, 3, 0, 0, 0, -2.5, -5, -9.75, -24, -24])
    gains = film_drc_gains(np.array([-20.0] * 5 + [0.0] * 3 + [-20.0] * 60), -20.0, release_s=1.0)
    assert gains[4] == 0.0 and gains[5] == pytest.approx(-9.75)  # +20 dB: cut at once
    assert -9.75 < gains[8] < gains[20] < gains[-1] < 0.0  # released: e^-1 of the cut left after a second
    assert gains[7 + 31] == pytest.approx(-9.75 * np.exp(-31 * 1536 / 48000), abs=0.05)


def test_a_file_given_the_profile_keeps_its_picture_and_every_frame_carries_a_word(tmp_path):
    src = write_scene(tmp_path / "scene.mp4", material_scene(6.0), width=160, height=90, fps=25)
    dvd = reencode(src, tmp_path / "dvd.mkv", video_codec="copy", audio_codec="ac3", audio_bit_rate=448_000)
    out = with_film_drc(dvd, tmp_path / "drc.mkv")

    def packets(path, kind):
        with av.open(str(path)) as c:
            return [bytes(p) for p in c.demux(getattr(c.streams, kind)[0]) if p.size]

    assert packets(out, "video") == packets(dvd, "video")
    frames = packets(out, "audio")
    assert len(frames) == len(packets(dvd, "audio")) > 100
    for frame in frames:
        with pytest.raises(ParameterError, match="already"):
            with_drc(frame, 0)
    with pytest.raises(ParameterError, match="not AC-3"):
        with_film_drc(src, tmp_path / "again.mkv")
