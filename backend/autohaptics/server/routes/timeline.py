"""The timeline: composed JSON, the binary form, edit history (append / undo / redo), export, import."""

from __future__ import annotations

import io
import re
from pathlib import PurePosixPath
from typing import Literal
from urllib.parse import quote

import numpy as np
from anyio import to_thread
from fastapi import APIRouter, Query, Request, Response

from autohaptics.errors import ParameterError
from autohaptics.formats import export_timeline, get_format
from autohaptics.layout import FAN_COLS, FAN_ROWS
from autohaptics.server.deps import ChairDep, ComposerDep, RunnerDep, SettingsDep, StoreDep
from autohaptics.server.routes.jobs import apply_params
from autohaptics.server.schemas import ChairTemperatureOut, EditIn, LaneValuesOut, EditOut, EditsOut, RevisionIn, StepOut
from autohaptics.server.uploads import display_name, multipart_body, receive_upload
from autohaptics.temperature.device import played_curve, profile_of
from autohaptics.timeline import edit_ops

router = APIRouter(tags=["timeline"])
MAX_COPY_VALUES = 2_000_000  # one copy: 10 min of the fan grid, or hours of a few lanes

_IMPORT_BODY = multipart_body(
    "our timeline JSON or CSV",
    base_revision={"type": "integer", "description": "refuse (409) unless this is the revision"})


@router.get("/api/projects/{project_id}/timeline", response_class=Response,
            responses={200: {"content": {"application/json": {}}, "description": "the composed timeline"}})
def get_timeline(project_id: str, composer: ComposerDep,
                 layer: Literal["composed", "generated"] = Query(default="composed")) -> Response:
    return Response(composer.timeline_json(project_id, layer=layer), media_type="application/json")


@router.get("/api/projects/{project_id}/timeline.bin", response_class=Response,
            responses={200: {"content": {"application/octet-stream": {}}, "description": "binary timeline"},
                       304: {"description": "not modified (If-None-Match)"}})
def get_timeline_bin(project_id: str, request: Request, composer: ComposerDep,
                     layer: Literal["composed", "generated"] = Query(default="composed"),
                     blocks: str | None = Query(default=None, description="comma-separated block names, "
                                                "e.g. vibration,temperature_c,features (default: all)"),
                     since: int | None = Query(default=None, ge=0, description="a revision the client holds: the "
                                               "blocks unchanged since it are left out and named in the header")
                     ) -> Response:
    names = [b.strip() for b in blocks.split(",") if b.strip()] if blocks is not None else None
    if names is not None and not names:
        raise ParameterError("blocks must name at least one block (or leave the parameter out for all)")
    gzipped = _accepts_gzip(request.headers.get("accept-encoding", ""))
    data, tag = composer.timeline_bin(project_id, layer=layer, blocks=names, gzipped=gzipped, since=since)
    etag = f'"{tag}{"-gz" if gzipped else ""}"'
    headers = {"ETag": etag, "Cache-Control": "no-cache", "Vary": "Accept-Encoding"}
    if etag in _etags(request.headers.get("if-none-match", "")):
        return Response(status_code=304, headers=headers)
    if gzipped:
        headers["Content-Encoding"] = "gzip"
    return Response(data, media_type="application/octet-stream", headers=headers)


@router.get("/api/projects/{project_id}/timeline/chair-temperature", response_model=ChairTemperatureOut)
def get_chair_temperature(project_id: str, composer: ComposerDep, chair: ChairDep) -> dict:
    """The composed temperature track as the chair plays it (the connected chair's profile, else the
    one the timeline was made for): clamped to its safe range and slew-limited from neutral, C per tick."""
    composed = composer.compose(project_id)
    tl = composed.timeline
    profile = chair.profile() or profile_of(tl.generator.get("params") or {})
    played = played_curve(tl.temperature_c, profile, tick_s=tl.tick_s)
    return {"revision": composed.revision, "tick_s": tl.tick_s, "min_c": profile.temp_min_c,
            "max_c": profile.temp_max_c, "neutral_c": profile.temp_neutral_c,
            "rate_c_per_s": profile.temp_rate_c_per_s, "values": np.round(played, 3).tolist()}


@router.get("/api/projects/{project_id}/timeline/values", response_model=LaneValuesOut)
def get_lane_values(project_id: str, composer: ComposerDep,
                    lanes: str = Query(description="comma-separated lane ids, e.g. A1,A2,temperature,fans"),
                    t0: int = Query(ge=0, description="first tick"),
                    t1: int = Query(gt=0, description="tick after the last")) -> dict:
    """The composed values of lanes over [t0, t1) at full precision (what the editor copies)."""
    names = [lane.strip() for lane in lanes.split(",") if lane.strip()]
    if not names:
        raise ParameterError("lanes must name at least one lane")
    width = sum(FAN_ROWS * FAN_COLS if lane == "fans" else 1 for lane in names)
    if (t1 - t0) * width > MAX_COPY_VALUES:
        raise ParameterError(f"a copy holds at most {MAX_COPY_VALUES} values; select fewer ticks or lanes")
    composed = composer.compose(project_id)
    return {"revision": composed.revision, "t0": t0, "t1": t1,
            "values": edit_ops.lane_values(composed.timeline, names, t0, t1)}


def _accepts_gzip(accept_encoding: str) -> bool:
    for part in accept_encoding.split(","):
        coding, _, params = part.strip().partition(";")
        if coding.strip().lower() == "gzip":
            q = params.strip()
            return not (q.startswith("q=") and _float(q[2:]) == 0.0)
    return False


def _float(text: str) -> float | None:
    try:
        return float(text)
    except ValueError:
        return None


def _etags(if_none_match: str) -> set[str]:
    return {t.strip().removeprefix("W/") for t in if_none_match.split(",") if t.strip()}


@router.get("/api/projects/{project_id}/edits", response_model=EditsOut)
def get_edits(project_id: str, composer: ComposerDep) -> dict:
    return composer.edits(project_id)


@router.post("/api/projects/{project_id}/edits", response_model=EditOut,
             responses={409: {"description": "stale base_revision, or no timeline yet"}})
def post_edit(project_id: str, body: EditIn, composer: ComposerDep) -> dict:
    return composer.append(project_id, body.base_revision, body.op)


@router.post("/api/projects/{project_id}/undo", response_model=StepOut,
             responses={409: {"description": "stale base_revision, or nothing to undo"}})
def undo(project_id: str, body: RevisionIn, composer: ComposerDep, store: StoreDep, runner: RunnerDep) -> dict:
    with runner.params_lock(project_id):
        res = composer.undo(project_id, body.base_revision)
        op = store.edits(project_id)["ops"][res["cursor"]]
        return _params_again(project_id, res, op, "from", store, runner, composer)


@router.post("/api/projects/{project_id}/redo", response_model=StepOut,
             responses={409: {"description": "stale base_revision, or nothing to redo"}})
def redo(project_id: str, body: RevisionIn, composer: ComposerDep, store: StoreDep, runner: RunnerDep) -> dict:
    with runner.params_lock(project_id):
        res = composer.redo(project_id, body.base_revision)
        op = store.edits(project_id)["ops"][res["cursor"] - 1]
        return _params_again(project_id, res, op, "to", store, runner, composer)


def _params_again(project_id: str, res: dict, op: dict, side: str, store, runner, composer) -> dict:
    """After undo (``side`` "from") or redo ("to") of a ``params`` op, its parameters apply again."""
    if op.get("op") != "params":
        return res
    out = apply_params(project_id, op[side], store, runner, composer)
    return {**res, "revision": out["revision"], "params": op[side], "job": out["job"]}


def content_disposition(filename: str) -> str:
    """``attachment`` with an ASCII fallback name and the UTF-8 name (RFC 6266 / 5987)."""
    ascii_name = re.sub(r'[^A-Za-z0-9._ -]', "_", filename) or "timeline"
    return f"attachment; filename=\"{ascii_name}\"; filename*=UTF-8''{quote(filename, safe='')}"


@router.get("/api/projects/{project_id}/export", response_class=Response,
            responses={200: {"description": "the composed timeline as a file (Content-Disposition attachment)"}})
def export(project_id: str, store: StoreDep, composer: ComposerDep,
           format: str = Query(default="json", description="json, csv, ahap, hjif or mpegv")) -> Response:
    spec = get_format(format)
    project = store.get_project(project_id)
    composed = composer.compose(project_id)
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
                      composer: ComposerDep) -> dict:
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
    return await to_thread.run_sync(lambda: composer.import_file(
        project_id, data, name=display_name(upload.filename), base_revision=int(base) if base else None))
