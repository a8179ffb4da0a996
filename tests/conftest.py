"""Shared fixtures. Data from ../shared (real clips, ISO/DIN references) is read in place; tests
that need it skip with a message saying where it comes from when it is absent (shared_data.py)."""

from __future__ import annotations

from pathlib import Path

import pytest

from shared_data import MEDIA, PSYCHO, REPO, SHARED, SHARED_CLIPS, need, shared_clip  # noqa: F401


@pytest.fixture(scope="session")
def repo_dir() -> Path:
    return REPO


@pytest.fixture(scope="session")
def media_dir() -> Path:
    return need(MEDIA, "shared media clips")


@pytest.fixture(scope="session")
def psycho_dir() -> Path:
    return need(PSYCHO, "ISO 532-1 / DIN 45692 reference data")
