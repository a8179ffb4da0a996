"""Browser fixtures: a real ``autohaptics serve`` on a free port with a temporary data folder, and
Debian's Chromium driven by Playwright (never a downloaded browser).

- ``server``: base URL of the running service (one per session).
- ``api``: an httpx client on it, for setting up projects and checking what the UI saved.
- ``sintel_project``: a generated project of the sintel trailer (once per session); tests work on
  copies from ``project_copy`` so they never see each other's edits.
- ``page``: a fresh browser context and page per test; an uncaught page error fails the test.

The helpers the tests import live in browser_support.py.
"""

from __future__ import annotations

import os
import signal
import socket
import subprocess
import sys
import time
from pathlib import Path

import httpx
import pytest

from browser_support import REPO, media_clip, upload

CHROMIUM = Path(os.environ.get("AUTOHAPTICS_CHROMIUM", "/usr/bin/chromium"))
CHROMIUM_ARGS = ["--no-sandbox", "--disable-gpu", "--disable-background-networking", "--disable-component-update",
                 "--disable-sync", "--no-first-run", "--disable-quic"]
VIEWPORT = {"width": 1440, "height": 900}
SERVER_START_S = 60.0


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
         "--data", str(data / "data"), "--frontend", str(REPO / "frontend")],
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
            os.killpg(proc.pid, signal.SIGKILL)
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
