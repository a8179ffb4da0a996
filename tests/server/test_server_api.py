"""The editor's HTTP API end to end (docs/API.md): a real clip, the real process pool, a temporary data folder.

One application serves the tests of this module (starting the pool and its first worker costs
seconds); each test makes its own projects.
"""

from __future__ import annotations

import csv
import io
import json
from pathlib import Path

import numpy as np
import pytest

from autohaptics.server.app import create_app
from autohaptics.timeline.wire import decode
from autohaptics.server.settings import Settings
from autohaptics.timeline import Timeline

from shared_data import shared_clip
from service_client import LocalClient

CLIP = "bbb_1s_1280x720_vp8_vorbis.webm"
TERMINAL = ("done", "failed", "cancelled")


def events_until_end(client: LocalClient, job_id: str) -> list[tuple[str, dict]]:
    """Read the job's SSE stream to its terminal event."""
    out: list[tuple[str, dict]] = []
    event = None
    with client.stream("GET", f"/api/jobs/{job_id}/events") as resp:
        assert resp.status_code == 200
        assert resp.headers["content-type"].startswith("text/event-stream")
        for line in resp.iter_lines():
            if line.startswith("event: "):
                event = line[len("event: "):]
            elif line.startswith("data: "):
                out.append((event, json.loads(line[len("data: "):])))
                if event in TERMINAL:
                    break
    return out


def upload(client: LocalClient, path: Path, *, filename: str | None = None, **fields) -> dict:
    resp = client.post("/api/projects", files={"file": (filename or path.name, path.read_bytes(), "video/webm")},
                       data={k: str(v) for k, v in fields.items()})
    assert resp.status_code == 201, resp.text
    return resp.json()


def ready_project(client: LocalClient, **fields) -> dict:
    project = upload(client, shared_clip(CLIP), **fields)
    assert events_until_end(client, project["job"]["id"])[-1][0] == "done"
    return client.get(f"/api/projects/{project['id']}").json()


@pytest.fixture(scope="module")
def data_dir(tmp_path_factory) -> Path:
    return tmp_path_factory.mktemp("server-api") / "data"


@pytest.fixture(scope="module")
def client(data_dir):
    with LocalClient(create_app(Settings(data_dir=data_dir, frontend_dir=None))) as c:
        yield c


def test_upload_job_progress_timeline_and_binary(client, data_dir):
    clip = shared_clip(CLIP)
    # the thesis's rule: the default finds no event in one second of a score under way (nothing vibrates)
    project = upload(client, clip, preset="thesis")
    assert project["status"] == "running" and project["job"]["status"] in ("queued", "running")
    assert project["name"] == CLIP and project["n_ticks"] == 10 and project["media_type"] == "video/webm"
    assert project["source"]["video"]["width"] == 1280 and not project["has_timeline"]

    events = events_until_end(client, project["job"]["id"])
    names = [e for e, _ in events]
    assert names[-1] == "done" and set(names[:-1]) == {"progress"}
    fractions = [d["progress"] for e, d in events if e == "progress"]
    assert fractions == sorted(fractions) and fractions[-1] == 1.0
    job = events[-1][1]
    assert job["status"] == "done" and job["progress"] == 1.0 and job["error"] is None
    assert job["started_at"] and job["finished_at"]
    assert client.get(f"/api/jobs/{job['id']}").json()["status"] == "done"

    pid = project["id"]
    project = client.get(f"/api/projects/{pid}").json()
    assert project["status"] == "ready" and project["has_timeline"] and project["revision"] == 1
    resp = client.get(f"/api/projects/{pid}/timeline")
    assert resp.status_code == 200
    doc = resp.json()
    tl = Timeline.from_dict(doc)
    assert tl.n_ticks == 10 and doc["edits"] == [] and doc["markers"] == [] and doc["revision"] == 1
    assert doc["source"]["name"] == CLIP and doc["generator"]["params"]["thresholds"]["loudness"] == 0.85
    assert float(tl.vibration.max()) > 0  # the clip's sound is loud throughout

    header, blocks = decode(client.get(f"/api/projects/{pid}/timeline.bin").content)
    assert header["n_ticks"] == 10 and header["revision"] == 1
    np.testing.assert_allclose(blocks["vibration"], tl.vibration, atol=0.5 / 255 + 1e-4)
    np.testing.assert_allclose(blocks["fans"], tl.fans, atol=0.5 / 255 + 1e-4)
    np.testing.assert_allclose(blocks["temperature_c"], tl.temperature_c, atol=1e-4)
    for name, values in tl.features.items():
        np.testing.assert_allclose(blocks[f"features.{name}"], values, atol=0.5 / 255 + 1e-4)
    # The job left its feature cache and generated timeline in the project, nothing in work/.
    pdir = data_dir / "projects" / pid
    assert (pdir / "analysis.npz").is_file() and (pdir / "generated.npz").is_file()
    assert list((data_dir / "work").iterdir()) == []
    assert pid in [p["id"] for p in client.get("/api/projects").json()]


def test_media_is_served_with_ranges(client):
    clip = shared_clip(CLIP)
    data = clip.read_bytes()
    size = len(data)
    pid = upload(client, clip, generate="false")["id"]
    url = f"/api/projects/{pid}/media"
    full = client.get(url)
    assert full.status_code == 200 and full.content == data
    assert full.headers["accept-ranges"] == "bytes" and full.headers["content-type"] == "video/webm"
    for rng, (a, b) in [("bytes=0-99", (0, 100)), ("bytes=5000-5999", (5000, 6000)), (f"bytes=-500", (size - 500, size)),
                        ("bytes=80000-", (80000, size)), ("bytes=100-199", (100, 200))]:
        part = client.get(url, headers={"Range": rng})
        assert part.status_code == 206, rng
        assert part.content == data[a:b]
        assert part.headers["content-range"] == f"bytes {a}-{b - 1}/{size}"
        assert int(part.headers["content-length"]) == b - a
    bad = client.get(url, headers={"Range": f"bytes={size}-{size + 10}"})
    assert bad.status_code == 416 and bad.headers["content-range"] == f"bytes */{size}"
    assert client.get(f"/api/projects/{'0' * 32}/media").status_code == 404


def test_edit_undo_redo_reload_and_regenerate_keep_edits(client, data_dir):
    project = ready_project(client, preset="thesis")  # a generated layer that vibrates (above)
    pid, rev = project["id"], project["revision"]
    set_op = {"op": "set", "lanes": ["A4"], "t0": 2, "t1": 6, "value": 0.9}
    r = client.post(f"/api/projects/{pid}/edits", json={"base_revision": rev, "op": set_op})
    assert r.status_code == 200, r.text
    assert r.json() == {"revision": rev + 1, "cursor": 1, "op": set_op, "markers": []}
    # Two editors sent an edit based on the same revision: the second one is refused.
    stale = client.post(f"/api/projects/{pid}/edits", json={"base_revision": rev, "op": set_op})
    assert stale.status_code == 409 and "revision" in stale.json()["detail"]
    marker = {"op": "marker_add", "marker": {"id": "m1", "t_s": 0.3, "label": "door"}}
    r = client.post(f"/api/projects/{pid}/edits", json={"base_revision": rev + 1, "op": marker})
    assert r.status_code == 200 and r.json()["markers"] == [{"id": "m1", "t_s": 0.3, "label": "door"}]

    undo = client.post(f"/api/projects/{pid}/undo", json={"base_revision": rev + 2})
    assert undo.json() == {"revision": rev + 3, "cursor": 1, "markers": [], "params": None, "job": None}
    assert client.get(f"/api/projects/{pid}/timeline").json()["markers"] == []
    assert client.post(f"/api/projects/{pid}/undo", json={"base_revision": rev}).status_code == 409
    redo = client.post(f"/api/projects/{pid}/redo", json={"base_revision": rev + 3})
    assert redo.json() == {"revision": rev + 4, "cursor": 2, "markers": [{"id": "m1", "t_s": 0.3, "label": "door"}],
                           "params": None, "job": None}
    assert client.post(f"/api/projects/{pid}/redo", json={"base_revision": rev + 4}).json()["detail"] == \
        "nothing to redo"
    edits = client.get(f"/api/projects/{pid}/edits").json()
    assert edits == {"revision": rev + 4, "cursor": 2, "ops": [set_op, marker],
                     "markers": [{"id": "m1", "t_s": 0.3, "label": "door"}]}

    # A new server on the same data folder sees the same history and composition.
    with LocalClient(create_app(Settings(data_dir=data_dir, frontend_dir=None))) as other:
        doc = other.get(f"/api/projects/{pid}/timeline").json()
        assert other.get(f"/api/projects/{pid}/edits").json() == edits
    vib = np.asarray(doc["tracks"]["vibration"])
    np.testing.assert_allclose(vib[2:6, 3], 0.9)
    assert doc["markers"] == [{"id": "m1", "t_s": 0.3, "label": "door"}] and doc["edits"] == [set_op, marker]

    # Regenerate with other thresholds: a new generated layer, the manual edit still on top, and the
    # change one more (undoable) step of the history.
    before = decode(client.get(f"/api/projects/{pid}/timeline.bin?layer=generated").content)[1]["vibration"]
    off = {"loudness": 1.0, "sharpness": 1.0, "booming": 1.0, "low_energy": 1.0}  # 1 disables a feature
    job = client.post(f"/api/projects/{pid}/generate", json={"thresholds": off})
    assert job.status_code == 202
    assert events_until_end(client, job.json()["job"]["id"])[-1][0] == "done"
    after = client.get(f"/api/projects/{pid}").json()
    assert after["params"]["thresholds"] == off and after["cursor"] == 3
    assert client.get(f"/api/projects/{pid}/edits").json()["ops"][2] == {
        "op": "params", "from": project["params"], "to": after["params"]}
    generated = decode(client.get(f"/api/projects/{pid}/timeline.bin?layer=generated").content)[1]["vibration"]
    assert before.max() > 0 and generated.max() == 0
    doc = client.get(f"/api/projects/{pid}/timeline").json()
    assert doc["generator"]["params"]["thresholds"] == off
    vib = np.asarray(doc["tracks"]["vibration"])
    np.testing.assert_allclose(vib[2:6, 3], 0.9)
    assert doc["markers"][0]["id"] == "m1"


def test_params_rederive_from_the_cache_keeps_edits(client):
    project = ready_project(client)
    pid, rev = project["id"], project["revision"]
    op = {"op": "clear", "lanes": ["A1", "A2", "A5"], "t0": 0, "t1": 3}
    assert client.post(f"/api/projects/{pid}/edits", json={"base_revision": rev, "op": op}).status_code == 200
    r = client.put(f"/api/projects/{pid}/params", json={"thresholds": {"loudness": 0.0, "sharpness": 0.0,
                                                                      "booming": 0.0, "low_energy": 0.0}})
    assert r.status_code == 200, r.text
    body = r.json()
    # Re-derived (rev + 2) and recorded as an undoable 'params' op after the edit (rev + 3); the ticks
    # this wakes that the analysis computed no saliency for get it from a job that follows
    assert body["derived"] is True and body["revision"] == rev + 3 and body["cursor"] == 2
    assert 0 < body["seconds"] < 5
    if body["job"] is not None:
        assert events_until_end(client, body["job"]["id"])[-1][0] == "done"
    doc = client.get(f"/api/projects/{pid}/timeline").json()
    vib = np.asarray(doc["tracks"]["vibration"])
    assert np.all(vib[:3, [0, 1, 4]] == 0) and vib[3:, 0].max() > 0
    assert doc["generator"]["params"]["thresholds"]["loudness"] == 0.0
    # An analysis parameter needs a new analysis: 202 with a job.
    r = client.put(f"/api/projects/{pid}/params", json={"overrides": {"lfe_gain_db": 0.0}})
    assert r.status_code == 202 and r.json()["derived"] is False
    assert events_until_end(client, r.json()["job"]["id"])[-1][0] == "done"
    assert client.get(f"/api/projects/{pid}").json()["params"]["overrides"] == {"lfe_gain_db": 0.0}
    bad = client.put(f"/api/projects/{pid}/params", json={"thresholds": {"loudness": -1}})
    assert bad.status_code == 400 and "loudness" in bad.json()["detail"]
    bad = client.put(f"/api/projects/{pid}/params", json={"preset": "nonsense"})
    assert bad.status_code == 400 and "preset" in bad.json()["detail"]
    for thresholds in ({"loud\nness": 0.1}, {"loudness\r\n": "x"}):  # a name sent with a line break: one line back
        bad = client.put(f"/api/projects/{pid}/params", json={"thresholds": thresholds})
        assert bad.status_code == 400 and "\n" not in bad.json()["detail"] and "\\n" in bad.json()["detail"]


def test_export_and_import(client):
    project = ready_project(client)
    pid = project["id"]
    exported = client.get(f"/api/projects/{pid}/export?format=csv")
    assert exported.status_code == 200 and exported.headers["content-type"].startswith("text/csv")
    assert exported.headers["content-disposition"].startswith('attachment; filename="bbb_1s_1280x720_vp8_vorbis.csv"')
    rows = list(csv.reader(io.StringIO(exported.text)))
    assert rows[0][:3] == ["time_s", "A1", "A2"] and len(rows) == 11
    js = client.get(f"/api/projects/{pid}/export?format=json")
    assert js.status_code == 200 and Timeline.from_json(js.text).n_ticks == 10
    for fmt in ("ahap", "hjif", "mpegv"):
        assert client.get(f"/api/projects/{pid}/export?format={fmt}").status_code == 200
    assert client.get(f"/api/projects/{pid}/export?format=wav").status_code == 400

    # Import an edited CSV: every motor at 0.25 -> one undoable import op.
    for row in rows[1:]:
        row[1:10] = ["0.2500"] * 9
    text = io.StringIO()
    csv.writer(text, lineterminator="\n").writerows(rows)
    rev = client.get(f"/api/projects/{pid}").json()["revision"]
    r = client.post(f"/api/projects/{pid}/import", files={"file": ("mine.csv", text.getvalue().encode(), "text/csv")},
                    data={"base_revision": str(rev)})
    assert r.status_code == 200, r.text
    assert r.json()["op"]["op"] == "import" and r.json()["revision"] == rev + 1
    vib = np.asarray(client.get(f"/api/projects/{pid}/timeline").json()["tracks"]["vibration"])
    np.testing.assert_allclose(vib, 0.25)
    undo = client.post(f"/api/projects/{pid}/undo", json={"base_revision": rev + 1})
    assert undo.status_code == 200
    assert not np.allclose(np.asarray(client.get(f"/api/projects/{pid}/timeline").json()["tracks"]["vibration"]),
                           0.25)
    rows[3][2] = "1.7"
    text = io.StringIO()
    csv.writer(text, lineterminator="\n").writerows(rows)
    bad = client.post(f"/api/projects/{pid}/import", files={"file": ("bad.csv", text.getvalue().encode(), "text/csv")})
    assert bad.status_code == 400
    assert bad.json()["problems"][0]["row"] == 3 and bad.json()["problems"][0]["column"] == "A2"
    stale = client.post(f"/api/projects/{pid}/import", files={"file": ("x.json", js.content, "application/json")},
                        data={"base_revision": "0"})
    assert stale.status_code == 409


def test_waveform_peaks(client, data_dir):
    project = upload(client, shared_clip(CLIP), generate="false")
    r = client.get(f"/api/projects/{project['id']}/waveform?points=50")
    assert r.status_code == 200
    w = r.json()
    assert w["points"] == 50 and w["has_audio"] and len(w["min"]) == len(w["max"]) == 50
    lo, hi = np.asarray(w["min"]), np.asarray(w["max"])
    assert np.all(lo >= -1) and np.all(hi <= 1) and np.all(lo <= hi) and hi.max() > 0.01 and lo.min() < -0.01
    assert (data_dir / "projects" / project["id"] / "waveform-50.json").is_file()
    assert client.get(f"/api/projects/{project['id']}/waveform?points=50").json() == w
    assert client.get(f"/api/projects/{project['id']}/waveform?points=0").status_code == 400
    assert client.get(f"/api/projects/{project['id']}/waveform?points=10000000").status_code == 400


def test_rename_view_duplicate_delete(client, data_dir):
    project = ready_project(client)
    pid = project["id"]
    op = {"op": "set", "lanes": ["fans"], "t0": 0, "t1": 2, "value": 0.5}
    client.post(f"/api/projects/{pid}/edits", json={"base_revision": project["revision"], "op": op})
    r = client.patch(f"/api/projects/{pid}", json={"name": "  My\x00 film\n/../x  ", "view": {"zoom": 3}})
    assert r.status_code == 200
    assert r.json()["name"] == "My film/../x" and r.json()["view"] == {"zoom": 3}
    assert client.patch(f"/api/projects/{pid}", json={"name": "\x01\x02"}).status_code == 400

    dup = client.post(f"/api/projects/{pid}/duplicate")
    assert dup.status_code == 201
    copy = dup.json()
    assert copy["id"] != pid and copy["name"] == "My film/../x (copy)" and copy["status"] == "ready"
    assert client.get(f"/api/projects/{copy['id']}/edits").json()["ops"] == [op]
    assert client.get(f"/api/projects/{copy['id']}/timeline").json()["tracks"] == \
        client.get(f"/api/projects/{pid}/timeline").json()["tracks"]

    assert client.app.state.pictures.wait_idle(60)  # the job's warm-up made the filmstrip in the background
    original = sorted(p.name for p in (data_dir / "projects" / pid).iterdir())
    assert client.delete(f"/api/projects/{copy['id']}").status_code == 204
    assert not (data_dir / "projects" / copy["id"]).exists()
    assert sorted(p.name for p in (data_dir / "projects" / pid).iterdir()) == original
    assert client.get(f"/api/projects/{pid}/timeline").status_code == 200
    assert client.get(f"/api/projects/{copy['id']}").status_code == 404
    assert client.delete(f"/api/projects/{copy['id']}").status_code == 404


def test_health_config_openapi(client):
    assert client.get("/health").json() == {"status": "ok", "version": "0.1.0"}
    cfg = client.get("/api/config").json()
    assert "balanced" in cfg["presets"] and "audio" in cfg["modes"]
    assert cfg["lanes"][:2] == ["A1", "A2"] and cfg["lanes"][-2:] == ["temperature", "fans"]
    assert cfg["layout"]["fans"] == {"rows": 9, "cols": 17} and len(cfg["layout"]["actuators"]) == 9
    assert cfg["default_thresholds"]["loudness"] == 0.85 and cfg["upload_limit_bytes"] == 4 * 1024 ** 3
    assert {f["name"] for f in cfg["export_formats"]} >= {"json", "csv"}
    paths = client.get("/openapi.json").json()["paths"]
    for path in ("/api/projects", "/api/projects/{project_id}/edits", "/api/jobs/{job_id}/events",
                 "/api/projects/{project_id}/timeline.bin", "/api/projects/{project_id}/import"):
        assert path in paths
    assert "multipart/form-data" in paths["/api/projects"]["post"]["requestBody"]["content"]
    assert client.get("/docs").status_code == 200


def test_frontend_is_served_without_stale_caches(tmp_path):
    front = tmp_path / "frontend"
    (front / "src").mkdir(parents=True)
    (front / "index.html").write_text("<!doctype html><head><title>editor</title></head><body></body>")
    (front / "src" / "app.js").write_text("export const x = 1;")
    (front / "src" / "data").mkdir()
    (front / "src" / "data" / "api.js").write_text("export const y = 2;")
    (front / "logo.png").write_bytes(b"\x89PNG")
    app = create_app(Settings(data_dir=tmp_path / "data", frontend_dir=front, jobs=1))
    with LocalClient(app) as c:
        index = c.get("/")
        assert index.status_code == 200 and "editor" in index.text
        assert index.headers["cache-control"] == "no-cache"
        # every module named up front, so a cold open fetches them at once, not level by level (added
        # by a script: the preload scanner would request links in the markup before the early requests)
        assert '<script>["src/app.js", "src/data/api.js"].forEach(' in index.text
        assert 'link.rel = "modulepreload"' in index.text and index.text.index("forEach(") < index.text.index("</head>")
        (front / "src" / "app.js").write_text("export const x = 3;")
        assert c.get("/src/app.js").text == "export const x = 3;"  # a changed file is served changed
        js = c.get("/src/app.js")
        assert js.status_code == 200 and js.headers["cache-control"] == "no-cache"
        assert "javascript" in js.headers["content-type"]
        assert "cache-control" not in c.get("/logo.png").headers
        assert c.get("/health").json()["status"] == "ok"
        assert c.get("/../settings.py").status_code == 404


def test_dependencies_can_be_swapped(client, data_dir):
    """Routes take their settings through ``get_settings``: a test can swap them (a tiny upload limit)."""
    from autohaptics.server.deps import get_settings

    small = Settings(data_dir=data_dir, frontend_dir=None, max_upload_bytes=1000)
    client.app.dependency_overrides[get_settings] = lambda: small
    try:
        assert client.get("/api/config").json()["upload_limit_bytes"] == 1000
        before = sorted(p.name for p in (data_dir / "projects").iterdir())
        r = client.post("/api/projects", files={"file": (CLIP, shared_clip(CLIP).read_bytes(), "video/webm")})
        assert r.status_code == 413 and "limit of 1000 bytes" in r.json()["detail"]
        assert sorted(p.name for p in (data_dir / "projects").iterdir()) == before
        assert list((data_dir / "uploads").iterdir()) == []
    finally:
        client.app.dependency_overrides.clear()
    assert client.get("/api/config").json()["upload_limit_bytes"] == 4 * 1024 ** 3
