"""Helpers of the browser tests, kept apart from conftest.py so test modules import them by a name
no other folder uses: paths, the shared clips, API set-up, and reading the editor's state."""

from __future__ import annotations

import os
import shutil
import subprocess
import time
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

import httpx
import pytest

from autohaptics.bench.serve import ServerError, free_port, stop_server  # noqa: F401 (the tests import them from here)
from autohaptics.bench.serve import start_server as serve

REPO = Path(__file__).resolve().parents[2]
SHARED = Path(os.environ.get("AUTOHAPTICS_SHARED", REPO.parent / "shared")).resolve()
MEDIA = SHARED / "media"
ARTIFACTS = REPO / "test-artifacts" / "screenshots"
JOB_TIMEOUT_S = 120.0
SERVER_START_S = 60.0
CHROMIUM = Path(os.environ.get("AUTOHAPTICS_CHROMIUM", "/usr/bin/chromium"))
CHROMIUM_ARGS = ["--no-sandbox", "--disable-gpu", "--disable-background-networking", "--disable-component-update",
                 "--disable-sync", "--no-first-run", "--disable-quic"]


def start_server(data_dir: Path, *, port: int | None = None, jobs: int = 1) -> tuple[subprocess.Popen, str]:
    """Start ``autohaptics serve`` on ``port`` (a free one by default) with ``data_dir/data`` and the
    repository's frontend; returns (process, base URL) once /health answers. Its output goes to
    ``data_dir/server.log``."""
    data_dir.mkdir(parents=True, exist_ok=True)
    log_path = data_dir / "server.log"
    log_path.write_text("")
    return serve(data_dir / "data", log_path=log_path, port=port, jobs=jobs, frontend=REPO / "frontend",
                 timeout_s=SERVER_START_S, cwd=REPO)


def api_client(url: str, **kwargs) -> httpx.Client:
    """An httpx client on the service that holds its session token (docs/API.md "Security")."""
    token = httpx.get(f"{url.rstrip('/')}/api/session", timeout=30.0).raise_for_status().json()["token"]
    return httpx.Client(base_url=url, headers={"x-autohaptics-token": token}, **kwargs)


def media_clip(name: str) -> Path:
    """A clip of ../shared/media; the test is skipped with the reason when it is absent."""
    path = MEDIA / name
    if not path.is_file():
        pytest.skip(f"shared clip {name} not found at {path}: it comes from the project's shared folder "
                    "(../shared next to the repository, or set AUTOHAPTICS_SHARED)")
    return path


def wait_until(check, what: str, timeout: float = 20.0) -> None:
    """Poll ``check()`` until it is true; fail naming ``what`` on timeout."""
    deadline = time.monotonic() + timeout
    while not check():
        if time.monotonic() > deadline:
            pytest.fail(f"timed out after {timeout} s waiting until {what}")
        time.sleep(0.1)


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


def screenshot(pg, name: str) -> Path:
    """Save test-artifacts/screenshots/<name>.png."""
    ARTIFACTS.mkdir(parents=True, exist_ok=True)
    path = ARTIFACTS / f"{name}.png"
    pg.screenshot(path=str(path))
    return path


def copy_to_docs(src: Path, name: str) -> None:
    """Refresh a README screenshot in docs/img (only when AUTOHAPTICS_UPDATE_DOCS_IMG=1)."""
    if os.environ.get("AUTOHAPTICS_UPDATE_DOCS_IMG") == "1":
        dest = REPO / "docs" / "img" / name
        dest.parent.mkdir(parents=True, exist_ok=True)
        shutil.copyfile(src, dest)


@contextmanager
def checked_page(browser, base_url: str, viewport: dict, **context_kw) -> Iterator:
    """A page in a fresh browser context (20 s default timeout); the test fails on any uncaught
    error in the page once it is done with it."""
    context = browser.new_context(viewport=viewport, base_url=base_url, **context_kw)
    pg = context.new_page()
    errors: list[str] = []
    pg.on("pageerror", lambda exc: errors.append(str(exc)))
    pg.set_default_timeout(20_000)
    yield pg
    context.close()
    assert not errors, f"uncaught errors in the page: {errors}"


def open_editor(pg, project_id: str) -> None:
    """Open the editor on a project and wait until its timeline is drawn and its history loaded."""
    pg.goto(f"/#/project/{project_id}")
    pg.wait_for_selector("#app[data-ready='true']")
    pg.wait_for_function("() => { const s = window.autohaptics.state(); return s && s.revision !== null; }")


def state(pg) -> dict:
    """The editor's debug snapshot (window.autohaptics.state())."""
    return pg.evaluate("() => window.autohaptics.state()")


def values_at(pg, tick: int) -> dict:
    """Composed values at one tick as the editor holds them."""
    return pg.evaluate("(t) => window.autohaptics.valuesAt(t)", tick)


def sampled_ticks(pg, count: int = 52, step: int = 10) -> list[dict]:
    """Composed values at every ``step``-th tick once the drawn revision is complete: its played
    temperature curve (``played_c``) arrives in a request of its own after the lanes are drawn, so
    values read before it show ``played_c`` null and compare unequal to the same revision later."""
    pg.wait_for_function("() => { const s = window.autohaptics.state();"
                         " return s && s.played !== null && s.played.revision === s.drawnRevision; }")
    return pg.evaluate("([n, k]) => Array.from({length: n}, (_, i) => window.autohaptics.valuesAt(i * k))",
                       [count, step])


def next_frame(pg) -> None:
    """Let the page draw: resolves after two animation frames."""
    pg.evaluate("() => new Promise((r) => requestAnimationFrame(() => requestAnimationFrame(r)))")


def lane_pixels(pg, lane: str, background: tuple[int, int, int] = (18, 21, 28)) -> dict:
    """What a lane's canvas shows, summarised in the page: a hash of its RGBA bytes and the number
    of pixels that differ from the lane background (``lit``)."""
    return pg.evaluate(
        """([lane, bg]) => {
            const c = document.querySelector(`canvas[data-lane="${lane}"]`);
            const d = c.getContext('2d').getImageData(0, 0, c.width, c.height).data;
            let h = 0x811c9dc5, lit = 0;
            for (let i = 0; i < d.length; i++) h = Math.imul(h ^ d[i], 0x01000193) >>> 0;
            for (let i = 0; i < d.length; i += 4) if (d[i] !== bg[0] || d[i + 1] !== bg[1] || d[i + 2] !== bg[2]) lit++;
            return {hash: h.toString(16), lit};
        }""",
        [lane, list(background)],
    )


def settled_lane_pixels(pg, lane: str, *, still_s: float = 0.3, timeout_s: float = 10.0) -> dict:
    """:func:`lane_pixels` once the lane has not changed for ``still_s``: on a loaded machine a lane
    was seen to redraw a moment after the editor was ready, with no input."""
    last, since, end = lane_pixels(pg, lane), time.monotonic(), time.monotonic() + timeout_s
    while time.monotonic() < end:
        pg.wait_for_timeout(50)
        now = lane_pixels(pg, lane)
        if now != last:
            last, since = now, time.monotonic()
        elif time.monotonic() - since >= still_s:
            return now
    raise AssertionError(f"lane {lane!r} kept changing for {timeout_s} s")


def lane_rect(pg, lane: str) -> dict:
    """Client rectangle of a lane's canvas, scrolled into view first (the timeline scrolls vertically)."""
    pg.evaluate("(id) => document.querySelector(`canvas[data-lane=\"${id}\"]`).scrollIntoView({block: 'nearest'})", lane)
    return pg.evaluate("(id) => window.autohaptics.laneRect(id)", lane)


def client_x(pg, time_s: float) -> float:
    return pg.evaluate("(t) => window.autohaptics.clientXOf(t)", time_s)


def wait_jobs_settled(pg) -> dict:
    """Wait until no job is being followed (a threshold re-derive may start a background re-analysis)
    and the editor drew its saved revision."""
    pg.wait_for_function(
        """() => {
            const s = window.autohaptics.state();
            return s && !s.jobActive && s.drawnRevision === s.revision && s.saveState === 'saved';
        }""")
    return state(pg)


def wait_revision_above(pg, revision: int) -> dict:
    """Wait until the editor saved past ``revision`` and drew the composed timeline of the new revision."""
    pg.wait_for_function(
        """(rev) => {
            const s = window.autohaptics.state();
            return s && s.revision > rev && s.drawnRevision === s.revision && s.saveState === 'saved';
        }""",
        arg=revision)
    return state(pg)
