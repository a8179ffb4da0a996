"""``server.uploads.container_suffix``: a stored film's suffix and Content-Type come from what the probe
found in it, never from the client's name."""

from __future__ import annotations

import pytest

from autohaptics import testing as synth
from autohaptics.media import probe
from autohaptics.server.uploads import container_suffix
from autohaptics.testing.broadcast import as_recording
from autohaptics.testing.scenes import material_scene


@pytest.mark.parametrize("suffix, expected", [(".mp4", (".mp4", "video/mp4")), (".mkv", (".mkv", "video/x-matroska")),
                                              (".webm", (".webm", "video/webm")), (".avi", (".avi", "video/x-msvideo")),
                                              (".ts", (".ts", "video/mp2t"))])
def test_the_suffix_is_the_containers(tmp_path, suffix, expected):
    src = synth.write_scene(tmp_path / "film.mp4", material_scene(2.0), width=64, height=36, fps=25, quality="low")
    path = as_recording(src, tmp_path / "named.mp4") if suffix == ".ts" else src
    if suffix not in (".mp4", ".ts"):
        path = synth.write_scene(tmp_path / f"film{suffix}", material_scene(2.0), width=64, height=36, fps=25,
                                 quality="low")
    assert container_suffix(probe(path)) == expected
