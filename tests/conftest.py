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


@pytest.fixture(scope="session")
def sim_binary(tmp_path_factory) -> Path:
    """The virtual chair: the firmware core built natively for this host, once per test session."""
    from autohaptics.chair import build_simulator
    return build_simulator(build_dir=tmp_path_factory.mktemp("chair-sim"))


@pytest.fixture
def chair(sim_binary, tmp_path):
    """A virtual chair on a pseudo-terminal (``chair.device``), its frames logged to ``chair.jsonl``."""
    from autohaptics.chair import VirtualChair
    with VirtualChair(link_path=tmp_path / "chair", log_path=tmp_path / "chair.jsonl", binary=sim_binary) as vc:
        yield vc
