"""Generation jobs through the API: queueing, cancel, delete while running, server restart, crash recovery.

A 3-minute noise recording keeps a job busy for seconds, so it is certainly running when the test
acts (each test waits for its first progress event); the short real clip is used for the rest.
"""

from __future__ import annotations

import json
import shutil
import wave
from pathlib import Path

import numpy as np
import pytest

from autohaptics import media
from autohaptics.server.app import create_app
from autohaptics.server.settings import Settings
from autohaptics.server.store import Store

from shared_data import shared_clip
from service_client import LocalClient

CLIP = "bbb_1s_1280x720_vp8_vorbis.webm"
TERMINAL = ("done", "failed", "cancelled")


@pytest.fixture(scope="module")
def long_wav(tmp_path_factory) -> Path:
    path = tmp_path_factory.mktemp("media") / "noise_3min.wav"
    rng = np.random.default_rng(0)
    rate = 16_000
    with wave.open(str(path), "wb") as w:
        w.setnchannels(1)
        w.setsampwidth(2)
        w.setframerate(rate)
        w.writeframes((rng.standard_normal(180 * rate) * 3000).astype("<i2").tobytes())
    return path


def settings(data_dir: Path, **kw) -> Settings:
    return Settings(data_dir=data_dir, frontend_dir=None, **kw)


def upload(client: LocalClient, path: Path, **fields) -> dict:
    r = client.post("/api/projects", files={"file": (path.name, path.read_bytes())},
                    data={k: str(v) for k, v in fields.items()})
    assert r.status_code == 201, r.text
    return r.json()


def read_events(lines, *, stage: str | None = None) -> list[tuple[str, dict]]:
    """SSE events from an iterator of lines, up to the terminal event or the first progress of ``stage``."""
    out, event = [], None
    for line in lines:
        if line.startswith("event: "):
            event = line[7:]
        elif line.startswith("data: "):
            data = json.loads(line[6:])
            out.append((event, data))
            if event in TERMINAL or (event == "progress" and data["stage"] == stage):
                break
    return out


def sse(client: LocalClient, job_id: str, *, stage: str | None = None) -> list[tuple[str, dict]]:
    """Events of a job's stream up to its terminal event, or the first progress event of ``stage``."""
    with client.stream("GET", f"/api/jobs/{job_id}/events") as resp:
        assert resp.status_code == 200, resp.read()
        return read_events(resp.iter_lines(), stage=stage)


def wait_running(client: LocalClient, job_id: str) -> None:
    """Block until the job reports analysis progress (the worker is inside the pipeline)."""
    events = sse(client, job_id, stage="audio")
    assert events[-1][0] == "progress" and events[-1][1]["progress"] < 1.0, events
    assert client.get(f"/api/jobs/{job_id}").json()["status"] == "running"


def tree(path: Path) -> dict[str, tuple[int, int]]:
    return {str(p.relative_to(path)): (p.stat().st_size, p.stat().st_mtime_ns)
            for p in sorted(path.rglob("*")) if p.is_file()}


def test_queue_cancel_and_conflicts(tmp_path, long_wav):
    with LocalClient(create_app(settings(tmp_path / "data", jobs=1))) as client:
        long_p = upload(client, long_wav)
        short_p = upload(client, shared_clip(CLIP))
        wait_running(client, long_p["job"]["id"])
        # One worker: the second job waits in the queue.
        assert client.get(f"/api/jobs/{short_p['job']['id']}").json()["status"] == "queued"
        r = client.post(f"/api/projects/{long_p['id']}/generate", json={})
        assert r.status_code == 409 and "already running" in r.json()["detail"]
        r = client.put(f"/api/projects/{long_p['id']}/params", json={"overrides": {"lfe_gain_db": 3}})
        assert r.status_code == 409

        # Cancelling the queued job ends it at once; the running one stops at its next check.
        assert client.post(f"/api/jobs/{short_p['job']['id']}/cancel").status_code == 202
        assert sse(client, short_p["job"]["id"])[-1][0] == "cancelled"
        r = client.post(f"/api/jobs/{long_p['job']['id']}/cancel")
        assert r.status_code == 202 and r.json()["id"] == long_p["job"]["id"]
        final = sse(client, long_p["job"]["id"])[-1]
        assert final[0] == "cancelled" and final[1]["status"] == "cancelled" and final[1]["error"] is None
        assert client.post(f"/api/jobs/{long_p['job']['id']}/cancel").status_code == 409
        for p in (long_p, short_p):
            project = client.get(f"/api/projects/{p['id']}").json()
            assert project["status"] == "cancelled" and not project["has_timeline"]
            assert client.get(f"/api/projects/{p['id']}/timeline").status_code == 404
        assert list((tmp_path / "data" / "work").iterdir()) == []

        # The pool is still fine: the short project can be generated now.
        job = client.post(f"/api/projects/{short_p['id']}/generate").json()["job"]
        assert sse(client, job["id"])[-1][0] == "done"


def test_delete_while_running_touches_nothing_else(tmp_path, long_wav):
    data = tmp_path / "data"
    with LocalClient(create_app(settings(data))) as client:
        other = upload(client, shared_clip(CLIP))
        assert sse(client, other["job"]["id"])[-1][0] == "done"
        op = {"op": "set", "lanes": ["A7"], "t0": 1, "t1": 4, "value": 0.6}
        assert client.post(f"/api/projects/{other['id']}/edits", json={"base_revision": 1, "op": op}).status_code == 200
        other_dir = data / "projects" / other["id"]
        other_files = tree(other_dir)
        other_state = (client.get(f"/api/projects/{other['id']}").json(),
                       client.get(f"/api/projects/{other['id']}/timeline").content)

        doomed = upload(client, long_wav)
        job_id = doomed["job"]["id"]
        # Follow the job's stream across the deletion: it ends with "cancelled".
        with client.stream("GET", f"/api/jobs/{job_id}/events") as resp:
            lines = resp.iter_lines()
            events = read_events(lines, stage="audio")
            assert events[-1][0] == "progress" and events[-1][1]["stage"] == "audio"
            assert client.delete(f"/api/projects/{doomed['id']}").status_code == 204
            assert not (data / "projects" / doomed["id"]).exists()
            assert client.get(f"/api/projects/{doomed['id']}").status_code == 404
            assert client.post(f"/api/projects/{doomed['id']}/generate").status_code == 404
            final = read_events(lines)[-1]
        assert final[0] == "cancelled" and final[1]["id"] == job_id
        assert client.get(f"/api/jobs/{job_id}").status_code == 404

        assert tree(other_dir) == other_files
        assert (client.get(f"/api/projects/{other['id']}").json(),
                client.get(f"/api/projects/{other['id']}/timeline").content) == other_state
        assert sorted(p.name for p in (data / "projects").iterdir()) == [other["id"]]
        assert list((data / "work").iterdir()) == [] and list((data / "uploads").iterdir()) == []
        # The runner survived: the other project generates again.
        job = client.post(f"/api/projects/{other['id']}/generate").json()["job"]
        assert sse(client, job["id"])[-1][0] == "done"


@pytest.mark.slow
def test_restart_while_running_resumes_the_job(tmp_path, long_wav):
    data = tmp_path / "data"
    quiet = {"loudness": 0.9, "sharpness": 0.9, "booming": 0.9, "low_energy": 0.9}
    with LocalClient(create_app(settings(data))) as client:
        short = upload(client, shared_clip(CLIP))
        assert sse(client, short["job"]["id"])[-1][0] == "done"
        project = upload(client, long_wav)
        wait_running(client, project["job"]["id"])
        assert client.put(f"/api/projects/{project['id']}/params", json={"thresholds": quiet}).status_code == 202
    # The server stopped while the job ran; a new one starts on the same data folder and runs the
    # interrupted first generate again, from the start, with the designer's latest parameters.
    with LocalClient(create_app(settings(data))) as client:
        job = client.get(f"/api/jobs/{project['job']['id']}").json()
        assert job["status"] in ("queued", "running") and job["error"] is None and job["progress"] < 0.5
        assert client.get(f"/api/projects/{project['id']}").json()["status"] == "running"
        assert sse(client, job["id"])[-1][0] == "done"
        p = client.get(f"/api/projects/{project['id']}").json()
        assert p["status"] == "ready" and p["has_timeline"] and p["params"]["thresholds"] == quiet
        # Nothing else was lost.
        assert client.get(f"/api/projects/{short['id']}").json()["status"] == "ready"
        assert client.get(f"/api/projects/{short['id']}/timeline").status_code == 200
        assert list((data / "work").iterdir()) == []
        rerun = client.post(f"/api/projects/{project['id']}/generate")
        assert rerun.status_code == 202
        rerun_id = rerun.json()["job"]["id"]
        wait_running(client, rerun_id)
        # New thresholds while the analysis runs: derived now from the cache, and with them when the job ends.
        off = {"loudness": 1.0, "sharpness": 1.0, "booming": 1.0, "low_energy": 1.0}
        r = client.put(f"/api/projects/{project['id']}/params", json={"thresholds": off})
        assert r.status_code == 200 and r.json()["job"] is None and r.json()["derived"] is True
        assert sse(client, rerun_id)[-1][0] == "done"
        p = client.get(f"/api/projects/{project['id']}").json()
        assert p["status"] == "ready" and p["n_ticks"] == 1800 and p["params"]["thresholds"] == off
        doc = client.get(f"/api/projects/{project['id']}/timeline").json()
        assert doc["generator"]["params"]["thresholds"] == off and np.asarray(doc["tracks"]["vibration"]).max() == 0
        before = client.get(f"/api/projects/{project['id']}/timeline").content
        assert json.loads(before)["n_ticks"] == 1800
        # A cancelled regeneration keeps the previous timeline (and its revision).
        job = client.post(f"/api/projects/{project['id']}/generate", json={"thresholds": {"loudness": 0.5}}).json()["job"]
        wait_running(client, job["id"])
        assert client.post(f"/api/jobs/{job['id']}/cancel").status_code == 202
        assert sse(client, job["id"])[-1][0] == "cancelled"
        after = client.get(f"/api/projects/{project['id']}").json()
        assert after["status"] == "ready" and after["job"]["status"] == "cancelled"  # the cancelled attempt: a note
        assert after["has_timeline"] and after["revision"] == p["revision"]
        assert after["params"] == p["params"], "the parameters of the timeline on show, not the cancelled attempt's"
        assert client.get(f"/api/projects/{project['id']}/timeline").content == before


def test_a_crash_leaves_jobs_that_the_next_start_resumes(tmp_path):
    """A server killed hard never records its jobs' end; the next start runs them again."""
    data = tmp_path / "data"
    store = Store(data)
    clip = tmp_path / "clip.part"
    shutil.copy(shared_clip(CLIP), clip)
    info = media.probe(clip)
    project = store.create_project(clip, media_file="a" * 32 + ".webm", media_type="video/webm", name="crash",
                                   source=info.source_block(name="crash"),
                                   params={"preset": "balanced", "mode": "audio", "thresholds": {}, "overrides": {}},
                                   n_ticks=10, duration_s=info.duration_s)
    job = store.create_job(project["id"], project["params"])
    store.job_started(job["id"], "2024-01-01T00:00:00.000Z")
    (store.job_work_dir(job["id"]) / "analysis.npz").write_bytes(b"half written")
    (store.uploads_dir / "deadbeef.part").write_bytes(b"half an upload")
    store.close()

    with LocalClient(create_app(settings(data))) as client:
        assert list((data / "uploads").iterdir()) == []
        assert client.get(f"/api/projects/{project['id']}").json()["status"] in ("running", "ready")
        assert sse(client, job["id"])[-1][0] == "done"
        j = client.get(f"/api/jobs/{job['id']}").json()
        assert j["status"] == "done" and j["error"] is None and j["started_at"] != "2024-01-01T00:00:00.000Z"
        assert client.get(f"/api/projects/{project['id']}").json()["status"] == "ready"
        assert list((data / "work").iterdir()) == []
        rerun = client.post(f"/api/projects/{project['id']}/generate").json()["job"]
        assert sse(client, rerun["id"])[-1][0] == "done"
