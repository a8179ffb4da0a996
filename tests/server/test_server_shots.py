"""GET /api/projects/{id}/shots and the boundary edits (shot_split, shot_merge): boundaries from the
analysis, summaries from the composed timeline; a threshold change or a track edit changes the
summaries, not the boundaries; boundary edits undo, redo and survive a re-derive; bad operations
are 4xx with one sentence and change nothing; a project analysed before shots existed gets them
from its cache."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from autohaptics.server.app import create_app
from autohaptics.server.settings import Settings
from autohaptics.testing import Scene, Segment, Texture, Tone, write_scene
from service_client import LocalClient

N_TICKS = 120


@pytest.fixture(scope="module")
def data_dir(tmp_path_factory) -> Path:
    return tmp_path_factory.mktemp("server-shots") / "data"


@pytest.fixture(scope="module")
def client(data_dir):
    with LocalClient(create_app(Settings(data_dir=data_dir, frontend_dir=None))) as c:
        yield c


@pytest.fixture(scope="module")
def base_project(client, tmp_path_factory) -> dict:
    """Three shots (hard cuts at 4.0 and 8.0 s): blue, red (warm, with a low tone), green."""
    path = tmp_path_factory.mktemp("film") / "film.mp4"
    tex = [Texture("noise", 0.15, 0.5, seed=s) for s in (1, 2, 3)]
    scene = Scene(12.0, background=(Segment(0, 4, (50, 80, 200), texture=tex[0]),
                                    Segment(4, 8, (220, 60, 40), texture=tex[1]),
                                    Segment(8, 12, (40, 200, 60), texture=tex[2])),
                  audio=(Tone(4.5, 7.5, 55.0, level_dbfs=-12.0),), name="shots test")
    write_scene(path, scene, width=96, height=54, fps=10, quality="low", sample_rate=24000)
    return client.generated_project(path)


@pytest.fixture
def project(client, base_project):
    with client.duplicated(base_project["id"]) as copy:
        yield copy


def shots(client, pid: str) -> dict:
    r = client.get(f"/api/projects/{pid}/shots")
    assert r.status_code == 200, r.text
    return r.json()


def post_edit(client, pid: str, op: dict):
    rev = client.get(f"/api/projects/{pid}").json()["revision"]
    return client.post(f"/api/projects/{pid}/edits", json={"base_revision": rev, "op": op})


def bounds(doc: dict) -> list[tuple[int, int, str]]:
    return [(s["t0"], s["t1"], s["kind"]) for s in doc["shots"]]


def test_the_shots_of_a_film_with_two_cuts(client, project):
    doc = shots(client, project["id"])
    assert doc["n_ticks"] == N_TICKS and doc["tick_s"] == 0.1
    assert bounds(doc) == [(0, 40, "start"), (40, 80, "cut"), (80, 120, "cut")]
    blue, red, green = doc["shots"]
    assert [s["id"] for s in doc["shots"]] == [0, 40, 80]
    assert blue["colour"].startswith("#") and int(red["colour"][1:3], 16) > 150 > int(red["colour"][5:7], 16)
    assert red["temperature_mean_c"] > max(blue["temperature_mean_c"], green["temperature_mean_c"])
    assert red["loudness_sone"] > 10 * max(blue["loudness_sone"], 0.01)  # the tone plays in the red shot
    for s in doc["shots"]:
        assert 0 <= s["vibration_mean"] <= s["vibration_peak"] <= 1 and 0 <= s["fans_share"] <= 1
        assert s["motion"] >= 0


def test_a_threshold_change_and_an_edit_change_the_summary_not_the_boundaries(client, project):
    pid = project["id"]
    before = shots(client, pid)
    r = post_edit(client, pid, {"op": "set", "lanes": ["A5"], "t0": 0, "t1": 40, "value": 1.0})
    assert r.status_code == 200, r.text
    after = shots(client, pid)
    assert bounds(after) == bounds(before) and after["revision"] == r.json()["revision"]
    assert after["shots"][0]["vibration_mean"] == 1.0 and after["shots"][0]["vibration_peak"] == 1.0
    r = client.put(f"/api/projects/{pid}/params", json={"thresholds": {"loudness": 1.0, "sharpness": 1.0,
                                                                      "booming": 1.0, "low_energy": 1.0}})
    assert r.status_code == 200 and r.json()["derived"], r.text
    quiet = shots(client, pid)
    assert bounds(quiet) == bounds(before) and quiet["revision"] > after["revision"]
    assert quiet["shots"][1]["vibration_peak"] == 0.0  # every feature off: only the edited shot vibrates
    assert quiet["shots"][0]["vibration_mean"] == 1.0


def test_split_and_merge_are_undoable_operations_kept_through_a_rederive(client, project):
    pid = project["id"]
    r = post_edit(client, pid, {"op": "shot_split", "t": 60})
    assert r.status_code == 200, r.text
    assert r.json()["op"] == {"op": "shot_split", "t": 60}
    assert bounds(shots(client, pid)) == [(0, 40, "start"), (40, 60, "cut"), (60, 80, "split"), (80, 120, "cut")]
    r = post_edit(client, pid, {"op": "shot_merge", "shots": [80, 60]})
    assert r.status_code == 200 and r.json()["op"]["shots"] == [60, 80], r.text
    merged = [(0, 40, "start"), (40, 60, "cut"), (60, 120, "split")]
    assert bounds(shots(client, pid)) == merged
    r = client.put(f"/api/projects/{pid}/params", json={"thresholds": {"loudness": 0.3}})
    assert r.status_code == 200, r.text
    assert bounds(shots(client, pid)) == merged  # the edits stay through the re-derive
    undo = client.post(f"/api/projects/{pid}/undo", json={"base_revision": r.json()["revision"]}).json()
    undo = client.post(f"/api/projects/{pid}/undo", json={"base_revision": undo["revision"]}).json()
    assert len(bounds(shots(client, pid))) == 4  # the params op, then the merge undone
    client.post(f"/api/projects/{pid}/undo", json={"base_revision": undo["revision"]})
    assert bounds(shots(client, pid)) == [(0, 40, "start"), (40, 80, "cut"), (80, 120, "cut")]


@pytest.mark.parametrize("op, words", [
    ({"op": "shot_split", "t": 40}, "already starts a shot"),
    ({"op": "shot_split", "t": 0}, "outside the film's shots"),
    ({"op": "shot_split", "t": N_TICKS}, "outside the film's shots"),
    ({"op": "shot_merge", "shots": [0, 80]}, "not neighbours"),
    ({"op": "shot_merge", "shots": [0, 41]}, "no shot starts at tick 41"),
    ({"op": "shot_merge", "shots": [40, 40]}, "two different shots"),
    ({"op": "shot_merge", "shots": [40]}, "list of two shot ids"),
    ({"op": "shot_split", "t": -3}, "field 't'"),
    ({"op": "shot_split", "t": 50, "lanes": ["A1"]}, "unknown field 'lanes'"),
])
def test_bad_boundary_operations_are_refused_and_change_nothing(client, project, op, words):
    pid = project["id"]
    rev = client.get(f"/api/projects/{pid}").json()["revision"]
    r = post_edit(client, pid, op)
    assert r.status_code == 400, r.text
    detail = r.json()["detail"]
    assert words in detail and detail.count(". ") == 0 and "/" not in detail.replace("1..", "")
    assert client.get(f"/api/projects/{pid}").json()["revision"] == rev
    assert len(shots(client, pid)["shots"]) == 3


def test_a_project_analysed_before_shots_gets_them_from_its_cache(client, project, data_dir):
    pid = project["id"]
    path = data_dir / "projects" / pid / "analysis.npz"
    with np.load(path) as z:
        old = {k: z[k] for k in z.files if not k.startswith("shots_") and k != "video_signature"}
    np.savez(path.with_name("old.npz"), **old)
    path.with_name("old.npz").replace(path)
    r = post_edit(client, pid, {"op": "shot_split", "t": 100})  # a new revision: nothing cached is reused
    assert r.status_code == 200, r.text
    assert bounds(shots(client, pid)) == [(0, 40, "start"), (40, 80, "cut"), (80, 100, "cut"), (100, 120, "split")]


def test_unknown_project_is_404(client):
    r = client.get(f"/api/projects/{'0' * 32}/shots")
    assert r.status_code == 404 and r.json()["detail"]


def test_posters_are_made_on_demand_cached_on_disk_and_removed_with_the_project(client, base_project, data_dir):
    import cv2

    r = client.post(f"/api/projects/{base_project['id']}/duplicate")
    pid = r.json()["id"]
    doc = shots(client, pid)
    urls = [s["poster_url"] for s in doc["shots"]]
    assert urls == [f"/api/projects/{pid}/posters/{t}.jpg" for t in (19, 59, 99)]  # each shot's middle tick
    folder = data_dir / "projects" / pid / "posters"
    r = client.get(urls[1])  # made now, or already made ahead in the background (test_server_filmstrip.py)
    assert r.status_code == 200 and r.headers["content-type"] == "image/jpeg", r.text
    assert "immutable" in r.headers["cache-control"] and r.content[:2] == b"\xff\xd8"
    img = cv2.imdecode(np.frombuffer(r.content, np.uint8), cv2.IMREAD_COLOR)  # BGR
    assert img.shape[1] == 160 and img[..., 2].mean() > 2 * img[..., 0].mean()  # the red shot
    assert (folder / "59.jpg").read_bytes() == r.content == client.get(urls[1]).content
    assert client.get(f"/api/projects/{pid}/posters/{N_TICKS}.jpg").status_code == 404
    assert client.get(f"/api/projects/{pid}/posters/-1.jpg").status_code == 404
    assert client.delete(f"/api/projects/{pid}").status_code in (200, 204)
    assert not folder.exists()


def test_boundary_edits_are_kept_through_a_regeneration(client, project):
    """A generate job replaces the generated layer (and the analysis, when its parameters ask for
    one); the split, an edit op, is replayed over the boundaries the analysis then holds."""
    pid = project["id"]
    assert post_edit(client, pid, {"op": "shot_split", "t": 60}).status_code == 200
    r = client.post(f"/api/projects/{pid}/generate", json={})
    assert r.status_code == 202, r.text
    job = client.finished_job(r.json()["job"]["id"])
    assert job["status"] == "done", job
    assert bounds(shots(client, pid)) == [(0, 40, "start"), (40, 60, "cut"), (60, 80, "split"), (80, 120, "cut")]
