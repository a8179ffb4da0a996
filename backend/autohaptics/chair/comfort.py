"""Per-viewer comfort, the device's safe range, and timeline tick -> wire frame.

Quantisation (what the chair receives for a timeline value; the tests rely on it):

- vibration and fans: ``u8 = floor(clip(v * intensity, 0, 1) * 255 + 0.5)`` (round half up)
- temperature: ``T' = neutral + intensity * (T - neutral)``, then clamped to the device's
  ``[temp_min_c, temp_max_c]``, then ``cC = floor(T' * 100 + 0.5)`` (centi-degrees, int16)
- a muted zone sends 0 for its motors (back, armrests, seat) or fans; muted heat sends the
  device's neutral temperature.

The chair clamps and slew-limits the temperature again on its side (firmware/PROTOCOL.md); what it
then plays (at full intensity, heat not muted) is :func:`autohaptics.temperature.played_curve`
of the timeline's curve.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from autohaptics.chair.protocol import N_FANS, Frame
from autohaptics.errors import ParameterError
from autohaptics.layout import ACTUATORS, ZONES
from autohaptics.temperature.device import DeviceProfile
from autohaptics.timeline import Timeline
from autohaptics.timeline.quantise import to_u8

MUTABLE_ZONES = ZONES + ("heat", "fans")  # back, armrests, seat, heat, fans


@dataclass(frozen=True)
class Comfort:
    """One viewer's comfort settings.

    intensity : float, 0..1, scales vibration, fan levels and the temperature's distance from neutral
    mute      : zones switched off, any of ``MUTABLE_ZONES`` (back, armrests, seat, heat, fans)
    """

    intensity: float = 1.0
    mute: frozenset[str] = field(default_factory=frozenset)

    def __post_init__(self) -> None:
        try:
            value = float(self.intensity)
        except (TypeError, ValueError):
            raise ParameterError(f"comfort intensity must be a number in [0, 1], got {self.intensity!r}") from None
        if not math.isfinite(value) or not 0.0 <= value <= 1.0:
            raise ParameterError(f"comfort intensity must be in [0, 1], got {self.intensity!r}")
        object.__setattr__(self, "intensity", value)
        if isinstance(self.mute, str):
            raise ParameterError(f"comfort mute must be a collection of zone names, got the string {self.mute!r}")
        mute = frozenset(self.mute)
        unknown = sorted(mute - set(MUTABLE_ZONES))
        if unknown:
            raise ParameterError(f"unknown comfort zone(s) {unknown}; zones are {', '.join(MUTABLE_ZONES)}")
        object.__setattr__(self, "mute", mute)

    def to_dict(self) -> dict:
        return {"intensity": self.intensity, "mute": sorted(self.mute)}

    @classmethod
    def from_dict(cls, d: dict) -> "Comfort":
        return cls(intensity=d.get("intensity", 1.0), mute=frozenset(d.get("mute", ())))


_ZONE_OF_MOTOR = tuple(a.zone for a in ACTUATORS)


def temperature_cc(temp_c: float, comfort: Comfort, profile: DeviceProfile) -> int:
    """Temperature target in centi-degrees after comfort scaling, muting and the device clamp."""
    neutral = profile.temp_neutral_c
    if "heat" in comfort.mute:
        t = neutral
    else:
        t = neutral + comfort.intensity * (float(temp_c) - neutral)
    t = min(max(t, profile.temp_min_c), profile.temp_max_c)
    return int(math.floor(t * 100.0 + 0.5))


def compose_frame(timeline: Timeline, tick: int, *, comfort: Comfort, profile: DeviceProfile) -> Frame:
    """The FRAME for ``tick`` of ``timeline`` (seq left at 0; ChairLink numbers frames)."""
    if not 0 <= tick < timeline.n_ticks:
        raise ParameterError(f"tick {tick} is outside the timeline (0..{timeline.n_ticks - 1})")
    vib = np.asarray(timeline.vibration[tick], dtype=np.float64)
    if comfort.mute:
        vib = vib * np.array([0.0 if z in comfort.mute else 1.0 for z in _ZONE_OF_MOTOR])
    motors = to_u8(vib, comfort.intensity).tobytes()
    if "fans" in comfort.mute:
        fans = bytes(N_FANS)
    else:
        fans = to_u8(np.asarray(timeline.fans[tick]).reshape(-1), comfort.intensity).tobytes()
    return Frame(tick=int(tick), motors=motors, temp_cc=temperature_cc(timeline.temperature_c[tick], comfort, profile),
                 fans=fans)
