"""Browser fixtures: a real ``autohaptics serve`` on a free port with a temporary data folder, and
Debian's Chromium driven by Playwright (never a downloaded browser).

- ``server``: base URL of the running service (one per session).
- ``api``: an httpx client on it, for setting up projects and checking what the UI saved.
- ``sintel_project``: a generated project of the sintel trailer (once per session); tests work on
  copies from ``project_copy`` so they never see each other's edits.
- ``page``: a fresh browser context and page per test; an uncaught page error fails the test.
- ``screenshot(page, name)``: saves test-artifacts/screenshots/<name>.png.
"""

from __future__ import annotations

import os
import shutil
import signal
import socket
import subprocess
import sys
import time
from pathlib import Path

import httpx
import pytest

REPO = Path(__file__).resolve().parents[2]
SHARED = Path(os.environ.get("AUTOHAPTICS_SHARED", REPO.parent / "shared")).resolve()
MEDIA = SHARED / "media"
ARTIFACTS = REPO / "test-artifacts" / "screenshots"
CHROMIUM = Path(os.environ.get("AUTOHAPTICS_CHROMIUM", "/usr/bin/chromium"))
CHROMIUM_ARGS = ["--no-sandbox", "--disable-gpu", "--disable-background-networking", "--disable-component-update",
                 "--disable-sync", "--no-first-run", "--disable-quic"]
VIEWPORT = {"width": 1440, "height": 900}
SERVER_START_S = 60.0
JOB_TIMEOUT_S = 120.0


def media_clip(name: str) -> Path:
    """A clip of ../shared/media; the test is skipped with the reason when it is absent."""
    path = MEDIA / name
    if not path.is_file():
        pytest.skip(f"shared clip {name} not found at {path}: it comes from the project's shared folder "
                    "(../shared next to the repository, or set AUTOHAPTICS_SHARED)")
    return path


def _free_port() -> int:
    with socket.socket(socket.AF_INET, socket.SOCK_STREAM) as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


@pytest.fixture(scope="session")
def server(tmp_path_factory) -> str:
    data = tmp_path_factory.mktemp("autohaptics-data")
    port = _free_port()
    log_path = data / "server.log"
    log = open(log_path, "w")
    proc = subprocess.Popen(
        [sys.executable, "-m", "autohaptics.cli.main", "serve", "--host", "127.0.0.1", "--port", str(port),
         "--data", str(data / "projects-data"), "--frontend", str(REPO / "frontend")],
        stdout=log, stderr=subprocess.STDOUT, cwd=REPO, start_new_session=True)
    url = f"http://127.0.0.1:{port}"
    deadline = time.monotonic() + SERVER_START_S
    while True:
        if proc.poll() is not None:
            log.close()
            pytest.fail(f"autohaptics serve exited with {proc.returncode}:\n{log_path.read_text()[-3000:]}")
        try:
            if httpx.get(f"{url}/health", timeout=1.0).status_code == 200:
                break
        except httpx.HTTPError:
            pass
        if time.monotonic() > deadline:
            proc.kill()
            log.close()
            pytest.fail(f"autohaptics serve did not answer /health within {SERVER_START_S} s:\n"
                        f"{log_path.read_text()[-3000:]}")
        time.sleep(0.2)
    yield url
    os.killpg(proc.pid, signal.SIGTERM)
    try:
        proc.wait(timeout=15)
    except subprocess.TimeoutExpired:
        os.killpg(proc.pid, signal.SIGKILL)
        proc.wait()
    log.close()


@pytest.fixture(scope="session")
def api(server) -> httpx.Client:
    with httpx.Client(base_url=server, timeout=60.0) as client:
        yield client


def wait_job(api: httpx.Client, job_id: str, timeout: float = JOB_TIMEOUT_S) -> dict:
    """Poll a job until it ends; returns it (fails the test on timeout)."""
    deadline = time.monotonic() + timeout
    while True:
        job = api.get(f"/api/jobs/{job_id}").json()
        if job["status"] in ("done", "failed", "cancelled"):
            return job
        if time.monotonic() > deadline:
            pytest.fail(f"job {job_id} still {job['status']} after {timeout} s")
        time.sleep(0.2)


def upload(api: httpx.Client, path: Path, *, name: str | None = None, generate: bool = True) -> dict:
    """Upload through the API; with ``generate`` waits for the job and checks it finished."""
    with open(path, "rb") as fh:
        r = api.post("/api/projects", files={"file": (path.name, fh)},
                     data={"name": name or path.stem, "generate": str(generate).lower()})
    assert r.status_code == 201, r.text
    project = r.json()
    if generate:
        job = wait_job(api, project["job"]["id"])
        assert job["status"] == "done", job
        project = api.get(f"/api/projects/{project['id']}").json()
    return project


@pytest.fixture(scope="session")
def sintel_project(api) -> dict:
    return upload(api, media_clip("sintel_trailer_480x204_h264_aac.mp4"), name="sintel")


@pytest.fixture
def project_copy(api, sintel_project):
    """A fresh copy of the generated sintel project (same media, analysis and timeline)."""
    r = api.post(f"/api/projects/{sintel_project['id']}/duplicate")
    assert r.status_code == 201, r.text
    project = r.json()
    yield project
    api.delete(f"/api/projects/{project['id']}")


@pytest.fixture(scope="session")
def browser():
    if not CHROMIUM.exists():
        pytest.fail(f"Chromium not found at {CHROMIUM}: install it with `scripts/setup --test` "
                    "(Debian package chromium), or set AUTOHAPTICS_CHROMIUM")
    from playwright.sync_api import sync_playwright

    with sync_playwright() as pw:
        b = pw.chromium.launch(executable_path=str(CHROMIUM), headless=True, args=CHROMIUM_ARGS)
        yield b
        b.close()


@pytest.fixture
def page(browser, server):
    context = browser.new_context(viewport=VIEWPORT, accept_downloads=True, base_url=server)
    pg = context.new_page()
    errors: list[str] = []
    pg.on("pageerror", lambda exc: errors.append(str(exc)))
    pg.set_default_timeout(20_000)
    yield pg
    context.close()
    assert not errors, f"uncaught errors in the page: {errors}"


def screenshot(pg, name: str) -> Path:
    ARTIFACTS.mkdir(parents=True, exist_ok=True)
    path = ARTIFACTS / f"{name}.png"
    pg.screenshot(path=str(path))
    return path


def open_editor(pg, project_id: str) -> None:
    """Open the editor on a project and wait until its timeline is drawn."""
    pg.goto(f"/#/project/{project_id}")
    pg.wait_for_selector("#app[data-ready='true']")
    pg.wait_for_function("() => window.autohaptics.state() && window.autohaptics.state().revision !== null")


def state(pg) -> dict:
    return pg.evaluate("() => window.autohaptics.state()")


def lane_pixels(pg, lane: str) -> list[int]:
    """RGBA bytes of a lane's canvas (what the user sees, at device resolution)."""
    return pg.evaluate(
        """(lane) => {
            const c = document.querySelector(`canvas[data-lane="${lane}"]`);
            return Array.from(c.getContext('2d').getImageData(0, 0, c.width, c.height).data);
        }""",
        lane,
    )


def wait_revision_above(pg, revision: int) -> dict:
    """Wait until the editor saved past ``revision`` and drew the composed timeline of the new revision."""
    pg.wait_for_function(
        """(rev) => {
            const s = window.autohaptics.state();
            return s && s.revision > rev && s.drawnRevision === s.revision && s.saveState === 'saved';
        }""",
        arg=revision)
    return state(pg)


def copy_to_docs(src: Path, name: str) -> None:
    """Refresh a README screenshot in docs/img (only when AUTOHAPTICS_UPDATE_DOCS_IMG=1)."""
    if os.environ.get("AUTOHAPTICS_UPDATE_DOCS_IMG") == "1":
        dest = REPO / "docs" / "img" / name
        dest.parent.mkdir(parents=True, exist_ok=True)
        shutil.copyfile(src, dest)
