"""Projects: upload, list, get, rename / view, delete, duplicate, media (Range), waveform."""

from __future__ import annotations

import json

from anyio import to_thread
from fastapi import APIRouter, Query, Request, Response
from fastapi.responses import FileResponse

from autohaptics.errors import ParameterError
from autohaptics.server.deps import ComposerDep, PicturesDep, RunnerDep, SettingsDep, StoreDep, StylesDep
from autohaptics.server.schemas import ProjectOut, ProjectPatch, WaveformOut
from autohaptics.server.store import new_id
from autohaptics.server.styles import style_ref
from autohaptics.params import resolve_doc
from autohaptics.server.uploads import display_name, inspect_media, multipart_body, receive_upload
from autohaptics.timebase import n_ticks

router = APIRouter(tags=["projects"])

MAX_VIEW_BYTES = 64 * 1024
_UPLOAD_BODY = multipart_body(
    "the film (video or audio)",
    name={"type": "string", "description": "display name (default: the file's name)"},
    preset={"type": "string", "description": "quality preset (default balanced)"},
    mode={"type": "string", "description": "vibration mode (default from the preset)"},
    style={"type": "string", "description": "id of a stored style to derive in (default none)"},
    generate={"type": "boolean", "default": True, "description": "start a generation job"})
_TRUE, _FALSE = ("1", "true", "yes", "on"), ("0", "false", "no", "off")


def _flag(fields: dict, name: str, default: bool) -> bool:
    value = fields.get(name, "").strip().lower()
    if not value:
        return default
    if value in _TRUE:
        return True
    if value in _FALSE:
        return False
    raise ParameterError(f"form field {name!r} must be true or false, got {fields[name]!r}")


@router.get("/api/projects", response_model=list[ProjectOut])
def list_projects(store: StoreDep) -> list[dict]:
    return store.list_projects()


@router.post("/api/projects", status_code=201, response_model=ProjectOut, openapi_extra=_UPLOAD_BODY,
             responses={413: {"description": "upload too large"}, 415: {"description": "not media"},
                        422: {"description": "truncated or damaged media"}})
async def create_project(request: Request, store: StoreDep, settings: SettingsDep, runner: RunnerDep,
                         styles: StylesDep) -> dict:
    dest = store.new_upload_path()
    upload = await receive_upload(request.headers, request.stream(), dest, max_bytes=settings.max_upload_bytes)
    try:
        fields = upload.fields
        generate = _flag(fields, "generate", True)
        name = (display_name(fields["name"], basename=False, fallback="")
                if fields.get("name", "").strip() else "") or display_name(upload.filename)
        params, _ = await to_thread.run_sync(
            lambda: resolve_doc(None, preset=fields.get("preset") or None, mode=fields.get("mode") or None))
        if fields.get("style", "").strip():
            params["style"] = style_ref(styles.get(fields["style"].strip()))
        accepted = await to_thread.run_sync(lambda: inspect_media(dest, name=name))
        info = accepted.info
        project = await to_thread.run_sync(lambda: store.create_project(
            dest, media_file=f"{new_id()}{accepted.ext}", media_type=accepted.media_type, name=name,
            source=info.source_block(name=name), params=params, n_ticks=n_ticks(info.duration_s),
            duration_s=info.duration_s))
    except BaseException:
        dest.unlink(missing_ok=True)
        raise
    if generate:
        await to_thread.run_sync(runner.submit, project, project["params"])
        project = store.get_project(project["id"])
    return project


@router.get("/api/projects/{project_id}", response_model=ProjectOut)
def get_project(project_id: str, store: StoreDep) -> dict:
    return store.get_project(project_id)


@router.patch("/api/projects/{project_id}", response_model=ProjectOut)
def patch_project(project_id: str, body: ProjectPatch, store: StoreDep) -> dict:
    name = None
    if body.name is not None:
        name = display_name(body.name, basename=False, fallback="")
        if not name:
            raise ParameterError("field 'name' must hold at least one visible character")
    if body.view is not None and len(json.dumps(body.view)) > MAX_VIEW_BYTES:
        raise ParameterError(f"field 'view' is larger than {MAX_VIEW_BYTES} bytes")
    return store.update_project(project_id, name=name, view=body.view)


@router.delete("/api/projects/{project_id}", status_code=204)
def delete_project(project_id: str, store: StoreDep, runner: RunnerDep, pictures: PicturesDep) -> Response:
    store.get_project(project_id)
    runner.cancel_project(project_id)
    pictures.forget(project_id)  # no picture is being made into the folder as it goes
    store.delete_project(project_id)
    return Response(status_code=204)


@router.post("/api/projects/{project_id}/duplicate", status_code=201, response_model=ProjectOut)
def duplicate_project(project_id: str, store: StoreDep, composer: ComposerDep) -> dict:
    source = store.get_project(project_id)
    composer.flush(project_id)  # the copy takes the latest re-derive's file
    return store.duplicate_project(project_id, name=display_name(f"{source['name']} (copy)", basename=False))


@router.get("/api/projects/{project_id}/media", response_class=FileResponse,
            responses={206: {"description": "partial content (Range)"}, 416: {"description": "bad range"}})
def get_media(project_id: str, store: StoreDep) -> FileResponse:
    project = store.get_project(project_id)
    return FileResponse(store.media_path(project), media_type=project["media_type"],
                        headers={"Cache-Control": "no-cache"})


@router.get("/api/projects/{project_id}/waveform", response_model=WaveformOut)
def get_waveform(project_id: str, composer: ComposerDep, settings: SettingsDep,
                 points: int = Query(default=2000, ge=1)) -> dict:
    if points > settings.waveform_max_points:
        raise ParameterError(f"points must be at most {settings.waveform_max_points}, got {points}")
    return composer.waveform(project_id, points)
