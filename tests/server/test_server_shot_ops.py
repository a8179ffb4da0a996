"""Shot operations through the server on a film whose shots alternate two looks (red still shots
in silence, blue panning shots with noise): a ``group`` op is one revision and one undo step, a
bad sub-op is 400 naming ``ops[i]`` and stores nothing, ``paste`` with ``t1`` fits a shot's
effects to another's length, and each shot's similar shots are its own kind first."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from autohaptics.server.app import create_app
from autohaptics.server.settings import Settings
from autohaptics.testing import Noise, Scene, Segment, Texture, write_scene
from service_client import LocalClient

SHOT_S = 2.0
N_SHOTS = 8
RED, BLUE = (200, 40, 40), (40, 60, 200)


def alternating_scene() -> Scene:
    """Even shots red and still in silence, odd shots blue, panning, with white noise."""
    segs, audio = [], []
    for i in range(N_SHOTS):
        t0, t1 = i * SHOT_S, (i + 1) * SHOT_S
        tex = Texture("noise", 0.12, 0.5, seed=i + 1)
        if i % 2 == 0:
            segs.append(Segment(t0, t1, RED, texture=tex))
        else:
            segs.append(Segment(t0, t1, BLUE, texture=tex, pan=(0.35, 0.05)))
            audio.append(Noise(t0 + 0.05, t1 - 0.05, level_dbfs=-14.0, seed=i))
    return Scene(N_SHOTS * SHOT_S, background=tuple(segs), audio=tuple(audio), name="two looks")


@pytest.fixture(scope="module")
def client(tmp_path_factory):
    data = tmp_path_factory.mktemp("server-shot-ops") / "data"
    with LocalClient(create_app(Settings(data_dir=data, frontend_dir=None))) as c:
        yield c


@pytest.fixture(scope="module")
def base_project(client, tmp_path_factory) -> dict:
    path = tmp_path_factory.mktemp("film") / "film.mp4"
    write_scene(path, alternating_scene(), width=96, height=54, fps=10, quality="low", sample_rate=24000)
    return client.generated_project(path)


@pytest.fixture
def project(client, base_project):
    with client.duplicated(base_project["id"]) as copy:
        yield copy


def revision(client, pid: str) -> int:
    return client.get(f"/api/projects/{pid}").json()["revision"]


def values(client, pid: str, lane: str, t0: int, t1: int) -> np.ndarray:
    r = client.get(f"/api/projects/{pid}/timeline/values", params={"lanes": lane, "t0": t0, "t1": t1})
    assert r.status_code == 200, r.text
    return np.array(r.json()["values"][lane])


def post(client, pid: str, op: dict):
    return client.post(f"/api/projects/{pid}/edits", json={"base_revision": revision(client, pid), "op": op})


def test_the_film_has_its_eight_shots(client, base_project):
    doc = client.get(f"/api/projects/{base_project['id']}/shots").json()
    assert [s["t0"] for s in doc["shots"]] == [20 * i for i in range(N_SHOTS)]


def test_a_group_is_one_revision_and_one_undo_step(client, project):
    pid = project["id"]
    before = {lane: values(client, pid, lane, 0, 160) for lane in ("A5", "A1")}
    rev, cursor = revision(client, pid), client.get(f"/api/projects/{pid}/edits").json()["cursor"]
    group = {"op": "group", "ops": [{"op": "set", "lanes": ["A5"], "t0": t, "t1": t + 20, "value": 0.75}
                                    for t in (0, 40, 80, 120)]
             + [{"op": "paste", "t0": 20, "t1": 60, "values": {"A1": [0.2, 0.6]}}]}
    r = post(client, pid, group)
    assert r.status_code == 200, r.text
    assert r.json()["revision"] == rev + 1 and r.json()["cursor"] == cursor + 1
    assert r.json()["op"]["ops"][4] == {"op": "paste", "t0": 20, "t1": 60, "values": {"A1": [0.2, 0.6]}}
    a5 = values(client, pid, "A5", 0, 160)
    even = np.concatenate([np.arange(t, t + 20) for t in (0, 40, 80, 120)])
    np.testing.assert_allclose(a5[even], 0.75, rtol=1e-6)
    np.testing.assert_array_equal(np.delete(a5, even), np.delete(before["A5"], even))
    np.testing.assert_allclose(values(client, pid, "A1", 20, 60), [0.2] * 20 + [0.6] * 20, rtol=1e-6)
    undo = client.post(f"/api/projects/{pid}/undo", json={"base_revision": r.json()["revision"]})
    assert undo.status_code == 200 and undo.json()["cursor"] == cursor, undo.text
    for lane, was in before.items():  # one step undoes all five
        np.testing.assert_array_equal(values(client, pid, lane, 0, 160), was)
    redo = client.post(f"/api/projects/{pid}/redo", json={"base_revision": undo.json()["revision"]})
    assert redo.status_code == 200, redo.text
    np.testing.assert_allclose(values(client, pid, "A5", 0, 20), 0.75, rtol=1e-6)


SET = {"op": "set", "lanes": ["A5"], "t0": 0, "t1": 20, "value": 0.5}


@pytest.mark.parametrize("ops, words", [
    ([SET, {"op": "clear", "lanes": ["A5"], "t0": 400, "t1": 420}], "ops[1] (clear): field 't0' (400) lies past the end"),
    ([SET, SET, {"op": "shot_split", "t": 30}], "ops[2] must be one of"),
    ([SET, {"op": "group", "ops": [SET]}], "ops[1] must be one of"),
    ([{**SET, "value": None}], "ops[0] (set): field 'value' must be a finite number"),
    ([SET, {"op": "paste", "t0": 20, "t1": 10, "values": {"A1": [1]}}], "ops[1] (paste): field 't1' (10)"),
    ([], "field 'ops' must be a list of 1..10000"),
])
def test_a_bad_group_is_refused_and_stores_nothing(client, project, ops, words):
    pid = project["id"]
    rev, n_ops = revision(client, pid), len(client.get(f"/api/projects/{pid}/edits").json()["ops"])
    r = post(client, pid, {"op": "group", "ops": ops})
    assert r.status_code == 400, r.text
    detail = r.json()["detail"]
    assert words in detail and detail.count(". ") == 0
    assert revision(client, pid) == rev and len(client.get(f"/api/projects/{pid}/edits").json()["ops"]) == n_ops


def test_each_shots_nearest_shots_are_its_own_kind(client, base_project):
    pid = base_project["id"]
    ids = [20 * i for i in range(N_SHOTS)]
    for i, shot in enumerate(ids):
        r = client.get(f"/api/projects/{pid}/shots/{shot}/similar")
        assert r.status_code == 200, r.text
        doc = r.json()
        assert doc["shot"] == shot and doc["revision"] == revision(client, pid)
        found = [s["id"] for s in doc["similar"]]
        d = [s["distance"] for s in doc["similar"]]
        assert sorted(found) == [t for t in ids if t != shot] and d == sorted(d)
        assert all(0 <= x <= 1 for x in d)
        same = {t for t in ids if t != shot and (t // 20) % 2 == i % 2}
        assert set(found[:len(same)]) == same, doc  # the three of its own look come first
        assert min(d[3:]) > 0.75 and min(d[3:]) - max(d[:3]) > 0.25, d  # and far from the other look


def test_similar_follows_the_boundary_edits_and_refuses_unknown_shots(client, project):
    pid = project["id"]
    assert post(client, pid, {"op": "shot_split", "t": 30}).status_code == 200
    doc = client.get(f"/api/projects/{pid}/shots/30/similar").json()
    assert {s["id"] for s in doc["similar"][:4]} == {20, 60, 100, 140}  # the blue shots, its other half among them
    for bad in (31, 160, 10**6, -1):
        r = client.get(f"/api/projects/{pid}/shots/{bad}/similar")
        assert r.status_code == 404, r.text
        assert r.json()["detail"] == f"no shot starts at tick {bad} (shot ids are their first ticks)"
    r = client.get(f"/api/projects/{pid}/shots/ten/similar")
    assert r.status_code == 400 and r.json()["detail"].startswith("field 'shot_id'"), r.text
    assert client.get(f"/api/projects/{'0' * 32}/shots/0/similar").status_code == 404
