"""A project's shots: the list with each shot's summary (boundary edits are ``POST edits`` ops), a
shot's similar shots, and the pictures: shot posters and the filmstrip."""

from __future__ import annotations

from anyio import to_thread
from fastapi import APIRouter, Response

from autohaptics.server import shots
from autohaptics.server.deps import ComposerDep, PicturesDep
from autohaptics.server.schemas import FilmstripOut, ShotsOut, SimilarOut

router = APIRouter(tags=["shots"])
_JPEG = {200: {"content": {"image/jpeg": {}}, "description": "the picture"}}
_IMMUTABLE = {"Cache-Control": "public, max-age=31536000, immutable"}  # a tick's frame never changes


@router.get("/api/projects/{project_id}/shots", response_model=ShotsOut)
def get_shots(project_id: str, composer: ComposerDep, pictures: PicturesDep) -> dict:
    """The shots of the composed timeline: boundaries from the analysis and the applied boundary
    edits, summaries from the composed tracks and the analysis (docs/API.md, "Shots")."""
    composed = composer.compose(project_id)
    answer = shots.shot_list(project_id, composer.analysis(project_id), composed)
    pictures.ahead(project_id)  # the posters and the coarse filmstrip, in the background
    return answer


@router.get("/api/projects/{project_id}/shots/{shot_id}/similar", response_model=SimilarOut)
def get_similar(project_id: str, shot_id: int, composer: ComposerDep) -> dict:
    """Every other shot by ascending distance to ``shot_id`` in the analysis's own features
    (docs/API.md, "Shots"); 404 for an id that starts no shot."""
    composed = composer.compose(project_id)
    return shots.similar_shots(project_id, composer.analysis(project_id), composed, shot_id)


@router.get("/api/projects/{project_id}/posters/{tick}.jpg", response_class=Response, responses=_JPEG)
async def get_poster(project_id: str, tick: int, pictures: PicturesDep) -> Response:
    """The poster of a shot (its ``poster_url``): the frame of ``tick``, made on first request."""
    data = await to_thread.run_sync(pictures.poster, project_id, tick)
    return Response(data, media_type="image/jpeg", headers=_IMMUTABLE)


@router.get("/api/projects/{project_id}/filmstrip", response_model=FilmstripOut)
def get_filmstrip(project_id: str, pictures: PicturesDep) -> dict:
    """The filmstrip's geometry: frame size, frames per tile, steps (docs/API.md, "Shots")."""
    answer = pictures.geometry(project_id)
    pictures.ahead(project_id)
    return answer


@router.get("/api/projects/{project_id}/filmstrip/{step}/{tile}.jpg", response_class=Response, responses=_JPEG)
async def get_filmstrip_tile(project_id: str, step: int, tile: int, pictures: PicturesDep) -> Response:
    """Tile ``tile`` at ``step``: frames of ticks (16 tile + k) step side by side, made on first request."""
    data = await to_thread.run_sync(pictures.tile, project_id, step, tile)
    return Response(data, media_type="image/jpeg", headers=_IMMUTABLE)
