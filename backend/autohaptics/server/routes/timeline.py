"""The timeline: composed JSON, the binary form, edit history (append / undo / redo), export, import."""

from __future__ import annotations

import io
import re
from pathlib import PurePosixPath
from typing import Literal
from urllib.parse import quote

from anyio import to_thread
from fastapi import APIRouter, Query, Request, Response

from autohaptics.errors import ParameterError
from autohaptics.export import export_timeline, get_format
from autohaptics.server import binary
from autohaptics.server.deps import SettingsDep, StoreDep, TimelinesDep
from autohaptics.server.schemas import EditIn, EditOut, EditsOut, RevisionIn, RevisionOut
from autohaptics.server.uploads import display_name, receive_upload

router = APIRouter(tags=["timeline"])

_IMPORT_BODY = {
    "requestBody": {
        "required": True,
        "content": {"multipart/form-data": {"schema": {
            "type": "object", "required": ["file"],
            "properties": {
                "file": {"type": "string", "format": "binary", "description": "our timeline JSON or CSV"},
                "base_revision": {"type": "integer", "description": "refuse (409) unless this is the revision"},
            }}}},
    }
}


@router.get("/api/projects/{project_id}/timeline", response_class=Response,
            responses={200: {"content": {"application/json": {}}, "description": "the composed timeline"}})
def get_timeline(project_id: str, timelines: TimelinesDep) -> Response:
    return Response(timelines.timeline_json(project_id), media_type="application/json")


@router.get("/api/projects/{project_id}/timeline.bin", response_class=Response,
            responses={200: {"content": {"application/octet-stream": {}}, "description": "binary timeline"}})
def get_timeline_bin(project_id: str, timelines: TimelinesDep,
                     layer: Literal["composed", "generated"] = Query(default="composed")) -> Response:
    composed = timelines.compose(project_id)
    tl = composed.timeline if layer == "composed" else timelines.require_generated(project_id)
    return Response(binary.encode(tl, revision=composed.revision), media_type="application/octet-stream")


@router.get("/api/projects/{project_id}/edits", response_model=EditsOut)
def get_edits(project_id: str, store: StoreDep) -> dict:
    return store.edits(project_id)


@router.post("/api/projects/{project_id}/edits", response_model=EditOut,
             responses={409: {"description": "stale base_revision, or no timeline yet"}})
def post_edit(project_id: str, body: EditIn, timelines: TimelinesDep) -> dict:
    return timelines.append(project_id, body.base_revision, body.op)


@router.post("/api/projects/{project_id}/undo", response_model=RevisionOut,
             responses={409: {"description": "stale base_revision, or nothing to undo"}})
def undo(project_id: str, body: RevisionIn, store: StoreDep) -> dict:
    return store.undo(project_id, body.base_revision)


@router.post("/api/projects/{project_id}/redo", response_model=RevisionOut,
             responses={409: {"description": "stale base_revision, or nothing to redo"}})
def redo(project_id: str, body: RevisionIn, store: StoreDep) -> dict:
    return store.redo(project_id, body.base_revision)


def content_disposition(filename: str) -> str:
    """``attachment`` with an ASCII fallback name and the UTF-8 name (RFC 6266 / 5987)."""
    ascii_name = re.sub(r'[^A-Za-z0-9._ -]', "_", filename) or "timeline"
    return f"attachment; filename=\"{ascii_name}\"; filename*=UTF-8''{quote(filename, safe='')}"


@router.get("/api/projects/{project_id}/export", response_class=Response,
            responses={200: {"description": "the composed timeline as a file (Content-Disposition attachment)"}})
def export(project_id: str, store: StoreDep, timelines: TimelinesDep,
           format: str = Query(default="json", description="json, csv, ahap, hjif or mpegv")) -> Response:
    spec = get_format(format)
    project = store.get_project(project_id)
    composed = timelines.compose(project_id)
    buf = io.BytesIO()
    export_timeline(composed.document(), spec.name, buf)
    stem = PurePosixPath(project["name"]).stem or "timeline"
    return Response(buf.getvalue(), media_type=spec.media_type,
                    headers={"Content-Disposition": content_disposition(f"{stem}{spec.suffix}")})


@router.post("/api/projects/{project_id}/import", response_model=EditOut, openapi_extra=_IMPORT_BODY,
             responses={400: {"description": "not a valid timeline (with a problems list)"},
                        409: {"description": "stale base_revision, or no timeline yet"},
                        413: {"description": "file too large"}})
async def import_file(project_id: str, request: Request, store: StoreDep, settings: SettingsDep,
                      timelines: TimelinesDep) -> dict:
    store.get_project(project_id)
    dest = store.new_upload_path()
    upload = await receive_upload(request.headers, request.stream(), dest, max_bytes=settings.max_import_bytes)
    try:
        data = await to_thread.run_sync(dest.read_bytes)
    finally:
        dest.unlink(missing_ok=True)
    base = upload.fields.get("base_revision", "").strip()
    if base and not re.fullmatch(r"\d+", base):
        raise ParameterError(f"form field 'base_revision' must be an integer, got {base!r}")
    return await to_thread.run_sync(lambda: timelines.import_file(
        project_id, data, name=display_name(upload.filename), base_revision=int(base) if base else None))
