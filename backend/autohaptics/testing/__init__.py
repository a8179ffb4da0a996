"""Synthetic scenes with known answers, for tests, benchmarks and the editor's sample clip:
:mod:`.scenes` (what a clip shows and sounds like), :mod:`.render` (its pictures and sound) and
:mod:`.encode` (a real media file of it, written with FFmpeg)."""

from autohaptics.testing.encode import CONTAINERS, STANDARD_LAYOUTS, sample_clip, write_scene
from autohaptics.testing.render import iter_frames, render_audio, render_frame
from autohaptics.testing.scenes import (Noise, Scene, Segment, Shape, Texture, Tone, left_boom_right_hum_scene,
                                        sample_scene, three_motions_scene)

__all__ = ["CONTAINERS", "STANDARD_LAYOUTS", "Noise", "Scene", "Segment", "Shape", "Texture", "Tone", "iter_frames",
           "left_boom_right_hum_scene", "render_audio", "render_frame", "sample_clip", "sample_scene",
           "three_motions_scene", "write_scene"]
