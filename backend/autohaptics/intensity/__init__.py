"""Stage 1, audio -> vibration intensity (ALGORITHM.md section 2, thesis 3.1.1).

The four psychoacoustic features per 20 ms frame (:mod:`.features`, computed by :mod:`.loudness`,
:mod:`.sharpness`, :mod:`.booming` and :mod:`.low_energy`), then the rule that turns them into a
per-tick intensity in 0..1 (:mod:`.rule`: the default "events" rule judges each feature against its
recent baseline, :mod:`.novelty`; the "thesis" rule against the film's maximum).
"""

from autohaptics.intensity.features import AudioFeatureParams, AudioFeatures, compute_audio_features
from autohaptics.intensity.rule import (
    APPLIED_AFTER_CURVES,
    DEFAULT_THRESHOLDS,
    FEATURES,
    NORMALISERS,
    RULES,
    IntensityParams,
    audio_intensity,
    decision_inputs,
    frame_intensity,
    normalise,
    normalise_features,
    tick_intensity,
)

__all__ = ["APPLIED_AFTER_CURVES", "AudioFeatureParams", "AudioFeatures", "DEFAULT_THRESHOLDS", "FEATURES",
           "IntensityParams", "NORMALISERS", "RULES", "audio_intensity", "compute_audio_features", "decision_inputs",
           "frame_intensity", "normalise", "normalise_features", "tick_intensity"]
