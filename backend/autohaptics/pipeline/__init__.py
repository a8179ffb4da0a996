"""The pipeline: the stages composed into a timeline, and the one place that decides what to skip.

:func:`analyse` (slow, decodes: the audio pass, then the video pass, :mod:`.video`) -> an
:class:`Analysis`, the feature cache (:mod:`.cache`) -> :func:`derive` (fast, pure: thresholds,
mode, mappings) -> :class:`~autohaptics.timeline.Timeline`. :func:`generate` does both. The editor
re-thresholds with :func:`derive` alone, and :func:`refine` computes the saliency that a lower
threshold's newly vibrating ticks lack.
"""

from autohaptics.pipeline.analyse import analyse, file_sha256
from autohaptics.pipeline.cache import Analysis, reusable
from autohaptics.pipeline.derive import derive
from autohaptics.pipeline.generate import generate
from autohaptics.pipeline.refine import frame_sources, lacking_saliency, refinable, refine
from autohaptics.pipeline.ticks import VideoAnalysis
from autohaptics.pipeline.video import video_pass

__all__ = ["Analysis", "VideoAnalysis", "analyse", "derive", "file_sha256", "frame_sources", "generate", "lacking_saliency", "refinable",
           "refine", "reusable", "video_pass"]
