"""A project's shots: the list with each shot's summary (boundary edits are ``POST edits`` ops) and
the shots' poster frames."""

from __future__ import annotations

from anyio import to_thread
from fastapi import APIRouter, Response

from autohaptics.server import posters, shots
from autohaptics.server.deps import ComposerDep, StoreDep
from autohaptics.server.schemas import ShotsOut, SimilarOut
from autohaptics.server.store import NotFound

router = APIRouter(tags=["shots"])


@router.get("/api/projects/{project_id}/shots", response_model=ShotsOut)
def get_shots(project_id: str, composer: ComposerDep) -> dict:
    """The shots of the composed timeline: boundaries from the analysis and the applied boundary
    edits, summaries from the composed tracks and the analysis (docs/API.md, "Shots")."""
    composed = composer.compose(project_id)
    return shots.shot_list(project_id, composer.analysis(project_id), composed)


@router.get("/api/projects/{project_id}/shots/{shot_id}/similar", response_model=SimilarOut)
def get_similar(project_id: str, shot_id: int, composer: ComposerDep) -> dict:
    """Every other shot by ascending distance to ``shot_id`` in the analysis's own features
    (docs/API.md, "Shots"); 404 for an id that starts no shot."""
    composed = composer.compose(project_id)
    return shots.similar_shots(project_id, composer.analysis(project_id), composed, shot_id)


@router.get("/api/projects/{project_id}/posters/{tick}.jpg", response_class=Response,
            responses={200: {"content": {"image/jpeg": {}}, "description": "the frame of that tick"}})
async def get_poster(project_id: str, tick: int, store: StoreDep, composer: ComposerDep) -> Response:
    """The poster of a shot (its ``poster_url``): the frame of ``tick``, made on first request."""
    project = store.get_project(project_id)
    generated = composer.generated(project_id)
    n = generated.n_ticks if generated is not None else 0
    if not 0 <= tick < n:
        raise NotFound(f"tick {tick} is not in this film's timeline (0..{n - 1})")
    path = await to_thread.run_sync(posters.poster, store.project_dir(project_id) / "posters",
                                    store.media_path(project), tick)
    return Response(path.read_bytes(), media_type="image/jpeg",
                    headers={"Cache-Control": "public, max-age=31536000, immutable"})
