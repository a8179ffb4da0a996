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

import httpx
import pytest

from browser_support import (
    CHROMIUM, CHROMIUM_ARGS, ServerError, api_client, checked_page, media_clip, start_server, stop_server, upload,
)
# Whichever conftest module pytest imports first answers ``from conftest import ...``: offer the
# shared-data names here too (import them from shared_data in new code).
from shared_data import MEDIA, REPO, SHARED, SHARED_CLIPS, need, shared_clip  # noqa: F401,E402

VIEWPORT = {"width": 1440, "height": 900}


@pytest.fixture(scope="session")
def server(tmp_path_factory) -> str:
    try:
        proc, url = start_server(tmp_path_factory.mktemp("autohaptics-server"))
    except ServerError as exc:
        pytest.fail(str(exc))
    yield url
    stop_server(proc)


@pytest.fixture(scope="session")
def api(server) -> httpx.Client:
    with api_client(server, timeout=60.0) as client:
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
    with checked_page(browser, server, VIEWPORT, accept_downloads=True) as pg:
        yield pg
