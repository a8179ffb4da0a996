"""The whole pipeline for one file: analyse, then derive."""

from __future__ import annotations

import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

from autohaptics.params import DEFAULT_PRESET, GenerateParams
from autohaptics.pipeline.analyse import analyse
from autohaptics.pipeline.derive import derive
from autohaptics.progress import CancelToken, ProgressFn
from autohaptics.timeline import Timeline


def generate(path: str | Path, params: GenerateParams | None = None, *, preset: str = DEFAULT_PRESET,
             progress: ProgressFn | None = None, cancel: CancelToken | None = None,
             between_passes: Callable[[], Any] | None = None, style: Any = None) -> Timeline:
    """Analyse a media file and derive its timeline (in ``style``, an :class:`autohaptics.style.Style`,
    when given); ``stats["total_seconds"]`` is the whole run."""
    params = params or GenerateParams()
    t0 = time.perf_counter()
    analysis = analyse(path, params, progress=progress, cancel=cancel, between_passes=between_passes)
    tl = derive(analysis, params, preset=preset, style=style)
    tl.stats["total_seconds"] = time.perf_counter() - t0
    return tl
