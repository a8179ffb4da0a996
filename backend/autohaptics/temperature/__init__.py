"""Stage 3, colour -> temperature (ALGORITHM.md section 4, thesis 5.2).

:mod:`.colour` (the frame's colour measures: mean RGB, CIELAB, warm-cool), :mod:`.warmcool` (the
default mapping around a skin-neutral temperature), :mod:`.mapping` (the parameters, the thesis's
red/green rule, the track) and :mod:`.device` (the device profile: its safe range, neutral point and
rate, and the curve a chair plays).
"""

from autohaptics.temperature.colour import cielab, mean_colour, warmth
from autohaptics.temperature.device import DeviceProfile, clamp_to_device, played_curve, profile_of, slew_limit
from autohaptics.temperature.mapping import (MAPPINGS, ThermalParams, temperature_target, temperature_track,
                                             warmth_ratio)
from autohaptics.temperature.warmcool import film_scales, warmcool_target

__all__ = ["MAPPINGS", "DeviceProfile", "ThermalParams", "cielab", "clamp_to_device", "film_scales", "mean_colour",
           "played_curve", "profile_of", "slew_limit", "temperature_target", "temperature_track", "warmcool_target", "warmth",
           "warmth_ratio"]
