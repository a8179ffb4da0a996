"""The trust boundary (docs/API.md "Security"): every state-changing request of issue 17, replayed
as a DNS-rebinding page, a foreign page (form-encoded, multipart, JSON) and a CORS preflight, is
refused with one sentence, and nothing changes on disk, in the database or on the virtual chair.
The same requests from the editor's own origin and from a local program with the token work.
"""

from __future__ import annotations

import json
import time
from pathlib import Path

import pytest
from fastapi.testclient import TestClient

from autohaptics.server.app import create_app
from autohaptics.server.settings import Settings
from autohaptics.testing import Noise, Scene, Segment, Tone, write_scene

from service_client import BASE_URL, LocalClient
from test_server_input import files_of
from test_server_jobs import sse, upload, wait_running

TERMINAL = ("done", "failed", "cancelled")
OWN = {"origin": BASE_URL, "sec-fetch-site": "same-origin"}  # the editor's own page
WAIT_S = 0.3  # a frame the chair were sent is logged by then (the positive control shows it)
REBINDING = {"host": "evil.example:8000", "origin": "http://evil.example:8000", "sec-fetch-site": "same-origin"}
FOREIGN = {"origin": "http://evil.example", "sec-fetch-site": "cross-site"}
VARIANTS = {
    "rebinding": REBINDING,
    "rebinding-no-origin": {"host": "evil.example:8000"},
    "foreign-origin": FOREIGN,
    "foreign-site-no-origin": {"sec-fetch-site": "cross-site"},
    "same-site-other-port": {"origin": "http://127.0.0.1:3000", "sec-fetch-site": "same-site"},
    "null-origin": {"origin": "null"},
}


@pytest.fixture(scope="module")
def root(tmp_path_factory) -> Path:
    return tmp_path_factory.mktemp("server-security")


@pytest.fixture(scope="module")
def client(root):
    with LocalClient(create_app(Settings(data_dir=root / "data", frontend_dir=None))) as c:
        yield c


@pytest.fixture(scope="module")
def film(root) -> Path:
    scene = Scene(duration_s=3.0, background=(Segment(0.0, 3.0, (150, 60, 40)),),
                  audio=(Tone(0.5, 2.0, 60.0, level_dbfs=-14.0),), name="security")
    return write_scene(root / "film.mp4", scene, width=64, height=36, fps=5, quality="low", sample_rate=24000)


@pytest.fixture(scope="module")
def project(client, film) -> dict:
    """A generated project with two edits, the second undone: both undo and redo would change it."""
    r = client.post("/api/projects", files={"file": ("film.mp4", film.read_bytes(), "video/mp4")},
                    data={"mode": "audio"})
    assert r.status_code == 201, r.text
    pid = r.json()["id"]
    deadline = time.monotonic() + 120
    while client.get(f"/api/jobs/{r.json()['job']['id']}").json()["status"] not in TERMINAL:
        assert time.monotonic() < deadline, "the generation job did not end"
        time.sleep(0.2)
    # The job's end warms the project in the background, which queues the pictures made ahead: wait
    # for it, so that after the wait below only a request could change the files.
    deadline = time.monotonic() + 60
    while not client.app.state.composer.held(pid):
        assert time.monotonic() < deadline, "the project was not warmed after its job"
        time.sleep(0.1)
    revision = client.get(f"/api/projects/{pid}").json()["revision"]
    for value in (0.5, 1.0):
        r = client.post(f"/api/projects/{pid}/edits", json={"base_revision": revision, "op": {
            "op": "set", "lanes": ["A1"], "t0": 0, "t1": 10, "value": value}})
        assert r.status_code == 200, r.text
        revision = r.json()["revision"]
    r = client.post(f"/api/projects/{pid}/undo", json={"base_revision": revision})
    assert r.status_code == 200, r.text
    client.app.state.composer.writer.flush(pid)
    assert client.app.state.pictures.wait_idle(60)  # queued at the job's warm-up (above)
    return client.get(f"/api/projects/{pid}").json()


def attacks(pid: str, job: str, film: Path, revision: int) -> list[tuple[str, str, dict]]:
    """(method, path, request keywords): every state-changing request issue 17 lists, and the rest."""
    media = {"files": {"file": ("film.mp4", film.read_bytes(), "video/mp4")}}
    return [
        ("PATCH", f"/api/projects/{pid}", {"json": {"name": "pwned"}}),
        ("DELETE", f"/api/projects/{pid}", {}),
        ("POST", "/api/projects", media),
        ("POST", f"/api/projects/{pid}/duplicate", {}),
        ("POST", f"/api/projects/{pid}/generate", {}),
        ("PUT", f"/api/projects/{pid}/params", {"json": {"thresholds": {"loudness": 0.1}}}),
        ("POST", f"/api/projects/{pid}/edits", {"json": {"base_revision": revision, "op": {
            "op": "set", "lanes": ["A1"], "t0": 0, "t1": 10, "value": 1.0}}}),
        ("POST", f"/api/projects/{pid}/undo", {"json": {"base_revision": revision}}),
        ("POST", f"/api/projects/{pid}/redo", {"json": {"base_revision": revision}}),
        ("POST", f"/api/projects/{pid}/import", {"files": {"file": ("t.json", b"{}", "application/json")}}),
        ("POST", f"/api/jobs/{job}/cancel", {}),
        ("PUT", "/api/chair/settings", {"json": {"comfort": {"scale": 0.2}}}),
        ("POST", "/api/chair/push", {"json": {"project_id": pid, "start_s": 0, "end_s": 2}}),
        ("POST", "/api/chair/playback", {"json": {"project_id": pid, "state": "play", "position_s": 0}}),
        ("POST", "/api/chair/connect", {"json": {"port": "/dev/null"}}),
        ("POST", "/api/chair/disconnect", {"data": {"x": "1"}}),  # form-encoded: a "simple" request
        ("POST", "/api/chair/stop", {"data": {"x": "1"}}),
    ]


def snapshot(client, root: Path, pid: str) -> tuple:
    return (files_of(root / "data"), client.get("/api/projects").json(), client.get("/api/chair/settings").json(),
            client.get(f"/api/projects/{pid}/edits").json())


def played(chair, since: int) -> list[dict]:
    return [e for e in chair.read_log()[since:] if e["ev"] in ("frame", "stop")]


@pytest.mark.parametrize("variant", sorted(VARIANTS))
def test_foreign_and_rebinding_requests_change_nothing(client, root, project, film, chair, variant):
    pid = project["id"]
    assert client.post("/api/chair/connect", json={"port": chair.device}).status_code == 200
    try:
        before, log_before = snapshot(client, root, pid), len(chair.read_log())
        for method, path, kwargs in attacks(pid, project["job"]["id"], film, project["revision"]):
            r = client.request(method, path, headers=VARIANTS[variant], **kwargs)
            assert r.status_code == 403, (method, path, r.status_code, r.text)
            detail = r.json()["detail"]
            assert detail and "\n" not in detail and str(root) not in detail, detail
            assert "access-control-allow-origin" not in r.headers
        time.sleep(WAIT_S)
        assert snapshot(client, root, pid) == before
        assert played(chair, log_before) == []
        assert client.get("/api/chair/status").json()["connected"]
        # The positive control: the same push from the editor's own page (with the token) plays
        # within the same wait, so the assertion above would see a frame that reached the chair.
        r = client.post("/api/chair/push", json={"project_id": pid, "start_s": 0, "end_s": 2}, headers=OWN)
        assert r.status_code == 202, r.text
        time.sleep(WAIT_S)
        assert [e for e in played(chair, log_before) if e["ev"] == "frame"], chair.read_log()[log_before:]
    finally:
        client.post("/api/chair/stop")
        client.post("/api/chair/disconnect")


def test_a_foreign_cancel_leaves_the_running_job_running(client, root):
    """The cancel of a job that is running (the project's own job has ended, so its replay above
    could change nothing): refused for every variant, then the editor's own cancel works."""
    noise = Scene(duration_s=900.0, audio=(Noise(0.0, 900.0, level_dbfs=-20.0),), name="long noise")
    wav = write_scene(root / "noise_15min.wav", noise, video=False, sample_rate=8000, channels=1)
    job = upload(client, wav)["job"]["id"]
    wait_running(client, job)
    try:
        for variant, headers in VARIANTS.items():
            r = client.post(f"/api/jobs/{job}/cancel", headers=headers)
            assert r.status_code == 403, (variant, r.status_code, r.text)
        time.sleep(WAIT_S)
        assert client.get(f"/api/jobs/{job}").json()["status"] == "running"
    finally:
        r = client.post(f"/api/jobs/{job}/cancel", headers=OWN)
    assert r.status_code == 202, r.text
    assert sse(client, job)[-1][0] == "cancelled"


def test_cors_preflight_is_refused(client, project):
    for path in (f"/api/projects/{project['id']}", "/api/chair/push", "/api/projects"):
        r = client.options(path, headers={"origin": "http://evil.example", "access-control-request-method": "PUT",
                                          "access-control-request-headers": "content-type"})
        assert r.status_code == 403 and r.json()["detail"] == "cross-origin requests are refused"
        assert not any(k.startswith("access-control-") for k in r.headers)


def test_chair_routes_and_event_streams_need_the_token(client, project):
    bare = TestClient(client.app, base_url=BASE_URL)  # no token: neither cookie nor header
    job = project["job"]["id"]
    for path in ("/api/chair/status", "/api/chair/ports", "/api/chair/settings", "/api/chair/events",
                 f"/api/jobs/{job}/events"):
        r = bare.get(path)
        assert r.status_code == 403 and "session token" in r.json()["detail"], (path, r.text)
    assert bare.post("/api/chair/stop").status_code == 403
    assert bare.get("/api/chair/status", headers={"x-autohaptics-token": "0" * 43}).status_code == 403
    for headers in (REBINDING, {"host": "evil.example"}, {"host": "127.0.0.1.evil.example:8000"}):
        r = bare.get("/api/session", headers=headers)  # a rebinding page would read the token here
        assert r.status_code == 403 and "token" not in r.json() and "is not a name" in r.json()["detail"], r.text
    token = bare.get("/api/session").json()["token"]
    assert bare.get("/api/chair/status", headers={"x-autohaptics-token": token}).status_code == 200
    with bare.stream("GET", f"/api/jobs/{job}/events", headers={"x-autohaptics-token": token}) as r:
        assert r.status_code == 200 and r.headers["content-type"].startswith("text/event-stream")


def test_the_editor_gets_the_token_as_a_strict_cookie_and_its_own_requests_work(client, project):
    browser = TestClient(client.app, base_url=BASE_URL)
    r = browser.get("/health", headers={"sec-fetch-site": "none"})  # the typed-in address
    cookie = r.headers["set-cookie"]
    assert cookie.startswith("autohaptics_token_8000=") and "HttpOnly" in cookie and "SameSite=Strict" in cookie
    assert "set-cookie" not in browser.get("/health", headers={"sec-fetch-site": "cross-site"}).headers
    assert browser.get("/api/chair/status", headers={"sec-fetch-site": "same-origin"}).status_code == 200
    assert browser.put("/api/chair/settings", json={"latency_ms": 0}, headers=OWN).status_code == 200
    r = browser.patch(f"/api/projects/{project['id']}", json={"name": "renamed"}, headers=OWN)
    assert r.status_code == 200 and r.json()["name"] == "renamed"
    assert browser.post("/api/chair/stop", headers=OWN).status_code == 200
    assert browser.get("/api/projects", headers={"host": "localhost:8000"}).status_code == 200


def test_a_lan_name_is_allowed_only_on_purpose(tmp_path):
    for allowed, status in (((), 403), (("studio.lan",), 200)):
        app = create_app(Settings(data_dir=tmp_path / "data", frontend_dir=None, allowed_hosts=allowed))
        with TestClient(app, base_url="http://studio.lan:8000") as c:
            r = c.get("/api/projects")
            assert r.status_code == status, r.text
            if status == 403:
                assert "--allow-host studio.lan" in r.json()["detail"]
            else:
                r = c.patch("/api/projects/nope", json={"name": "x"}, headers={"origin": "http://studio.lan:8000"})
                assert r.status_code == 404


def huge(body: dict) -> dict:
    """``body`` as raw JSON text: 10**400 written out, and the string "DIGITS" as a 5000-digit integer."""
    text = json.dumps(body).replace('"DIGITS"', "9" * 5000)
    return {"content": text.encode(), "headers": {"content-type": "application/json"}}


def malformed(pid: str, revision: int) -> list[tuple[str, str, dict, str]]:
    """(method, path, request keywords, a word of the refusal): the 500s and wrong messages of issue 17."""
    edit = f"/api/projects/{pid}/edits"
    span = {"lanes": ["A1"], "t0": 0, "t1": 1}
    return [
        ("PUT", "/api/chair/settings", huge({"comfort": {"scale": 10**400}}), "scale"),
        ("POST", edit, huge({"base_revision": revision, "op": {"op": "scale", **span, "factor": 10**400}}), "factor"),
        ("POST", edit, huge({"base_revision": revision, "op": {"op": "pencil", "lane": "A1", "t0": 0,
                                                                "values": [10**400]}}), "values"),
        ("POST", edit, {"json": {"base_revision": revision, "op": ["set"]}}, "op"),
        ("POST", edit, {"json": {"base_revision": revision, "op": {"op": {"set": 1}, **span, "value": 1}}}, "op"),
        ("POST", edit, huge({"base_revision": "DIGITS", "op": {"op": "clear", **span}}), "body"),
        ("POST", edit, {"json": {"base_revision": revision, "op": {"op": "import", "ref": "0" * 32}}}, "import"),
        ("POST", f"/api/projects/{pid}/import", {"files": {"file": ("t.json", b'{"format": "autohaptics.timeline", '
                                                                          b'"version": 1, "n_ticks": 1' + b"0" * 400
                                                                          + b"}", "application/json")}}, "t.json"),
        ("PUT", f"/api/projects/{pid}/params", {"json": {"overrides": {"intensity": 5}}}, "intensity"),
        ("PUT", f"/api/projects/{pid}/params", {"json": {"overrides": {"thermal": {"x": 1}}}}, "x"),
        ("PUT", f"/api/projects/{pid}/params", {"json": {"overrides": {"flow": "x"}}}, "flow"),
        ("PUT", f"/api/projects/{pid}/params", {"json": {"overrides": {"depth.onnx_input_size": None}}},
         "onnx_input_size"),
        ("POST", "/api/chair/playback", {"json": {"project_id": pid, "state": "play", "position_s": 1e308}},
         "position_s"),
        ("POST", "/api/projects", {"files": {"video": ("film.mp4", b"\0" * 70000, "video/mp4")}}, "file"),
    ]


def test_malformed_requests_are_one_sentence_4xx_and_change_nothing(client, root, project):
    before = snapshot(client, root, project["id"])
    params = client.get(f"/api/projects/{project['id']}").json()["params"]
    for method, path, kwargs, word in malformed(project["id"], project["revision"]):
        r = client.request(method, path, **kwargs)
        assert 400 <= r.status_code < 500, (method, path, word, r.status_code, r.text[:300])
        detail = r.json()["detail"]
        assert isinstance(detail, str) and word in detail and "\n" not in detail, (word, detail)
        assert str(root) not in detail and "/tmp" not in detail and "65536" not in detail, detail
    assert snapshot(client, root, project["id"]) == before
    assert client.get(f"/api/projects/{project['id']}").json()["params"] == params
