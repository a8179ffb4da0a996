"""Generation jobs (start, state, SSE progress, cancel) and parameter changes (re-derive or re-analyse)."""

from __future__ import annotations

import asyncio
import json

from fastapi import APIRouter, Body, Response
from fastapi.responses import StreamingResponse

from autohaptics.params import analysis_key
from autohaptics.records import params_to_dict
from autohaptics.server.deps import RunnerDep, StoreDep, TimelinesDep
from autohaptics.server.jobs import TERMINAL
from autohaptics.server.schemas import JobAccepted, JobOut, ParamsIn, ParamsOut
from autohaptics.server.timelines import params_from_doc, resolve

router = APIRouter(tags=["jobs"])
KEEP_ALIVE_S = 15.0


def _resolve(project: dict, body: ParamsIn | None) -> dict:
    given = body.model_dump(exclude_unset=True) if body is not None else {}
    doc, _ = resolve(project["params"], **given)
    return doc


@router.post("/api/projects/{project_id}/generate", status_code=202, response_model=JobAccepted,
             responses={409: {"description": "a job of this project is running"}})
def generate(project_id: str, store: StoreDep, runner: RunnerDep, body: ParamsIn | None = Body(default=None)) -> dict:
    project = store.get_project(project_id)
    doc = _resolve(project, body)
    job = runner.submit(project, doc)
    store.set_params(project_id, doc)
    return {"job": job}


@router.put("/api/projects/{project_id}/params", response_model=ParamsOut,
            responses={202: {"model": ParamsOut, "description": "a new analysis was started"}})
def put_params(project_id: str, body: ParamsIn, response: Response, store: StoreDep, runner: RunnerDep,
               timelines: TimelinesDep) -> dict:
    with runner.params_lock(project_id):
        return _put_params(project_id, body, response, store, runner, timelines)


def _put_params(project_id: str, body: ParamsIn, response: Response, store, runner, timelines) -> dict:
    project = store.get_project(project_id)
    doc = _resolve(project, body)
    derived = timelines.rederive(project_id, doc)
    if derived is not None:
        job = None
        if derived.needs_analysis and runner.active_job(project_id) is None:
            job = runner.submit(store.get_project(project_id), doc)
        return {"revision": derived.revision, "derived": True, "seconds": derived.seconds, "job": job}
    response.status_code = 202
    running = runner.active_job(project_id)
    if running is not None and _same_analysis(running["params"], doc):
        store.set_params(project_id, doc)  # the running job derives with them when it finishes
        return {"revision": project["revision"], "derived": False, "job": running}
    job = runner.submit(project, doc)
    store.set_params(project_id, doc)
    return {"revision": project["revision"], "derived": False, "job": job}


def _same_analysis(a: dict, b: dict) -> bool:
    return analysis_key(params_to_dict(params_from_doc(a)[0])) == analysis_key(params_to_dict(params_from_doc(b)[0]))


@router.get("/api/jobs/{job_id}", response_model=JobOut)
def get_job(job_id: str, runner: RunnerDep) -> dict:
    return runner.job(job_id)


@router.post("/api/jobs/{job_id}/cancel", status_code=202, response_model=JobOut,
             responses={409: {"description": "the job has already finished"}})
def cancel_job(job_id: str, runner: RunnerDep) -> dict:
    return runner.cancel(job_id)


def _sse(event: str, data: dict) -> str:
    return f"event: {event}\ndata: {json.dumps(data, separators=(',', ':'))}\n\n"


@router.get("/api/jobs/{job_id}/events", response_class=StreamingResponse,
            responses={200: {"content": {"text/event-stream": {}},
                             "description": "progress events, then done / failed / cancelled"}})
async def job_events(job_id: str, runner: RunnerDep) -> StreamingResponse:
    sub = runner.subscribe(job_id)

    async def stream():
        try:
            for name, data in sub.initial:
                yield _sse(name, data)
            if sub.queue is None:
                return
            while True:
                try:
                    name, data = await asyncio.wait_for(sub.queue.get(), timeout=KEEP_ALIVE_S)
                except asyncio.TimeoutError:
                    yield ": keep-alive\n\n"
                    continue
                yield _sse(name, data)
                if name in TERMINAL:
                    return
        finally:
            sub.close()

    return StreamingResponse(stream(), media_type="text/event-stream",
                             headers={"Cache-Control": "no-cache", "X-Accel-Buffering": "no"})
