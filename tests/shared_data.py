"""Where the shared data lives (../shared next to the repository, or $AUTOHAPTICS_SHARED).

Import from here, not from ``conftest`` (two conftest modules exist, tests/ and tests/browser/, and
``import conftest`` would get whichever pytest loaded first). Tests that need shared data skip
with a message saying where it comes from when it is absent.
"""

from __future__ import annotations

import os
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[1]
SHARED = Path(os.environ.get("AUTOHAPTICS_SHARED", REPO.parent / "shared")).resolve()
MEDIA = SHARED / "media"
PSYCHO = SHARED / "reference" / "psychoacoustics"
SHARED_CLIPS = sorted(p.name for p in MEDIA.glob("*") if p.suffix in (".mp4", ".webm", ".mkv")) if MEDIA.is_dir() else []


def need(path: Path, what: str) -> Path:
    """``path`` if it exists; otherwise skip the test with the reason."""
    if not path.exists():
        pytest.skip(f"{what} not found at {path}: it comes from the project's shared folder "
                    "(../shared next to the repository, or set AUTOHAPTICS_SHARED)")
    return path


def shared_clip(name: str) -> Path:
    """Path of a clip in ../shared/media, skipping the test when it is absent."""
    return need(MEDIA / name, f"shared clip {name}")
