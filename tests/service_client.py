"""The web service as a local program reaches it in tests: Host 127.0.0.1:8000 (a name the service
answers to, docs/API.md "Security") and the session token from ``GET /api/session`` kept as a cookie."""

from __future__ import annotations

import time
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

from fastapi.testclient import TestClient

BASE_URL = "http://127.0.0.1:8000"


class LocalClient(TestClient):
    """``TestClient`` for ``app`` at :data:`BASE_URL`; entering it starts the app and takes the token."""

    def __init__(self, app, **kwargs):
        super().__init__(app, base_url=BASE_URL, **kwargs)

    def __enter__(self) -> "LocalClient":
        client = super().__enter__()
        response = client.get("/api/session")
        assert response.status_code == 200, response.text
        return client

    def finished_job(self, job_id: str, *, timeout_s: float = 180.0) -> dict:
        """The job ``job_id`` once it has ended (done, failed or cancelled), polled every 0.1 s."""
        deadline = time.monotonic() + timeout_s
        while (job := self.get(f"/api/jobs/{job_id}").json())["status"] not in ("done", "failed", "cancelled"):
            assert time.monotonic() < deadline, f"job {job_id} did not end within {timeout_s:g} s: {job}"
            time.sleep(0.1)
        return job

    def generated_project(self, film: Path, **form: str) -> dict:
        """Upload ``film`` (form fields ``form``, e.g. ``mode="audio"``), wait for its generate job
        to end done, and return the project."""
        r = self.post("/api/projects", files={"file": (film.name, film.read_bytes(), "video/mp4")}, data=form)
        assert r.status_code == 201, r.text
        job = self.finished_job(r.json()["job"]["id"])
        assert job["status"] == "done", job
        return self.get(f"/api/projects/{r.json()['id']}").json()

    @contextmanager
    def duplicated(self, pid: str) -> Iterator[dict]:
        """A copy of project ``pid`` for one test (its analysis and timeline reused), removed after."""
        r = self.post(f"/api/projects/{pid}/duplicate")
        assert r.status_code == 201, r.text
        try:
            yield r.json()
        finally:
            self.delete(f"/api/projects/{r.json()['id']}")
