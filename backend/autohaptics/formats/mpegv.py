"""MPEG-V (ISO/IEC 23005-3) Sensory Effect Metadata export: a SEM XML document, streamed.

One ``<Effect>`` element per change, never per tick:

- ``sev:VibrationType`` per actuator, ``sev:TemperatureType`` for the temperature element and
  ``sev:WindType`` per fan cell, each with ``si:pts`` in units of the root's ``si:timeScale``
  (1000: milliseconds; a tick is 100).
- A channel that turns on or changes level gets ``activate="true"`` with ``intensity-value`` /
  ``intensity-range``; one that falls to 0 gets ``activate="false"``. The value holds until the
  channel's next effect. Temperature is announced at pts 0 and on every change.
- Vibration and wind: ``intensity-range="0 100"``, ``intensity-value`` = level x 100 with 2
  decimals (the timeline's 4). Temperature: degrees Celsius with 4 decimals,
  ``intensity-range`` = the timeline's temp_low..temp_high.
- ``location`` uses the MPEG-V location classification scheme (coarse: 5 x 3 x 3 positions); the
  exact channel is named by the attribute ``ah:actuator`` ("A1".."A9") or ``ah:fan`` ("r3c4") in
  the namespace ``AH_NS`` (effects allow attributes from other namespaces).
- At the end time n x 100 ms every effect still active is deactivated.
"""

from __future__ import annotations

from typing import IO
from xml.sax.saxutils import escape

import numpy as np

from autohaptics.formats.common import MS_PER_TICK, QUANTUM, ensure_valid, quantise, timeline_title
from autohaptics.layout import ACTUATOR_IDS, FAN_COLS, FAN_ROWS, N_ACTUATORS
from autohaptics.timeline import Timeline

SEDL_NS = "urn:mpeg:mpeg-v:2010:01-SEDL-NS"
SEV_NS = "urn:mpeg:mpeg-v:2010:01-SEV-NS"
SI_NS = "urn:mpeg:mpeg21:2003:01-DIA-XSI-NS"
XSI_NS = "http://www.w3.org/2001/XMLSchema-instance"
AH_NS = "urn:autohaptics:sem:1"
LOCATION_CS = "urn:mpeg:mpeg-v:01-SI-LocationCS-NS"
TIME_SCALE = 1000
LEVEL_RANGE = "0 100"

# Location relative to the seated viewer: x left..right, y bottom/middle/top, z back/midway/front.
ACTUATOR_LOCATION = {
    "A1": "centerleft:top:back", "A2": "centerright:top:back",
    "A3": "left:middle:midway",
    "A4": "centerleft:middle:back", "A5": "center:middle:back", "A6": "centerright:middle:back",
    "A7": "right:middle:midway",
    "A8": "centerleft:bottom:midway", "A9": "centerright:bottom:midway",
}
_X = ("left", "centerleft", "center", "centerright", "right")
_Y = ("top", "middle", "bottom")
_BLOCK_TICKS = 2048
_FLUSH_LINES = 8192


def fan_location(row: int, col: int) -> str:
    """LocationCS term of fan cell (row, col): the 17 x 9 grid folded onto 5 x 3 positions, front."""
    x = _X[min(len(_X) - 1, col * len(_X) // FAN_COLS)]
    y = _Y[min(len(_Y) - 1, row * len(_Y) // FAN_ROWS)]
    return f"{x}:{y}:front"


def write_sem(tl: Timeline, fh: IO[str]) -> None:
    """Write ``tl`` as an MPEG-V SEM document to the text stream ``fh`` (effects only on changes)."""
    tl = ensure_valid(tl)
    n = tl.n_ticks
    lo, hi = tl.temp_range
    n_ch = 1 + N_ACTUATORS + FAN_ROWS * FAN_COLS  # order within a tick: temperature, A1..A9, fans
    on_tpl, off_tpl = _templates(lo, hi)

    title = escape(timeline_title(tl.source)).replace("--", "- -")
    fh.write('<?xml version="1.0" encoding="UTF-8"?>\n')
    fh.write(f"<!-- autohaptics MPEG-V export of {title}: {n} ticks of 100 ms; si:pts in ms -->\n")
    fh.write(f'<SEM xmlns="{SEDL_NS}" xmlns:sev="{SEV_NS}" xmlns:si="{SI_NS}" xmlns:xsi="{XSI_NS}" '
             f'xmlns:ah="{AH_NS}" si:timeScale="{TIME_SCALE}">\n')

    prev = np.zeros(n_ch, dtype=np.int64)  # everything off before the start
    for a in range(0, n, _BLOCK_TICKS):
        b = min(n, a + _BLOCK_TICKS)
        q = np.concatenate([
            quantise(tl.temperature_c[a:b])[:, None],
            quantise(tl.vibration[a:b]),
            quantise(tl.fans[a:b].reshape(b - a, n_ch - 1 - N_ACTUATORS)),
        ], axis=1)
        changed = np.empty(q.shape, dtype=bool)
        changed[0] = q[0] != prev
        changed[1:] = q[1:] != q[:-1]
        if a == 0:
            changed[0, 0] = True  # the temperature is always announced at the start
        prev = q[-1].copy()
        ticks, chans = np.nonzero(changed)
        lines: list[str] = []
        for k, ch, v in zip((ticks + a).tolist(), chans.tolist(), q[ticks, chans].tolist()):
            pts = k * MS_PER_TICK
            if ch == 0:
                lines.append(on_tpl[0] % (_fmt_celsius(v), pts))
            elif v:
                lines.append(on_tpl[ch] % (_fmt_percent(v), pts))
            else:
                lines.append(off_tpl[ch] % pts)
            if len(lines) >= _FLUSH_LINES:
                fh.write("".join(lines))
                lines = []
        fh.write("".join(lines))
    end = n * MS_PER_TICK
    fh.write("".join(off_tpl[ch] % end for ch in range(n_ch) if ch == 0 or prev[ch] != 0))
    fh.write("</SEM>\n")


def _templates(lo: float, hi: float) -> tuple[list[str], list[str]]:
    """Per-channel ``%``-templates of the 'on' (value, pts) and 'off' (pts) effect lines."""
    on = [f'  <Effect xsi:type="sev:TemperatureType" activate="true" intensity-value="%s" '
          f'intensity-range="{lo:.4f} {hi:.4f}" si:pts="%d"/>\n']
    off = ['  <Effect xsi:type="sev:TemperatureType" activate="false" si:pts="%d"/>\n']
    for aid in ACTUATOR_IDS:
        attrs = f'location="{LOCATION_CS}:{ACTUATOR_LOCATION[aid]}" ah:actuator="{aid}"'
        on.append(f'  <Effect xsi:type="sev:VibrationType" activate="true" intensity-value="%s" '
                  f'intensity-range="{LEVEL_RANGE}" {attrs} si:pts="%d"/>\n')
        off.append(f'  <Effect xsi:type="sev:VibrationType" activate="false" {attrs} si:pts="%d"/>\n')
    for r in range(FAN_ROWS):
        for c in range(FAN_COLS):
            attrs = f'location="{LOCATION_CS}:{fan_location(r, c)}" ah:fan="r{r}c{c}"'
            on.append(f'  <Effect xsi:type="sev:WindType" activate="true" intensity-value="%s" '
                      f'intensity-range="{LEVEL_RANGE}" {attrs} si:pts="%d"/>\n')
            off.append(f'  <Effect xsi:type="sev:WindType" activate="false" {attrs} si:pts="%d"/>\n')
    return on, off


def _fmt_percent(q: int) -> str:
    """A level quantised to 1e-4 as a percentage with 2 decimals: 5312 -> '53.12'."""
    whole, frac = divmod(int(q), 100)
    return f"{whole}.{frac:02d}"


def _fmt_celsius(q: int) -> str:
    """A temperature quantised to 1e-4 C with 4 decimals: 330000 -> '33.0000'."""
    q = int(q)
    sign = "-" if q < 0 else ""
    whole, frac = divmod(abs(q), QUANTUM)
    return f"{sign}{whole}.{frac:04d}"
