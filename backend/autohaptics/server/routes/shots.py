"""A project's shots: the list with each shot's summary (boundary edits are ``POST edits`` ops)."""

from __future__ import annotations

from fastapi import APIRouter

from autohaptics.server import shots
from autohaptics.server.deps import ComposerDep
from autohaptics.server.schemas import ShotsOut

router = APIRouter(tags=["shots"])


@router.get("/api/projects/{project_id}/shots", response_model=ShotsOut)
def get_shots(project_id: str, composer: ComposerDep) -> dict:
    """The shots of the composed timeline: boundaries from the analysis and the applied boundary
    edits, summaries from the composed tracks and the analysis (docs/API.md, "Shots")."""
    composed = composer.compose(project_id)
    return shots.shot_list(project_id, composer.analysis(project_id), composed)
