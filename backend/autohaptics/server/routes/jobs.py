"""Generation jobs (start, state, SSE progress, cancel) and parameter changes (re-derive or re-analyse)."""

from __future__ import annotations

from fastapi import APIRouter, Body, Response
from fastapi.responses import StreamingResponse

from autohaptics.server.sse import event_stream
from autohaptics.server.deps import ComposerDep, RunnerDep, StoreDep, StylesDep
from autohaptics.server.jobs import TERMINAL
from autohaptics.server.schemas import JobAccepted, JobOut, ParamsIn, ParamsOut
from autohaptics.server.styles import style_ref
from autohaptics.params import params_from_doc, resolve_doc, same_analysis

router = APIRouter(tags=["jobs"])


def _resolve(project: dict, body: ParamsIn | None, styles) -> dict:
    given = body.model_dump(exclude_unset=True) if body is not None else {}
    choose = "style" in given
    style_id = given.pop("style", None)
    doc, _ = resolve_doc(project["params"], **given)
    if choose:  # null drops the style, an id chooses that stored style (404 when unknown)
        doc.pop("style", None)
        if style_id is not None:
            doc["style"] = style_ref(styles.get(style_id))
    return doc


@router.post("/api/projects/{project_id}/generate", status_code=202, response_model=JobAccepted,
             responses={409: {"description": "a job of this project is running"}})
def generate(project_id: str, store: StoreDep, runner: RunnerDep, styles: StylesDep,
             body: ParamsIn | None = Body(default=None)) -> dict:
    project = store.get_project(project_id)
    doc = _resolve(project, body, styles)
    job = runner.submit(project, doc, record=True)
    store.set_params(project_id, doc)
    return {"job": job}


@router.put("/api/projects/{project_id}/params", response_model=ParamsOut,
            responses={202: {"model": ParamsOut, "description": "a new analysis was started"}})
def put_params(project_id: str, body: ParamsIn, response: Response, store: StoreDep, runner: RunnerDep,
               composer: ComposerDep, styles: StylesDep) -> dict:
    with runner.params_lock(project_id):
        return _put_params(project_id, body, response, store, runner, composer, styles)


def _put_params(project_id: str, body: ParamsIn, response: Response, store, runner, composer, styles) -> dict:
    project = store.get_project(project_id)
    doc = _resolve(project, body, styles)
    out = apply_params(project_id, doc, store, runner, composer)
    if not out["derived"]:
        response.status_code = 202
    if project["has_timeline"] and doc != project["params"]:
        recorded = store.append_edit(project_id, None, {"op": "params", "from": project["params"], "to": doc})
        out.update(recorded)
    return out


def apply_params(project_id: str, doc: dict, store, runner, composer) -> dict:
    """Make ``doc`` the project's parameters: re-derived from the cached analysis (or from the
    previous one, while no job runs) when it can be (``derived`` true, the revision moves on), else
    a job analyses the film again (or the running one, when it needs the same analysis, derives
    with them when it ends). Call it under the project's ``runner.params_lock``. Returns
    ``{revision, derived, seconds?, job}``."""
    derived = composer.rederive(project_id, doc, previous=runner.active_job(project_id) is None)
    if derived is not None:
        job = None
        if derived.needs_analysis and runner.active_job(project_id) is None:
            # the ticks that now vibrate lack saliency: compute just theirs (a running job derives
            # with these parameters when it ends, and refines again if they still lack some)
            from autohaptics.pipeline.refine import refinable  # the pipeline loads on first use

            job = runner.submit(store.get_project(project_id), doc, refine=refinable(params_from_doc(doc)[0]))
        return {"revision": derived.revision, "derived": True, "seconds": derived.seconds, "job": job}
    project = store.get_project(project_id)
    running = runner.active_job(project_id)
    if running is not None and same_analysis(running["params"], doc):
        store.set_params(project_id, doc)  # the running job derives with them when it finishes
        return {"revision": project["revision"], "derived": False, "job": running}
    job = runner.submit(project, doc)
    store.set_params(project_id, doc)
    return {"revision": project["revision"], "derived": False, "job": job}


@router.get("/api/jobs/{job_id}", response_model=JobOut)
def get_job(job_id: str, runner: RunnerDep) -> dict:
    return runner.job(job_id)


@router.post("/api/jobs/{job_id}/cancel", status_code=202, response_model=JobOut,
             responses={409: {"description": "the job has already finished"}})
def cancel_job(job_id: str, runner: RunnerDep) -> dict:
    return runner.cancel(job_id)


@router.get("/api/jobs/{job_id}/events", response_class=StreamingResponse,
            responses={200: {"content": {"text/event-stream": {}},
                             "description": "progress events, then done / failed / cancelled"}})
async def job_events(job_id: str, runner: RunnerDep) -> StreamingResponse:
    return event_stream(runner.subscribe(job_id), final=lambda name: name in TERMINAL)
