"""Native export: the timeline file itself (format "autohaptics.timeline", version 1).

Lossless for everything the format holds (tracks and features to 4 decimals, source, generator,
layout, stats and any extra top-level keys such as ``edits``/``markers``).
"""

from __future__ import annotations

from typing import IO

from autohaptics.timeline import Timeline


def write_json(tl: Timeline, fh: IO[str]) -> None:
    """Write ``tl`` as its own JSON document to the text stream ``fh`` (streamed tick by tick)."""
    tl.write(fh)
