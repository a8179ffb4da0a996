"""Learned styles through the HTTP API (docs/API.md "Styles"): learn from a project's edits, list,
get, download, import, delete; a project's parameters name their style (upload, PUT params,
Regenerate, a threshold change keep it; undo and redo of a style choice); bad input is 400 with one
sentence and stores nothing, unknown ids 404. Two small synthetic films, the real process pool.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from autohaptics.server.app import create_app
from autohaptics.server.settings import Settings
from autohaptics.style import from_dict
from autohaptics.testing import scenes, write_scene
from autohaptics.timeline.wire import decode

from service_client import LocalClient

VIBRATION = [f"A{i}" for i in range(1, 10)]


@pytest.fixture(scope="module")
def root(tmp_path_factory) -> Path:
    return tmp_path_factory.mktemp("server-styles")


@pytest.fixture(scope="module")
def client(root):
    with LocalClient(create_app(Settings(data_dir=root / "data", frontend_dir=None))) as c:
        yield c


@pytest.fixture(scope="module")
def films(root) -> dict[str, Path]:
    return {"sample": write_scene(root / "sample.mp4", scenes.sample_scene(8.0), width=96, height=54, fps=10,
                                  quality="low"),
            "boom": write_scene(root / "boom.mp4", scenes.left_boom_right_hum_scene(), width=96, height=54,
                                fps=10, quality="low")}


def wait(client, job: dict) -> None:
    assert client.finished_job(job["id"])["status"] == "done"


def upload(client, film: Path, **fields) -> dict:
    r = client.post("/api/projects", files={"file": (film.name, film.read_bytes(), "video/mp4")},
                    data={k: str(v) for k, v in fields.items()})
    assert r.status_code == 201, r.text
    if r.json()["job"] is not None:
        wait(client, r.json()["job"])
    return client.get(f"/api/projects/{r.json()['id']}").json()


def vibration(client, pid: str, layer: str = "composed") -> np.ndarray:
    r = client.get(f"/api/projects/{pid}/timeline.bin", params={"layer": layer})
    assert r.status_code == 200, r.text
    return decode(r.content)[1]["vibration"]


@pytest.fixture(scope="module")
def edited(client, films) -> dict:
    """A project whose designer halved every actuator and warmed the heater by 2 C."""
    project = upload(client, films["sample"])
    rev = project["revision"]
    for op in ({"op": "scale", "lanes": VIBRATION, "t0": 0, "t1": project["n_ticks"], "factor": 0.5},):
        r = client.post(f"/api/projects/{project['id']}/edits", json={"base_revision": rev, "op": op})
        assert r.status_code == 200, r.text
        rev = r.json()["revision"]
    return client.get(f"/api/projects/{project['id']}").json()


@pytest.fixture(scope="module")
def halved(client, edited) -> dict:
    r = client.post("/api/styles", json={"name": "half", "project_ids": [edited["id"]]})
    assert r.status_code == 201, r.text
    return r.json()


def stored_files(root: Path) -> list[str]:
    folder = root / "data" / "styles"
    return sorted(p.name for p in folder.iterdir()) if folder.is_dir() else []


def test_a_dry_run_reports_and_stores_nothing(client, edited, root):
    before, files = client.get("/api/styles").json(), stored_files(root)
    r = client.post("/api/styles", json={"name": "preview", "project_ids": [edited["id"]], "dry_run": True})
    assert r.status_code == 200, r.text
    out = r.json()
    assert out["id"] is None and out["name"] == "preview" and out["films"][0]["project_id"] == edited["id"]
    film = out["report"][0]
    assert film["explained"] > 0.8, film  # a halving is a tone curve: the style explains it
    assert film["styled"]["vibration_mae"] < film["plain"]["vibration_mae"]
    assert client.get("/api/styles").json() == before and stored_files(root) == files


def test_learn_get_list_download_and_delete(client, edited, root):
    r = client.post("/api/styles", json={"name": "  warm half  ", "project_ids": [edited["id"]]})
    assert r.status_code == 201, r.text
    style = r.json()
    assert style["name"] == "warm half" and len(style["id"]) == 32
    curve = style["document"]["vibration"]["A5"]
    assert curve[-1] == pytest.approx(0.5, abs=0.05)  # full level -> half
    assert [s["id"] for s in client.get("/api/styles").json()].count(style["id"]) == 1
    assert (root / "data" / "styles" / f"{style['id']}.json").is_file()
    got = client.get(f"/api/styles/{style['id']}").json()
    assert got["document"] == style["document"] and got["report"] == style["report"]
    down = client.get(f"/api/styles/{style['id']}/download")
    assert down.status_code == 200 and "attachment" in down.headers["content-disposition"]
    assert "warm half.style.json" in down.headers["content-disposition"]
    assert from_dict(json.loads(down.content)).to_dict() == style["document"]
    assert client.delete(f"/api/styles/{style['id']}").status_code == 204
    assert client.get(f"/api/styles/{style['id']}").status_code == 404
    assert style["id"] not in [s["id"] for s in client.get("/api/styles").json()]
    assert not (root / "data" / "styles" / f"{style['id']}.json").exists()


def test_import_a_style_file(client, halved):
    data = client.get(f"/api/styles/{halved['id']}/download").content
    doc = json.loads(data)
    doc["name"] = ""
    r = client.post("/api/styles/import", files={"file": ("house.style.json", json.dumps(doc).encode(), "application/json")})
    assert r.status_code == 201, r.text
    out = r.json()
    assert out["name"] == "house" and out["id"] != halved["id"] and out["report"] == [] and out["films"] == []
    assert out["document"]["vibration"] == halved["document"]["vibration"]
    assert client.delete(f"/api/styles/{out['id']}").status_code == 204
    doc["name"] = "line\nbreak\u202e" + "x" * 300
    r = client.post("/api/styles/import", files={"file": ("a.json", json.dumps(doc).encode(), "application/json")})
    assert r.status_code == 201 and r.json()["name"] == "linebreak" + "x" * 191, r.text
    assert r.json()["document"]["name"] == r.json()["name"]
    assert client.delete(f"/api/styles/{r.json()['id']}").status_code == 204


@pytest.mark.parametrize("content,field", [
    (b"{not json", "not JSON"),
    (b'{"format": "autohaptics.style", "version": 3}', "version"),
    (b'{"format": "autohaptics.style", "version": 1, "colour": 3}', "'colour'"),
    (b'{"format": "autohaptics.style", "version": 1, "threshold_scale": 9}', "threshold_scale"),
    (b'{"format": "autohaptics.style", "version": 1, "fans": [0, 1]}', "fans"),
    (b'{"format": "autohaptics.style", "version": 1, "overrides": {"video.stride": 2}}', "video.stride"),
    (b'{"format": "autohaptics.style", "version": 1, "temperature": {"offset_c": 1e400}}', "temperature"),
    (b"[1, 2]", "JSON object"),
    (b"\xff\xfe", "not JSON"),
])
def test_a_bad_style_file_is_400_naming_the_field_and_stores_nothing(client, root, content, field):
    before, files = client.get("/api/styles").json(), stored_files(root)
    r = client.post("/api/styles/import", files={"file": ("bad.json", content, "application/json")})
    assert r.status_code == 400, r.text
    detail = r.json()["detail"]
    assert field in detail and "\n" not in detail and str(root) not in detail, detail
    assert client.get("/api/styles").json() == before and stored_files(root) == files


def test_a_style_file_over_the_limit_is_413(client, root):
    files = stored_files(root)
    r = client.post("/api/styles/import", files={"file": ("big.json", b" " * (1024 * 1024 + 1), "application/json")})
    assert r.status_code == 413 and stored_files(root) == files


@pytest.mark.parametrize("body,status,words", [
    ({"name": "x", "project_ids": ["0" * 32]}, 404, "no project"),
    ({"name": "x", "project_ids": ["../../etc"]}, 404, "no project"),
    ({"name": "x", "project_ids": []}, 400, "project_ids"),
    ({"name": "   ", "project_ids": ["0" * 32]}, 400, "name"),
    ({"name": "x"}, 400, "project_ids"),
    ({"name": "x", "project_ids": ["0" * 32], "colour": 1}, 400, "colour"),
    ({"name": "x", "project_ids": ["0" * 32], "dry_run": "maybe"}, 400, "dry_run"),
])
def test_bad_learn_requests(client, root, body, status, words):
    files = stored_files(root)
    r = client.post("/api/styles", json=body)
    assert r.status_code == status, r.text
    assert words in r.json()["detail"] and stored_files(root) == files


def test_learning_needs_a_timeline_and_the_same_parameters(client, films, edited):
    bare = upload(client, films["boom"], generate="false")
    r = client.post("/api/styles", json={"name": "x", "project_ids": [bare["id"]]})
    assert r.status_code == 409 and "no timeline" in r.json()["detail"]
    r = client.post("/api/styles", json={"name": "x", "project_ids": [edited["id"], edited["id"]]})
    assert r.status_code == 400 and "twice" in r.json()["detail"]
    other = upload(client, films["boom"], mode="audio")
    r = client.post("/api/styles", json={"name": "x", "project_ids": [edited["id"], other["id"]]})
    assert r.status_code == 400 and "different parameters" in r.json()["detail"]
    client.delete(f"/api/projects/{bare['id']}")
    client.delete(f"/api/projects/{other['id']}")


@pytest.mark.parametrize("method,path", [("GET", "/api/styles/{}"), ("GET", "/api/styles/{}/download"),
                                         ("DELETE", "/api/styles/{}")])
@pytest.mark.parametrize("sid", ["0" * 32, "..%2F..%2Fautohaptics", "nope"])
def test_unknown_style_ids_are_404(client, method, path, sid):
    r = client.request(method, path.format(sid))
    assert r.status_code == 404, r.text


def test_upload_in_a_style_changes_only_the_generated_layer_and_its_choice_undoes(client, films, halved):
    plain = upload(client, films["boom"])
    styled = upload(client, films["boom"], style=halved["id"])
    assert styled["params"]["style"]["id"] == halved["id"] and styled["params"]["style"]["name"] == "half"
    assert "style" not in plain["params"]
    base = vibration(client, plain["id"])
    assert base.max() > 0.3
    np.testing.assert_allclose(vibration(client, styled["id"]), base * 0.5, atol=0.03)

    pid = plain["id"]  # choose the style on a project with a designer's edit on top
    rev = client.get(f"/api/projects/{pid}").json()["revision"]
    r = client.post(f"/api/projects/{pid}/edits", json={"base_revision": rev, "op": {
        "op": "set", "lanes": ["A1"], "t0": 0, "t1": 3, "value": 1.0}})
    assert r.status_code == 200, r.text
    mine = vibration(client, pid)
    r = client.put(f"/api/projects/{pid}/params", json={"style": halved["id"]})
    assert r.status_code == 200 and r.json()["derived"], r.text
    params = client.get(f"/api/projects/{pid}").json()["params"]
    assert params["style"]["id"] == halved["id"]
    now = vibration(client, pid)
    np.testing.assert_allclose(now[:3, 0], 1.0, atol=1e-6)  # the designer's edit stays on top
    np.testing.assert_allclose(now[3:], mine[3:] * 0.5, atol=0.03)

    r = client.put(f"/api/projects/{pid}/params", json={"thresholds": {"loudness": 0.4}})  # a threshold change
    assert r.status_code == 200 and client.get(f"/api/projects/{pid}").json()["params"]["style"]["id"] == halved["id"]
    rev = client.get(f"/api/projects/{pid}").json()["revision"]
    r = client.post(f"/api/projects/{pid}/undo", json={"base_revision": rev})  # the threshold again
    assert r.status_code == 200 and r.json()["params"]["style"]["id"] == halved["id"]
    r = client.post(f"/api/projects/{pid}/undo", json={"base_revision": r.json()["revision"]})  # the style choice
    assert r.status_code == 200, r.text
    assert "style" not in r.json()["params"]
    assert "style" not in client.get(f"/api/projects/{pid}").json()["params"]
    np.testing.assert_allclose(vibration(client, pid), mine, atol=1e-6)
    r = client.post(f"/api/projects/{pid}/redo", json={"base_revision": r.json()["revision"]})
    assert r.status_code == 200 and r.json()["params"]["style"]["id"] == halved["id"]
    np.testing.assert_allclose(vibration(client, pid), now, atol=1e-6)

    r = client.put(f"/api/projects/{pid}/params", json={"style": None})  # dropping it is a settings change too
    assert r.status_code == 200 and "style" not in client.get(f"/api/projects/{pid}").json()["params"]
    np.testing.assert_allclose(vibration(client, pid), mine, atol=1e-6)
    ops = client.get(f"/api/projects/{pid}/edits").json()["ops"]
    assert [o["op"] for o in ops][-2:] == ["params", "params"]


def test_regenerate_keeps_the_style_and_a_deleted_style_stays_in_its_projects(client, films, edited):
    r = client.post("/api/styles", json={"name": "gone soon", "project_ids": [edited["id"]]})
    sid = r.json()["id"]
    project = upload(client, films["boom"], style=sid)
    assert client.delete(f"/api/styles/{sid}").status_code == 204
    r = client.post(f"/api/projects/{project['id']}/generate", json={"preset": "balanced"})
    assert r.status_code == 202, r.text
    wait(client, r.json()["job"])
    params = client.get(f"/api/projects/{project['id']}").json()["params"]
    assert params["style"]["id"] == sid and params["style"]["name"] == "gone soon"
    plain = upload(client, films["boom"])
    np.testing.assert_allclose(vibration(client, project["id"]), vibration(client, plain["id"]) * 0.5, atol=0.03)


def test_unknown_style_in_params_or_upload_is_404_and_changes_nothing(client, films, edited):
    before = client.get(f"/api/projects/{edited['id']}").json()
    for style in ("0" * 32, "../x"):
        r = client.put(f"/api/projects/{edited['id']}/params", json={"style": style})
        assert r.status_code == 404 and "no style" in r.json()["detail"]
    after = client.get(f"/api/projects/{edited['id']}").json()
    assert after["params"] == before["params"] and after["revision"] == before["revision"]
    r = client.put(f"/api/projects/{edited['id']}/params", json={"style": 5})
    assert r.status_code == 400 and "style" in r.json()["detail"]
    count = len(client.get("/api/projects").json())
    r = client.post("/api/projects", files={"file": ("f.mp4", films["boom"].read_bytes(), "video/mp4")},
                    data={"style": "f" * 32})
    assert r.status_code == 404 and len(client.get("/api/projects").json()) == count


def test_a_foreign_page_cannot_learn_import_or_delete(client, edited, halved):
    foreign = {"origin": "http://evil.example", "sec-fetch-site": "cross-site"}
    count = len(client.get("/api/styles").json())
    r = client.post("/api/styles", json={"name": "x", "project_ids": [edited["id"]]}, headers=foreign)
    assert r.status_code == 403
    r = client.post("/api/styles/import", files={"file": ("a.json", b"{}", "application/json")}, headers=foreign)
    assert r.status_code == 403
    assert client.delete(f"/api/styles/{halved['id']}", headers=foreign).status_code == 403
    assert len(client.get("/api/styles").json()) == count


def test_a_film_without_edits_learns_the_identity_and_explains_nothing(client, films):
    project = upload(client, films["sample"])
    r = client.post("/api/styles", json={"name": "none", "project_ids": [project["id"]], "dry_run": True})
    assert r.status_code == 200, r.text
    assert from_dict(r.json()["document"]).is_identity
    film = r.json()["report"][0]
    assert film["explained"] is None and film["plain"] == film["styled"] and film["plain"]["vibration_mae"] == 0
    client.delete(f"/api/projects/{project['id']}")


def test_a_style_whose_file_went_missing_is_404(client, edited, root):
    r = client.post("/api/styles", json={"name": "lost", "project_ids": [edited["id"]]})
    sid = r.json()["id"]
    (root / "data" / "styles" / f"{sid}.json").unlink()
    r = client.get(f"/api/styles/{sid}")
    assert r.status_code == 404 and "missing" in r.json()["detail"] and str(root) not in r.json()["detail"]
    assert client.delete(f"/api/styles/{sid}").status_code == 204
