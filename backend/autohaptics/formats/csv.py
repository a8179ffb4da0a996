"""Plain CSV export: one row per 100 ms tick, streamed in blocks of rows.

Columns (164): ``time_s``, ``A1`` .. ``A9``, ``temperature_c``, then the 153 fan cells
``fan_r{row}_c{col}`` in row-major order (row 0 = top, column 0 = left). One header row, every
number with exactly 4 decimals, ``,`` separator, ``\\n`` line ends, UTF-8. No comment or metadata
line (plain CSV readers would take it for data): the timeline's ``source``/``generator``/``layout``
go, when wanted, into a JSON sidecar written by :func:`write_csv_sidecar`.
"""

from __future__ import annotations

import json
from typing import IO

import numpy as np

from autohaptics.formats.common import FAN_NAMES, VALUE_DECIMALS, ensure_valid
from autohaptics.layout import ACTUATOR_IDS, FAN_COLS, FAN_ROWS
from autohaptics.timeline import Timeline, json_default

TIME_COLUMN = "time_s"
TEMPERATURE_COLUMN = "temperature_c"
CSV_COLUMNS: tuple[str, ...] = (TIME_COLUMN, *ACTUATOR_IDS, TEMPERATURE_COLUMN, *FAN_NAMES)
SIDECAR_FORMAT = "autohaptics.timeline.csv-meta"
SIDECAR_VERSION = 1
_BLOCK_ROWS = 512


def write_csv(tl: Timeline, fh: IO[str]) -> None:
    """Write ``tl`` as CSV to the text stream ``fh``, ``_BLOCK_ROWS`` rows per write.

    Memory beyond the timeline itself is one block of formatted rows, so a 2-hour timeline
    (72,000 ticks x 164 columns) streams without building the whole text.
    """
    tl = ensure_valid(tl)
    n = tl.n_ticks
    row_fmt = ",".join([f"%.{VALUE_DECIMALS}f"] * len(CSV_COLUMNS)) + "\n"
    fh.write(",".join(CSV_COLUMNS) + "\n")
    fans = tl.fans.reshape(n, FAN_ROWS * FAN_COLS)
    for start in range(0, n, _BLOCK_ROWS):
        stop = min(n, start + _BLOCK_ROWS)
        block = np.empty((stop - start, len(CSV_COLUMNS)), dtype=np.float64)
        block[:, 0] = np.arange(start, stop, dtype=np.float64) / 10.0
        block[:, 1:10] = tl.vibration[start:stop]
        block[:, 10] = tl.temperature_c[start:stop]
        block[:, 11:] = fans[start:stop]
        # Rounding first keeps float32 noise (0.30000001) from flipping the 4th decimal.
        block = np.round(block, VALUE_DECIMALS) + 0.0  # + 0.0 turns -0.0 into 0.0
        fh.write("".join(row_fmt % tuple(row) for row in block.tolist()))


def sidecar_dict(tl: Timeline) -> dict:
    """The CSV's metadata sidecar: everything of the timeline that is not a per-tick track."""
    return {
        "format": SIDECAR_FORMAT,
        "version": SIDECAR_VERSION,
        "tick_s": tl.tick_s,
        "n_ticks": int(tl.n_ticks),
        "columns": list(CSV_COLUMNS),
        "source": tl.source,
        "generator": tl.generator,
        "layout": tl.layout,
        "stats": tl.stats,
        "extra": tl.extra,
    }


def write_csv_sidecar(tl: Timeline, fh: IO[str]) -> None:
    """Write the sidecar JSON (see :func:`sidecar_dict`) to the text stream ``fh``."""
    tl = ensure_valid(tl)
    json.dump(sidecar_dict(tl), fh, indent=1, default=json_default)
    fh.write("\n")
