"""Learned styles: learn from projects, list, get, download, import a file, delete (docs/API.md "Styles")."""

from __future__ import annotations

import json

from anyio import to_thread
from fastapi import APIRouter, Request, Response

from autohaptics.errors import ParameterError
from autohaptics.server.deps import ComposerDep, StoreDep, StylesDep
from autohaptics.server.routes.timeline import content_disposition
from autohaptics.server.schemas import StyleDetailOut, StyleLearnIn, StyleOut
from autohaptics.server.styles import MAX_STYLE_BYTES, learn_from_projects, parse_style_file
from autohaptics.server.uploads import display_name, multipart_body, receive_upload
from autohaptics.style import to_dict

router = APIRouter(tags=["styles"])

_IMPORT_BODY = multipart_body("a style file (JSON, docs/STYLE_FORMAT.md)")


@router.post("/api/styles", status_code=201, response_model=StyleDetailOut,
             responses={200: {"model": StyleDetailOut, "description": "dry run: learned, nothing stored"},
                        409: {"description": "a project has no timeline yet"}})
async def learn_style(body: StyleLearnIn, response: Response, store: StoreDep, composer: ComposerDep,
                      styles: StylesDep) -> dict:
    name = display_name(body.name, basename=False, fallback="")
    if not name:
        raise ParameterError("field 'name' must hold at least one visible character")
    style, report = await to_thread.run_sync(
        lambda: learn_from_projects(store, composer, body.project_ids, name=name))
    films = [{"project_id": r["project_id"], "name": r["name"]} for r in report]
    if body.dry_run:
        response.status_code = 200
        return {"id": None, "name": style.name, "created_at": None, "films": films, "report": report,
                "document": to_dict(style)}
    return await to_thread.run_sync(lambda: styles.add(style, films=films, report=report))


@router.get("/api/styles", response_model=list[StyleOut])
def list_styles(styles: StylesDep) -> list[dict]:
    return styles.list()


@router.post("/api/styles/import", status_code=201, response_model=StyleDetailOut, openapi_extra=_IMPORT_BODY,
             responses={400: {"description": "not a valid style file"}, 413: {"description": "file too large"}})
async def import_style(request: Request, store: StoreDep, styles: StylesDep) -> dict:
    dest = store.new_upload_path()
    upload = await receive_upload(request.headers, request.stream(), dest, max_bytes=MAX_STYLE_BYTES)
    try:
        data = await to_thread.run_sync(dest.read_bytes)
    finally:
        dest.unlink(missing_ok=True)
    stem = display_name(upload.filename).rsplit(".json", 1)[0].removesuffix(".style") or "style"
    style = parse_style_file(data, fallback_name=stem)
    return await to_thread.run_sync(lambda: styles.add(style, films=[], report=[]))


@router.get("/api/styles/{style_id}", response_model=StyleDetailOut)
def get_style(style_id: str, styles: StylesDep) -> dict:
    return styles.get(style_id)


@router.get("/api/styles/{style_id}/download", response_class=Response,
            responses={200: {"description": "the style file (Content-Disposition attachment)"}})
def download_style(style_id: str, styles: StylesDep) -> Response:
    style = styles.get(style_id)
    data = json.dumps(style["document"], indent=1) + "\n"
    return Response(data, media_type="application/json",
                    headers={"Content-Disposition": content_disposition(f"{style['name']}.style.json")})


@router.delete("/api/styles/{style_id}", status_code=204)
def delete_style(style_id: str, styles: StylesDep) -> Response:
    styles.delete(style_id)
    return Response(status_code=204)
