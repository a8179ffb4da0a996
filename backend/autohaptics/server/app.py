"""The FastAPI application: routes, error mapping, the job runner's lifetime, the static frontend."""

from __future__ import annotations

import logging
import re
from contextlib import asynccontextmanager

import anyio
from fastapi import FastAPI, Request
from fastapi.exceptions import RequestValidationError
from fastapi.responses import JSONResponse

from autohaptics import __version__
from autohaptics.errors import DeviceError, MediaError, ParameterError
from autohaptics.server import folder_lock
from autohaptics.server.chair import ChairService
from autohaptics.server.frontend import FrontendFiles
from autohaptics.server.jobs import JobRunner
from autohaptics.server.pictures import Pictures
from autohaptics.server.routes import chair, jobs, projects, service, shots, styles, timeline
from autohaptics.server.security import TrustBoundary, folder_token, host_names
from autohaptics.server.settings import Settings
from autohaptics.server.store import Conflict, NotFound, Store
from autohaptics.server.styles import Styles
from autohaptics.server.composer import Composer
from autohaptics.server.uploads import MediaRejected, UploadTooLarge

log = logging.getLogger("autohaptics.server")


def create_app(settings: Settings | None = None) -> FastAPI:
    """The service for ``settings`` (default: :meth:`Settings.from_env`).

    The store, the composer, the job runner and the chair service start with the application's lifespan
    (use ``with TestClient(app)`` in tests) and are reachable through the dependencies of
    :mod:`autohaptics.server.deps`.
    """
    settings = settings or Settings.from_env()

    @asynccontextmanager
    async def lifespan(app: FastAPI):
        folder = folder_lock.acquire(settings.data_dir)  # before recovery: one server per folder
        try:
            app.state.token = folder_token(folder)
            async with _services(app, settings):
                yield
        finally:
            folder_lock.release(folder)

    app = FastAPI(title="autohaptics", version=__version__, lifespan=lifespan,
                  description="The editor's HTTP API: projects, generation jobs, timelines and edits "
                              "(docs/API.md).")
    app.state.settings = settings
    app.state.token = None
    app.add_middleware(TrustBoundary, names=host_names(settings.bind_host, settings.allowed_hosts),
                       token_of=lambda: app.state.token)
    _add_error_handlers(app)
    for module in (service, projects, jobs, timeline, shots, styles, chair):
        app.include_router(module.router)
    front = settings.frontend_dir
    if front is not None and front.is_dir():
        app.mount("/", FrontendFiles(directory=front, html=True), name="frontend")
    return app


@asynccontextmanager
async def _services(app: FastAPI, settings: Settings):
    """The store (after its start-up recovery), the composer, the job runner and the chair service."""
    store = Store(settings.data_dir)
    interrupted = store.recover()
    composer = Composer(store)
    pictures = Pictures(store, composer, bound_bytes=settings.picture_cache_bytes,
                        busy=lambda: bool(store.active_jobs()), mp_context=settings.mp_context)
    composer.on_warm = pictures.ahead  # after a job, and the project opened at start-up
    recent = store.last_worked_on()
    if recent is not None:
        composer.warm(recent)
    runner = JobRunner(store, workers=settings.jobs, mp_context=settings.mp_context, composer=composer)
    await anyio.to_thread.run_sync(runner.start)
    if interrupted:
        log.warning("%d job(s) interrupted by a server restart are queued again", len(interrupted))
        await anyio.to_thread.run_sync(runner.resume, interrupted)
    chair_service = ChairService(store, composer)
    chair_service.start()
    app.state.store, app.state.composer, app.state.runner = store, composer, runner
    app.state.pictures = pictures
    app.state.chair = chair_service
    app.state.styles = Styles(settings.data_dir)
    try:
        yield
    finally:
        await anyio.to_thread.run_sync(chair_service.close)  # STOP before anything else goes
        await anyio.to_thread.run_sync(runner.stop)
        await anyio.to_thread.run_sync(pictures.close)
        await anyio.to_thread.run_sync(composer.writer.close)  # the last re-derive reaches the disk
        app.state.styles.close()
        store.close()



def _detail(status: int, message: str, **extra) -> JSONResponse:
    """An error answer; control characters a client put in a name it sent are shown escaped, so the
    message stays one line."""
    message = _CONTROL.sub(lambda m: ascii(m.group())[1:-1], message)
    return JSONResponse(status_code=status, content={"detail": message, **extra})


_CONTROL = re.compile(r"[\x00-\x1f\x7f]")


# Every error the application raises on purpose, and its HTTP status (MediaRejected carries its own).
_STATUS = ((NotFound, 404), (Conflict, 409), (DeviceError, 409), (UploadTooLarge, 413), (MediaError, 422))


def _add_error_handlers(app: FastAPI) -> None:
    for exc_type, status in _STATUS:
        app.add_exception_handler(exc_type, lambda request, exc, status=status: _detail(status, str(exc)))

    @app.exception_handler(MediaRejected)
    async def rejected(request: Request, exc: MediaRejected):
        return _detail(exc.status, str(exc))

    @app.exception_handler(ParameterError)
    async def bad_parameter(request: Request, exc: ParameterError):
        problems = getattr(exc, "problems", None)
        if problems is not None:
            return _detail(400, str(exc), problems=[
                {"row": p.row, "column": p.column, "message": p.message} for p in problems])
        return _detail(400, str(exc))

    @app.exception_handler(RequestValidationError)
    async def invalid_request(request: Request, exc: RequestValidationError):
        errors = exc.errors()
        if not errors:
            return _detail(400, "invalid request")
        first = errors[0]
        where = ".".join(str(p) for p in first.get("loc", ())[1:]) or "body"
        return _detail(400, f"field '{where}': {first.get('msg', 'invalid')}")
