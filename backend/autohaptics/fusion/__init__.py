"""Stage 2, saliency -> the spatial distribution over the nine actuators (ALGORITHM.md section 3).

:mod:`.saliency` (the map: spectral residual, fine-grained or an ONNX network, :mod:`.onnx`),
:mod:`.triangles` (the thesis's triangle weights: map -> beta per actuator) and :mod:`.modes` (the
vibration track of each generation mode).
"""

from autohaptics.fusion.modes import MODES, smoothed_weights, vibration_track
from autohaptics.fusion.saliency import SaliencyParams, make_saliency_backend, saliency_map, working_size
from autohaptics.fusion.triangles import (
    TRIANGLE_ACTUATORS,
    TRIANGLE_XY,
    VARIANTS,
    FusionParams,
    actuator_weights,
    fallback_weights,
    salient_shape,
    triangle_index_map,
    triangle_weights,
)

__all__ = ["MODES", "TRIANGLE_ACTUATORS", "TRIANGLE_XY", "VARIANTS", "FusionParams", "SaliencyParams",
           "actuator_weights", "fallback_weights", "make_saliency_backend", "salient_shape", "saliency_map",
           "smoothed_weights", "triangle_index_map", "triangle_weights", "vibration_track", "working_size"]
