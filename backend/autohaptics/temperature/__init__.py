"""Stage 3, colour -> temperature (ALGORITHM.md section 4, thesis 5.2).

:mod:`.colour` (the frame's colour measure), :mod:`.mapping` (colour -> target temperature) and
:mod:`.device` (the safe range and the rate a heater can follow).
"""

from autohaptics.temperature.colour import mean_colour
from autohaptics.temperature.device import clamp_to_device, slew_limit
from autohaptics.temperature.mapping import ThermalParams, temperature_target, temperature_track, warmth_ratio

__all__ = ["ThermalParams", "clamp_to_device", "mean_colour", "slew_limit", "temperature_target", "temperature_track",
           "warmth_ratio"]
