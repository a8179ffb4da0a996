"""Shared fixtures. Data from ../shared (real clips, ISO/DIN references) is read in place; tests
that need it skip with a message saying where it comes from when it is absent."""

from __future__ import annotations

import os
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[1]
SHARED = Path(os.environ.get("AUTOHAPTICS_SHARED", REPO.parent / "shared")).resolve()
MEDIA = SHARED / "media"
PSYCHO = SHARED / "reference" / "psychoacoustics"
SHARED_CLIPS = sorted(p.name for p in MEDIA.glob("*") if p.suffix in (".mp4", ".webm", ".mkv")) if MEDIA.is_dir() else []


def _need(path: Path, what: str) -> Path:
    if not path.exists():
        pytest.skip(f"{what} not found at {path}: it comes from the project's shared folder "
                    "(../shared next to the repository, or set AUTOHAPTICS_SHARED)")
    return path


@pytest.fixture(scope="session")
def repo_dir() -> Path:
    return REPO


@pytest.fixture(scope="session")
def media_dir() -> Path:
    return _need(MEDIA, "shared media clips")


@pytest.fixture(scope="session")
def psycho_dir() -> Path:
    return _need(PSYCHO, "ISO 532-1 / DIN 45692 reference data")


def shared_clip(name: str) -> Path:
    """Path of a clip in ../shared/media, skipping the test when it is absent."""
    return _need(MEDIA / name, f"shared clip {name}")
