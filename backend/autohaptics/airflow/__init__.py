"""Stage 4, motion + depth -> the 17 x 9 fan grid (ALGORITHM.md section 5, thesis 5.3).

:mod:`.flow` (optical flow and the static/fade checks), :mod:`.cuts` (shot cuts), :mod:`.depth`
(nearness), :mod:`.pair` (one flow pair's motion and depth, for the video pass) and :mod:`.fans`
(which ticks and cells blow).
"""

from autohaptics.airflow.fans import (
    AirflowParams,
    cell_motion,
    despiked_motion,
    fan_levels,
    fan_track,
    grid_means,
    motion_threshold,
    near_cells,
    smoothed_cell_motion,
    smoothed_motion,
    smoothed_nearness,
    strong_motion,
    sustained_motion,
)
from autohaptics.airflow.flow import (
    DIS_PRESETS,
    FLOW_METHODS,
    FlowParams,
    is_fade,
    is_static,
    motion_magnitude,
    motion_score,
    optical_flow,
)

__all__ = ["AirflowParams", "DIS_PRESETS", "FLOW_METHODS", "FlowParams", "cell_motion", "despiked_motion", "fan_levels", "fan_track",
           "grid_means", "is_fade", "is_static", "motion_magnitude", "motion_score", "motion_threshold", "near_cells",
           "optical_flow",
           "smoothed_cell_motion", "smoothed_motion", "smoothed_nearness", "strong_motion", "sustained_motion"]
