"""The chair: ports, connect / disconnect, status (and its SSE stream), playback reports, STOP,
settings (latency offset, comfort) and pushing a range. The work is done by
:class:`autohaptics.server.chair.ChairService`."""

from __future__ import annotations

from fastapi import APIRouter
from fastapi.responses import StreamingResponse

from autohaptics.server.deps import ChairDep
from autohaptics.server.sse import event_stream
from autohaptics.server.schemas import (
    ChairConnectIn, ChairPlaybackIn, ChairPushIn, ChairSettingsIn, ChairSettingsOut, ChairStatusOut, PortOut,
)

router = APIRouter(tags=["chair"])
_CONFLICT = {409: {"description": "no chair connected, the port failed, or a push is running"}}


@router.get("/api/chair/ports", response_model=list[PortOut])
def ports(chair: ChairDep) -> list[dict]:
    return chair.ports()


@router.post("/api/chair/connect", response_model=ChairStatusOut,
             responses={409: {"description": "the port cannot be opened or no chair answers on it"}})
def connect(body: ChairConnectIn, chair: ChairDep) -> dict:
    return chair.connect(body.port)


@router.post("/api/chair/disconnect", response_model=ChairStatusOut)
def disconnect(chair: ChairDep) -> dict:
    return chair.disconnect()


@router.get("/api/chair/status", response_model=ChairStatusOut)
def status(chair: ChairDep) -> dict:
    return chair.status()


@router.post("/api/chair/playback", response_model=ChairStatusOut, responses=_CONFLICT)
def playback(body: ChairPlaybackIn, chair: ChairDep) -> dict:
    return chair.playback(body.project_id, body.state, body.position_s, heartbeat=body.heartbeat,
                          initial=body.initial)


@router.post("/api/chair/stop", response_model=ChairStatusOut)
def stop(chair: ChairDep) -> dict:
    return chair.stop()


@router.get("/api/chair/settings", response_model=ChairSettingsOut)
def get_settings(chair: ChairDep) -> dict:
    return chair.settings


@router.put("/api/chair/settings", response_model=ChairSettingsOut)
def put_settings(body: ChairSettingsIn, chair: ChairDep) -> dict:
    comfort = body.comfort
    mute = comfort.mute.model_dump(exclude_none=True) if comfort is not None and comfort.mute is not None else None
    return chair.update_settings(latency_ms=body.latency_ms, scale=comfort.scale if comfort is not None else None,
                                 mute=mute)


@router.post("/api/chair/push", response_model=ChairStatusOut, status_code=202, responses=_CONFLICT)
def push(body: ChairPushIn, chair: ChairDep) -> dict:
    return chair.push(body.project_id, body.start_s, body.end_s)


@router.get("/api/chair/events", response_class=StreamingResponse,
            responses={200: {"content": {"text/event-stream": {}},
                             "description": "`status` events: the current status, then on every change and "
                                            "at least twice a second"}})
async def events(chair: ChairDep) -> StreamingResponse:
    return event_stream(chair.subscribe())
