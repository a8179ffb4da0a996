"""The chair: nine actuators on the normalised frame, the 14 fusion triangles, the fan grid.

Coordinates are on the normalised video frame: x to the right, y downward, both in [0, 1]
(ALGORITHM.md section 3). Zones group actuators for the chair's comfort controls.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class Actuator:
    id: str
    x: float
    y: float
    zone: str  # "back" | "armrests" | "seat"
    body: str


ACTUATORS: tuple[Actuator, ...] = (
    Actuator("A1", 1 / 3, 0.0, "back", "upper back, left"),
    Actuator("A2", 2 / 3, 0.0, "back", "upper back, right"),
    Actuator("A3", 0.0, 0.5, "armrests", "left armrest"),
    Actuator("A4", 0.25, 0.5, "back", "lower back, left"),
    Actuator("A5", 0.5, 0.5, "back", "lower back, centre"),
    Actuator("A6", 0.75, 0.5, "back", "lower back, right"),
    Actuator("A7", 1.0, 0.5, "armrests", "right armrest"),
    Actuator("A8", 1 / 3, 1.0, "seat", "seat, left"),
    Actuator("A9", 2 / 3, 1.0, "seat", "seat, right"),
)
N_ACTUATORS = 9
ACTUATOR_IDS = tuple(a.id for a in ACTUATORS)
ACTUATOR_XY = np.array([[a.x, a.y] for a in ACTUATORS], dtype=np.float64)  # (9, 2)
ZONES = ("back", "armrests", "seat")
ZONE_OF = {a.id: a.zone for a in ACTUATORS}

# The audio-only study condition drives these (thesis table 4.1): A1, A2, A5.
AUDIO_MODE_ACTUATORS = ("A1", "A2", "A5")
CENTRE_ACTUATOR = "A5"  # fallback when nothing is salient (thesis 4.4.3)

# Frame corners: vertices of the triangulation that carry no actuator.
CORNERS = {"C00": (0.0, 0.0), "C10": (1.0, 0.0), "C01": (0.0, 1.0), "C11": (1.0, 1.0)}

# The thesis's 14 triangles (ALGORITHM.md section 3), vertices by name.
TRIANGLES: tuple[tuple[str, str, str], ...] = (
    ("C00", "A1", "A3"), ("A1", "A3", "A4"), ("A1", "A4", "A5"), ("A1", "A5", "A2"),
    ("A2", "A5", "A6"), ("A2", "A6", "A7"), ("A2", "A7", "C10"),
    ("C01", "A8", "A3"), ("A8", "A3", "A4"), ("A8", "A4", "A5"), ("A8", "A5", "A9"),
    ("A9", "A5", "A6"), ("A9", "A6", "A7"), ("A9", "A7", "C11"),
)


def vertex_xy(name: str) -> tuple[float, float]:
    """Normalised (x, y) of a triangle vertex, actuator ("A1".."A9") or corner ("C00".."C11")."""
    if name in CORNERS:
        return CORNERS[name]
    a = ACTUATORS[ACTUATOR_IDS.index(name)]
    return (a.x, a.y)


FAN_ROWS = 9
FAN_COLS = 17

# Temperature: the generator's target curve (thesis 5.2) and the device's safe range.
TEMP_LOW_C = 30.0
TEMP_HIGH_C = 55.0
TEMP_NEUTRAL_C = 33.0  # skin-neutral; what a chair returns to when idle or in safe state
DEVICE_TEMP_MIN_C = 18.0
DEVICE_TEMP_MAX_C = 40.0
DEVICE_TEMP_RATE_C_PER_S = 1.0  # the setpoint's slew limit (firmware AH_TEMP_RATE_CC_PER_S = 100)


def layout_dict() -> dict:
    """The timeline's ``layout`` block (TIMELINE.md)."""
    return {
        "actuators": [
            {"id": a.id, "x": round(a.x, 4), "y": round(a.y, 4), "zone": a.zone, "body": a.body}
            for a in ACTUATORS
        ],
        "fans": {"rows": FAN_ROWS, "cols": FAN_COLS},
    }
