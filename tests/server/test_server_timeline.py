"""Long-film plumbing of the timeline routes (docs/API.md "Timeline"): markers served with the edit
list and the binary header, imported documents kept out of the edit list (in imports/), the binary
timeline by blocks, gzipped and revalidated, the generated layer stored as .npz and kept in memory
after a re-derive, and projects from before both formats.

A 20 s synthetic film, generated in audio mode, is the project; each test works on its own copy.
"""

from __future__ import annotations

import gzip
import time
from pathlib import Path

import numpy as np
import pytest

from autohaptics.timeline import npz as generated_file
from autohaptics.server.app import create_app
from autohaptics.timeline.wire import decode
from autohaptics.server.settings import Settings
from autohaptics.testing import Scene, Segment, Tone, write_scene
from autohaptics.timeline import Timeline

from service_client import LocalClient

DURATION_S = 20.0
N_TICKS = 200
TERMINAL = ("done", "failed", "cancelled")


@pytest.fixture(scope="module")
def data_dir(tmp_path_factory) -> Path:
    return tmp_path_factory.mktemp("server-timeline") / "data"


@pytest.fixture(scope="module")
def client(data_dir):
    with LocalClient(create_app(Settings(data_dir=data_dir, frontend_dir=None))) as c:
        yield c


@pytest.fixture(scope="module")
def base_project(client, tmp_path_factory) -> dict:
    path = tmp_path_factory.mktemp("film") / "film.mp4"
    scene = Scene(duration_s=DURATION_S, background=(Segment(0.0, DURATION_S, (90, 90, 200)),),
                  audio=(Tone(3.0, 6.0, 55.0, level_dbfs=-12.0), Tone(12.0, 13.0, 3000.0, level_dbfs=-18.0)),
                  name="timeline test")
    write_scene(path, scene, width=64, height=36, fps=5, quality="low", sample_rate=24000)
    return client.generated_project(path, mode="audio")


@pytest.fixture
def project(client, base_project):
    with client.duplicated(base_project["id"]) as copy:
        yield copy


def edit(client, pid: str, op: dict) -> dict:
    rev = client.get(f"/api/projects/{pid}").json()["revision"]
    r = client.post(f"/api/projects/{pid}/edits", json={"base_revision": rev, "op": op})
    assert r.status_code == 200, r.text
    return r.json()


def known(n: int = N_TICKS) -> Timeline:
    tl = Timeline.empty(n)
    k = np.arange(n)
    tl.vibration[:] = ((k[:, None] + np.arange(9)[None, :] * 5) % 20) / 20.0
    tl.temperature_c[:] = 31.0 + (k % 10)
    tl.fans[:, 4, 8] = (k % 4) / 4.0
    return tl.validate()


# ------------------------------------------------------------------------------ markers
def test_markers_come_with_the_edit_list_every_history_answer_and_the_binary_header(client, project):
    pid = project["id"]
    assert client.get(f"/api/projects/{pid}/edits").json()["markers"] == []
    a = edit(client, pid, {"op": "marker_add", "marker": {"id": "a", "t_s": 12.5, "label": "boom"}})
    assert a["markers"] == [{"id": "a", "t_s": 12.5, "label": "boom"}]
    b = edit(client, pid, {"op": "marker_add", "marker": {"id": "b", "t_s": 99.0, "label": "end"}})
    # Held at the end of the film, as the composition does it; sorted by time.
    assert b["markers"] == [{"id": "a", "t_s": 12.5, "label": "boom"}, {"id": "b", "t_s": DURATION_S, "label": "end"}]
    c = edit(client, pid, {"op": "marker_update", "marker": {"id": "a", "t_s": 1.0}})
    assert [m["id"] for m in c["markers"]] == ["a", "b"] and c["markers"][0]["t_s"] == 1.0
    edits = client.get(f"/api/projects/{pid}/edits").json()
    doc = client.get(f"/api/projects/{pid}/timeline").json()
    header, _ = decode(client.get(f"/api/projects/{pid}/timeline.bin").content)
    assert edits["markers"] == doc["markers"] == header["markers"] == c["markers"]
    undo = client.post(f"/api/projects/{pid}/undo", json={"base_revision": c["revision"]}).json()
    assert undo["markers"][0] == {"id": "a", "t_s": 12.5, "label": "boom"}
    redo = client.post(f"/api/projects/{pid}/redo", json={"base_revision": undo["revision"]}).json()
    assert redo["markers"] == c["markers"]
    assert "markers" not in decode(client.get(f"/api/projects/{pid}/timeline.bin?layer=generated").content)[0]


# ------------------------------------------------------------------------------ imports
def test_an_import_is_stored_as_a_file_and_the_edit_list_stays_light(client, project, data_dir):
    pid = project["id"]
    doc = known().to_json().encode()
    rev = project["revision"]
    r = client.post(f"/api/projects/{pid}/import", files={"file": ("mine.json", doc, "application/json")},
                    data={"base_revision": str(rev)})
    assert r.status_code == 200, r.text
    op = r.json()["op"]
    assert set(op) == {"op", "ref", "name", "n_ticks"} and op["name"] == "mine.json" and op["n_ticks"] == N_TICKS
    stored = data_dir / "projects" / pid / "imports" / f"{op['ref']}.json"
    np.testing.assert_array_equal(Timeline.load(stored).vibration, known().vibration)
    edits = client.get(f"/api/projects/{pid}/edits")
    assert len(edits.content) < 1000 and edits.json()["ops"] == [op]
    composed = client.app.state.composer.compose(pid).timeline
    np.testing.assert_array_equal(composed.vibration, known().vibration)
    assert client.get(f"/api/projects/{pid}/timeline").json()["edits"] == [op]

    # An import sent as an op with its document is stored the same way.
    other = known(150)
    other.vibration[:] = 0.5
    res = edit(client, pid, {"op": "import", "timeline": other.to_dict()})
    assert set(res["op"]) == {"op", "ref", "name", "n_ticks"} and res["op"]["n_ticks"] == 150
    composed = client.app.state.composer.compose(pid).timeline
    assert np.all(composed.vibration[:150] == 0.5) and np.all(composed.vibration[150:] == 0)

    # A stored import can be named again (it exists in this project); an unknown one cannot.
    again = edit(client, pid, op)
    assert again["op"] == op
    bad = client.post(f"/api/projects/{pid}/edits", json={"base_revision": again["revision"], "op": {
        "op": "import", "ref": "0" * 32, "name": "x", "n_ticks": 3}})
    assert bad.status_code == 400 and "missing" in bad.json()["detail"]
    assert str(data_dir) not in bad.json()["detail"]  # never a server path

    # A copy of the project and a restarted server compose the same.
    copy = client.post(f"/api/projects/{pid}/duplicate").json()
    try:
        with LocalClient(create_app(Settings(data_dir=data_dir, frontend_dir=None))) as restarted:
            for p in (pid, copy["id"]):
                t = restarted.app.state.composer.compose(p).timeline
                np.testing.assert_array_equal(t.vibration, known().vibration)
    finally:
        client.delete(f"/api/projects/{copy['id']}")


def test_binary_blocks_gzip_and_revalidation(client, project):
    pid = project["id"]
    url = f"/api/projects/{pid}/timeline.bin"
    plain = client.get(url, headers={"Accept-Encoding": "identity"})
    assert plain.status_code == 200 and "content-encoding" not in plain.headers
    header, full = decode(plain.content)
    names = [b["name"] for b in header["blocks"]]
    assert names[:4] == ["vibration", "temperature_c", "fans", "fan_activity"]

    zipped = client.get(url, headers={"Accept-Encoding": "gzip, deflate"})
    assert zipped.headers["content-encoding"] == "gzip" and zipped.content == plain.content  # httpx decodes
    assert zipped.headers["vary"] == "Accept-Encoding" and zipped.headers["etag"] != plain.headers["etag"]
    with client.stream("GET", url, headers={"Accept-Encoding": "gzip"}) as resp:
        wire = b"".join(resp.iter_raw())
    assert gzip.decompress(wire) == plain.content and len(wire) < len(plain.content) / 3  # mostly-zero fans

    some = client.get(url, params={"blocks": "vibration,temperature_c,features"}, headers={"Accept-Encoding": "identity"})
    h2, part = decode(some.content)
    assert [b["name"] for b in h2["blocks"]] == [n for n in names if n not in ("fans", "fan_activity")]
    np.testing.assert_array_equal(part["vibration"], full["vibration"])
    assert h2["revision"] == header["revision"] and h2["markers"] == header["markers"]
    fans = decode(client.get(url, params={"blocks": "fans"}).content)[1]
    assert list(fans) == ["fans"]
    np.testing.assert_array_equal(fans["fans"], full["fans"])
    bad = client.get(url, params={"blocks": "vibration,smell"})
    assert bad.status_code == 400 and "smell" in bad.json()["detail"]
    assert client.get(url, params={"blocks": ","}).status_code == 400

    etag = plain.headers["etag"]
    again = client.get(url, headers={"Accept-Encoding": "identity", "If-None-Match": etag})
    assert again.status_code == 304 and again.content == b""
    res = edit(client, pid, {"op": "set", "lanes": ["A2"], "t0": 0, "t1": 5, "value": 1.0})
    changed = client.get(url, headers={"Accept-Encoding": "identity", "If-None-Match": etag})
    assert changed.status_code == 200 and changed.headers["etag"] != etag
    assert decode(changed.content)[0]["revision"] == res["revision"]


def test_binary_since_a_revision_sends_only_the_changed_blocks(client, project):
    """``?since=R``: the blocks unchanged since revision R are left out and named in the header;
    with R's blocks they make the whole timeline. An edit of one lane sends that lane; a threshold
    commit the vibration and the curves, never the fans or the temperature."""
    pid = project["id"]
    url = f"/api/projects/{pid}/timeline.bin"
    header0, full0 = decode(client.get(url).content)
    rev0 = header0["revision"]
    res = edit(client, pid, {"op": "set", "lanes": ["A2"], "t0": 0, "t1": 5, "value": 1.0})
    h1, part1 = decode(client.get(url, params={"since": rev0}).content)
    assert h1["since"] == rev0 and h1["revision"] == res["revision"] and list(part1) == ["vibration"]
    assert "fans" in h1["unchanged"] and "temperature_c" in h1["unchanged"]
    _, full1 = decode(client.get(url).content)
    np.testing.assert_array_equal(part1["vibration"], full1["vibration"])
    for name in h1["unchanged"]:
        np.testing.assert_array_equal(full0[name], full1[name])

    r = client.put(f"/api/projects/{pid}/params", json={"thresholds": {"loudness": 0.2, "sharpness": 0.2,
                                                                      "booming": 0.2, "low_energy": 0.2}})
    assert r.status_code == 200 and r.json()["derived"], r.text
    h2, part2 = decode(client.get(url, params={"since": h1["revision"]}).content)
    assert h2["since"] == h1["revision"] and "vibration" in part2
    assert not {"fans", "fan_activity", "temperature_c"} & set(part2)
    _, full2 = decode(client.get(url).content)
    assert set(part2) | set(h2["unchanged"]) == set(full2)
    for name, values in full2.items():
        np.testing.assert_array_equal(part2[name] if name in part2 else full1[name], values)
    assert not np.array_equal(full2["vibration"], full1["vibration"])

    h3, part3 = decode(client.get(url, params={"since": h2["revision"]}).content)  # nothing moved on
    assert part3 == {} and set(h3["unchanged"]) == set(full2)
    old = decode(client.get(url, params={"since": 10_000}).content)  # a revision not kept: all of it
    assert "since" not in old[0] and set(old[1]) == set(full2)
    assert client.get(url, params={"since": -1}).status_code in (400, 422)


# -------------------------------------------------------------------- generated layer
def test_a_request_for_some_blocks_that_ends_after_the_warm_keeps_the_others(monkeypatch):
    """The warm-up after a job quantises every block of the revision while the editor's reload asks
    for some of them: whichever ends last, the revision keeps every block, so the next commit's
    ``since`` answer sends only what changed (before, the fan grid too when the reload ended last)."""
    import threading

    from autohaptics.server import bins as bins_mod

    cache = bins_mod.BinaryCache(2)
    tl = known()
    inside, release = threading.Event(), threading.Event()
    real = bins_mod.binary.quantise

    def quantise(name, dtype, src):
        if threading.current_thread().name == "reload" and not inside.is_set():
            inside.set()
            assert release.wait(60)
        return real(name, dtype, src)

    monkeypatch.setattr(bins_mod.binary, "quantise", quantise)
    reload = threading.Thread(name="reload", target=lambda: cache.get(
        "p", "composed", 1, tl, header={}, names=("vibration",), gzipped=False, since=None))
    reload.start()
    assert inside.wait(60)
    cache.prepare("p", "composed", 1, tl)  # the warm, done while the reload quantises
    release.set()
    reload.join(60)
    changed = known()
    changed.vibration[:10] = 0.0
    h, part = decode(cache.get("p", "composed", 2, changed.validate(), header={}, names=None, gzipped=False, since=1))
    assert set(part) == {"vibration"} and "fans" in h["unchanged"]


def test_generated_layer_is_npz_and_its_json_export(client, project, data_dir):
    pid = project["id"]
    pdir = data_dir / "projects" / pid
    assert (pdir / "generated.npz").is_file() and not (pdir / "generated.json").exists()
    tl = generated_file.load_npz(pdir / "generated.npz")
    doc = client.get(f"/api/projects/{pid}/timeline", params={"layer": "generated"}).json()
    assert doc["n_ticks"] == tl.n_ticks == N_TICKS and doc["revision"] == project["revision"]
    np.testing.assert_allclose(np.asarray(doc["tracks"]["vibration"]), tl.vibration, atol=5e-5)
    edit(client, pid, {"op": "clear", "lanes": ["A1"], "t0": 0, "t1": N_TICKS})
    again = client.get(f"/api/projects/{pid}/timeline", params={"layer": "generated"}).json()
    assert again["tracks"]["vibration"] == doc["tracks"]["vibration"] and "edits" not in again


def test_rederive_keeps_the_derived_timeline_in_memory(client, project, monkeypatch):
    pid = project["id"]
    thresholds = {"loudness": 0.2, "sharpness": 0.2, "booming": 0.2, "low_energy": 0.2}
    r = client.put(f"/api/projects/{pid}/params", json={"thresholds": thresholds})
    assert r.status_code == 200 and r.json()["derived"], r.text

    def no_reading(path):
        raise AssertionError(f"{path} was read back after the re-derive")

    monkeypatch.setattr("autohaptics.server.composer.load_npz", no_reading)
    composed = client.app.state.composer.compose(pid)
    assert composed.revision == r.json()["revision"]
    assert composed.timeline.generator["params"]["thresholds"]["loudness"] == 0.2
    assert client.get(f"/api/projects/{pid}/timeline.bin").status_code == 200


def test_a_commit_writes_its_generated_layer_after_it_settles(client, project, data_dir, monkeypatch):
    """The re-derived layer is written ``settle_s`` after the commit (the editor's timeline request
    right after it does not share the CPU with the write); commits within that time are written
    once, the last one; a flush writes it at once."""
    pid = project["id"]
    writer = client.app.state.composer.writer
    writes = []
    real = type(writer)._write
    monkeypatch.setattr(writer, "settle_s", 600.0)
    monkeypatch.setattr(writer, "_write", lambda p, rev, tl: (writes.append(rev) if p == pid else None, real(writer, p, rev, tl)))
    writer.flush()  # earlier tests' layers
    path = data_dir / "projects" / pid / "generated.npz"
    before = path.stat().st_ino, path.stat().st_mtime_ns
    revisions = []
    for level in (0.2, 0.3):
        r = client.put(f"/api/projects/{pid}/params", json={"thresholds": {"loudness": level}})
        assert r.status_code == 200 and r.json()["derived"], r.text
        revisions.append(r.json()["revision"])
        assert client.get(f"/api/projects/{pid}/timeline.bin", params={"since": r.json()["revision"] - 1}).status_code == 200
    assert writer.pending(pid) is not None and writes == []
    assert (path.stat().st_ino, path.stat().st_mtime_ns) == before
    writer.flush(pid)
    assert writer.pending(pid) is None and len(writes) == 1 and writes[0] > revisions[0]  # the last one, once
    assert generated_file.load_npz(path).generator["params"]["thresholds"]["loudness"] == 0.3


def test_a_restarted_server_loads_the_project_worked_on_last_before_it_is_asked(client, project, data_dir,
                                                                             monkeypatch):
    """The editor of the film open before a restart opens without waiting for its files to load."""
    pid = project["id"]
    assert client.patch(f"/api/projects/{pid}", json={"view": {"zoom": 2.0}}).status_code == 200
    loaded = []

    def counting(path):
        loaded.append(Path(path))
        return generated_file.load_npz(path)

    monkeypatch.setattr("autohaptics.server.composer.load_npz", counting)
    with LocalClient(create_app(Settings(data_dir=data_dir, frontend_dir=None))) as restarted:
        deadline = time.monotonic() + 20
        while not loaded and time.monotonic() < deadline:
            time.sleep(0.05)
        assert [p.parent.name for p in loaded] == [pid]  # that project alone, before any request
        composer = restarted.app.state.composer
        deadline = time.monotonic() + 20
        while composer.analysis(pid) is None and time.monotonic() < deadline:
            time.sleep(0.05)

        def no_reading(path):
            raise AssertionError(f"{path} was read again after the start-up")

        monkeypatch.setattr("autohaptics.server.composer.load_npz", no_reading)
        assert restarted.get(f"/api/projects/{pid}/timeline.bin").status_code == 200


def test_a_cold_server_answers_the_first_requests_from_disk(client, project, base_project, data_dir, monkeypatch):
    """The whole gzipped answers of the revision on show are kept in the project's bins/ folder: a
    restarted server answers them without loading the project's layer, the same bytes; an edit's
    revision gets its own answers (equal to the plain ones), and the older revision's files go."""
    pid = project["id"]
    url, first = f"/api/projects/{pid}/timeline.bin", {"blocks": "vibration,temperature_c,fan_activity,features"}

    def raw(c) -> bytes:
        with c.stream("GET", url, params=first, headers={"Accept-Encoding": "gzip"}) as resp:
            assert resp.status_code == 200 and resp.headers["content-encoding"] == "gzip"
            return b"".join(resp.iter_raw())

    wire = raw(client)
    assert gzip.decompress(wire) == client.get(url, params=first, headers={"Accept-Encoding": "identity"}).content
    bins = data_dir / "projects" / pid / "bins"
    assert len(list(bins.iterdir())) == 1
    assert client.patch(f"/api/projects/{base_project['id']}", json={"view": {"zoom": 3.0}}).status_code == 200
    refused = [True]

    def guarded(path):
        assert not (refused[0] and Path(path).parent.name == pid), f"{path} was loaded for a kept answer"
        return generated_file.load_npz(path)

    monkeypatch.setattr("autohaptics.server.composer.load_npz", guarded)
    with LocalClient(create_app(Settings(data_dir=data_dir, frontend_dir=None))) as restarted:
        assert raw(restarted) == wire  # from the file: the layer was not loaded
        refused[0] = False
        res = edit(restarted, pid, {"op": "set", "lanes": ["A3"], "t0": 10, "t1": 40, "value": 0.5})
        changed = raw(restarted)
        header, blocks = decode(gzip.decompress(changed))
        assert header["revision"] == res["revision"] and changed != wire
        assert gzip.decompress(changed) == restarted.get(url, params=first,
                                                         headers={"Accept-Encoding": "identity"}).content
        assert [p.name.split("-")[0] for p in bins.iterdir()] == [str(res["revision"])]


def test_npz_round_trip_and_errors(tmp_path):
    tl = known()
    tl.features["loudness"] = np.linspace(0, 1, N_TICKS, dtype=np.float32)
    tl.stats["note"] = "kept"
    path = generated_file.save_npz(tl, tmp_path / "g.npz")
    back = generated_file.load_npz(path)
    for name in ("vibration", "temperature_c", "fans"):
        np.testing.assert_array_equal(getattr(back, name), getattr(tl, name))
    np.testing.assert_array_equal(back.features["loudness"], tl.features["loudness"])
    assert back.stats == tl.stats and back.generator == tl.generator and back.n_ticks == tl.n_ticks
    (tmp_path / "bad.npz").write_bytes(b"not a zip")
    with pytest.raises(Exception, match="bad.npz: not a generated timeline"):
        generated_file.load_npz(tmp_path / "bad.npz")
    with pytest.raises(Exception, match="missing.npz: no such file"):
        generated_file.load_npz(tmp_path / "missing.npz")


# ------------------------------------------------------------------- chair temperature
def test_the_chair_temperature_is_the_target_clamped_and_slew_limited(client, project):
    pid = project["id"]
    # the thesis's colour rule: a timeline range of 30..55 C, wider than the device's 18..40 C
    r = client.put(f"/api/projects/{pid}/params", json={"overrides": {"thermal.mapping": "thesis"}})
    assert r.status_code == 200 and r.json()["job"] is None, r.text
    edit(client, pid, {"op": "set", "lanes": ["temperature"], "t0": 0, "t1": 100, "value": 45.0})
    edit(client, pid, {"op": "set", "lanes": ["temperature"], "t0": 100, "t1": N_TICKS, "value": 20.0})
    target = np.asarray(client.get(f"/api/projects/{pid}/timeline").json()["tracks"]["temperature_c"])
    r = client.get(f"/api/projects/{pid}/timeline/chair-temperature")
    assert r.status_code == 200, r.text
    body = r.json()
    played = np.asarray(body["values"])
    assert (body["min_c"], body["max_c"], body["neutral_c"], body["rate_c_per_s"]) == (18.0, 40.0, 33.0, 1.0)
    assert body["revision"] == client.get(f"/api/projects/{pid}").json()["revision"]
    assert target[:100].min() == 45.0 and played.shape == target.shape
    step = body["rate_c_per_s"] * body["tick_s"]
    # From neutral, 0.1 C a tick up to the device's 40 C (not the target's 45), then down to 20 C.
    assert played[0] == pytest.approx(33.0 + step)
    assert np.abs(np.diff(played)).max() <= step + 1e-9
    assert played[69:100] == pytest.approx(40.0) and played.max() <= 40.0
    assert played[-1] == pytest.approx(40.0 - (N_TICKS - 100) * step)
    assert client.get("/api/projects/nope/timeline/chair-temperature").status_code == 404


def test_a_parameter_change_is_an_undoable_op_in_the_edit_history(client, project):
    pid = project["id"]
    p0 = client.get(f"/api/projects/{pid}").json()
    vib0 = client.get(f"/api/projects/{pid}/timeline").json()["tracks"]["vibration"]
    edit(client, pid, {"op": "set", "lanes": ["A1"], "t0": 0, "t1": 10, "value": 0.25})
    off = {"loudness": 1.0, "sharpness": 1.0, "booming": 1.0, "low_energy": 1.0}
    r = client.put(f"/api/projects/{pid}/params", json={"thresholds": off})
    assert r.status_code == 200 and r.json()["derived"] and r.json()["cursor"] == 2, r.text
    e = client.get(f"/api/projects/{pid}/edits").json()
    assert e["revision"] == r.json()["revision"] and e["cursor"] == 2
    assert e["ops"][1] == {"op": "params", "from": p0["params"], "to": {**p0["params"], "thresholds": off}}
    # The same parameters again change nothing and record nothing.
    r = client.put(f"/api/projects/{pid}/params", json={"thresholds": off})
    assert r.json()["cursor"] is None and client.get(f"/api/projects/{pid}/edits").json()["cursor"] == 2

    def vibration() -> np.ndarray:
        return np.asarray(client.get(f"/api/projects/{pid}/timeline").json()["tracks"]["vibration"])

    assert vibration()[10:].max() == 0 and vibration()[0:10, 0].tolist() == [0.25] * 10
    rev = client.get(f"/api/projects/{pid}").json()["revision"]
    u = client.post(f"/api/projects/{pid}/undo", json={"base_revision": rev})
    assert u.status_code == 200, u.text
    assert u.json()["params"] == p0["params"] and u.json()["cursor"] == 1 and u.json()["job"] is None
    assert client.get(f"/api/projects/{pid}").json()["params"] == p0["params"]
    assert u.json()["revision"] == client.get(f"/api/projects/{pid}").json()["revision"]
    assert np.array_equal(vibration()[10:], np.asarray(vib0)[10:]), "the previous thresholds' vibration is back"
    # An ordinary op undone answers without parameters; redo brings the thresholds back.
    u2 = client.post(f"/api/projects/{pid}/undo", json={"base_revision": u.json()["revision"]}).json()
    assert u2["params"] is None and u2["cursor"] == 0
    r1 = client.post(f"/api/projects/{pid}/redo", json={"base_revision": u2["revision"]}).json()
    r2 = client.post(f"/api/projects/{pid}/redo", json={"base_revision": r1["revision"]}).json()
    assert r2["params"]["thresholds"] == off and client.get(f"/api/projects/{pid}").json()["params"]["thresholds"] == off
    assert vibration()[10:].max() == 0
    # The op is the service's record of PUT params: a client cannot post one.
    bad = client.post(f"/api/projects/{pid}/edits", json={"base_revision": r2["revision"], "op": e["ops"][1]})
    assert bad.status_code == 400 and "PUT /api/projects/{id}/params" in bad.json()["detail"]


def wait_done(client, job_id: str) -> dict:
    for _ in range(1200):
        job = client.get(f"/api/jobs/{job_id}").json()
        if job["status"] in TERMINAL:
            return job
        time.sleep(0.1)
    raise AssertionError(f"job {job_id} still {job['status']}")


def test_a_regeneration_with_other_parameters_is_undone_from_the_kept_analysis(client, project, data_dir):
    pid = project["id"]
    pdir = data_dir / "projects" / pid
    p0 = client.get(f"/api/projects/{pid}").json()

    def tracks() -> dict:
        return client.get(f"/api/projects/{pid}/timeline").json()["tracks"]

    before = tracks()
    # The same parameters again: a job, but nothing to undo.
    assert wait_done(client, client.post(f"/api/projects/{pid}/generate", json={}).json()["job"]["id"])["status"] == "done"
    assert client.get(f"/api/projects/{pid}/edits").json()["cursor"] == 0
    assert not (pdir / "analysis-previous.npz").exists()
    # A cancelled attempt records nothing either.
    job = client.post(f"/api/projects/{pid}/generate", json={"preset": "reference"}).json()["job"]
    assert client.post(f"/api/jobs/{job['id']}/cancel").status_code == 202
    assert wait_done(client, job["id"])["status"] == "cancelled"
    assert client.get(f"/api/projects/{pid}/edits").json()["cursor"] == 0
    # Another preset (another analysis) and mode: one `params` op once the job is done.
    job = client.post(f"/api/projects/{pid}/generate", json={"preset": "fast", "mode": "multimodal"}).json()["job"]
    assert client.get(f"/api/projects/{pid}/edits").json()["cursor"] == 0, "recorded when done, not before"
    assert wait_done(client, job["id"])["status"] == "done"
    p1 = client.get(f"/api/projects/{pid}").json()
    assert (p1["params"]["preset"], p1["params"]["mode"]) == ("fast", "multimodal")
    e = client.get(f"/api/projects/{pid}/edits").json()
    assert e["cursor"] == 1 and e["revision"] == p1["revision"]
    assert e["ops"] == [{"op": "params", "from": p0["params"], "to": p1["params"]}]
    after = tracks()
    assert after != before
    assert (pdir / "analysis-previous.npz").is_file(), "the balanced analysis is kept"
    # Undo: the previous parameters and their timeline, re-derived from the kept analysis (no job).
    u = client.post(f"/api/projects/{pid}/undo", json={"base_revision": p1["revision"]})
    assert u.status_code == 200, u.text
    assert u.json()["params"] == p0["params"] and u.json()["job"] is None and u.json()["cursor"] == 0
    assert client.get(f"/api/projects/{pid}").json()["params"] == p0["params"]
    assert tracks() == before
    # Redo: the regenerated parameters and timeline again, from the analysis swapped back.
    r = client.post(f"/api/projects/{pid}/redo", json={"base_revision": u.json()["revision"]})
    assert r.status_code == 200, r.text
    assert r.json()["params"] == p1["params"] and r.json()["job"] is None and r.json()["cursor"] == 1
    assert client.get(f"/api/projects/{pid}").json()["params"] == p1["params"]
    assert tracks() == after
