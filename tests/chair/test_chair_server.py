"""The chair routes of the web service (docs/API.md "Chair") against the compiled virtual chair:
ports, connect / status / SSE / disconnect, settings (validation, persistence), playback of the
composed timeline (comfort, clamps, seek, pause, drift, a new revision while playing), STOP,
a chair that dies and comes back, and pushing a range.

The project is a generated 30 s synthetic film whose tracks are then replaced by an imported
timeline with known values (an undoable edit), so the chair's log can be checked frame by frame.
"""

from __future__ import annotations

import json
import math
import time
import uuid
from pathlib import Path

import numpy as np
import pytest

from autohaptics.chair import VirtualChair
from autohaptics.server.app import create_app
from autohaptics.server.settings import Settings
from autohaptics.testing import Scene, Segment, Tone, write_scene
from autohaptics.timeline import Timeline

from service_client import LocalClient

DURATION_S = 30.0
N_TICKS = 300
ARMRESTS = (2, 6)  # A3, A7
TERMINAL = ("done", "failed", "cancelled")


def known_timeline() -> Timeline:
    """Distinct, exactly representable values per tick (4 decimals survive JSON); temperature
    sweeps 30..55 C, beyond the virtual chair's 40 C limit."""
    tl = Timeline.empty(N_TICKS)
    k = np.arange(N_TICKS)
    tl.vibration[:] = ((k[:, None] * 3 + np.arange(9)[None, :] * 11) % 101) / 100.0
    tl.temperature_c[:] = 30.0 + 25.0 * (k % 100) / 100.0
    tl.fans[:] = (((k[:, None, None] + np.arange(9)[None, :, None] * 17 + np.arange(17)[None, None, :]) % 7) / 8.0)
    return tl.validate()


def expected_frame(tl: Timeline, k: int, scale: float, muted_motors=(), neutral=33.0, lo=18.0, hi=40.0):
    """The documented quantisation (chair/comfort.py), written out independently."""
    motors = [0 if i in muted_motors else int(math.floor(min(max(float(v) * scale, 0.0), 1.0) * 255 + 0.5))
              for i, v in enumerate(tl.vibration[k].astype(np.float64))]
    fans = [int(math.floor(min(max(float(v) * scale, 0.0), 1.0) * 255 + 0.5)) for v in tl.fans[k].ravel()]
    t = min(max(neutral + scale * (float(tl.temperature_c[k]) - neutral), lo), hi)
    return motors, fans, int(math.floor(t * 100 + 0.5))


def wait_until(check, what: str, timeout_s: float = 10.0):
    deadline = time.monotonic() + timeout_s
    while True:
        value = check()
        if value:
            return value
        if time.monotonic() > deadline:
            pytest.fail(f"timed out after {timeout_s} s waiting until {what}")
        time.sleep(0.02)


def frames_after(chair: VirtualChair, index: int) -> list[dict]:
    """Frame entries after the first ``index`` log entries."""
    return [e for e in chair.read_log()[index:] if e["ev"] == "frame"]


def consecutive(ticks: list[int]) -> bool:
    return all(b == a + 1 for a, b in zip(ticks, ticks[1:]))


def check_segment(ticks: list[int], start: int, skipped: int) -> None:
    """A playback segment from ``start``: in order, no duplicates, and consecutive except for ticks
    the player skipped after a stall of this process (it counts them in ``ticks_skipped``)."""
    assert ticks and ticks[0] >= start, ticks
    assert all(b > a for a, b in zip(ticks, ticks[1:])), ticks
    assert (ticks[0] - start) + sum(b - a - 1 for a, b in zip(ticks, ticks[1:])) <= skipped, ticks


# ----------------------------------------------------------------------------- fixtures
@pytest.fixture(scope="module")
def film(tmp_path_factory) -> Path:
    path = tmp_path_factory.mktemp("chair-film") / "film.mp4"
    scene = Scene(duration_s=DURATION_S, background=(Segment(0.0, DURATION_S, (150, 60, 40)),),
                  audio=(Tone(2.0, 4.0, 60.0, level_dbfs=-14.0),), name="chair test")
    return write_scene(path, scene, width=64, height=36, fps=5, quality="low", sample_rate=24000)


@pytest.fixture(scope="module")
def client(tmp_path_factory):
    data = tmp_path_factory.mktemp("chair-server") / "data"
    with LocalClient(create_app(Settings(data_dir=data, frontend_dir=None))) as c:
        yield c


@pytest.fixture(scope="module")
def project(client, film) -> dict:
    """A generated project whose tracks are then replaced by ``known_timeline()`` (an import op).

    Generated with the thesis preset: its temperature range is 30..55 C, so the imported sweep keeps
    values above the chair's 40 C (the default mapping's range is the device's own, 18..40 C)."""
    r = client.post("/api/projects", files={"file": ("film.mp4", film.read_bytes(), "video/mp4")},
                    data={"mode": "audio", "preset": "thesis"})
    assert r.status_code == 201, r.text
    pid = r.json()["id"]
    job = wait_until(lambda: (j := client.get(f"/api/jobs/{r.json()['job']['id']}").json())["status"] in TERMINAL
                     and j, "the generation job ends", 120.0)
    assert job["status"] == "done", job
    doc = known_timeline().to_json().encode()
    r = client.post(f"/api/projects/{pid}/import", files={"file": ("known.json", doc, "application/json")})
    assert r.status_code == 200, r.text
    return client.get(f"/api/projects/{pid}").json()


@pytest.fixture
def connected(client, chair):
    """The service connected to ``chair`` with default settings; disconnected afterwards."""
    assert client.put("/api/chair/settings", json={"latency_ms": 0, "comfort": {"scale": 1, "mute": {
        "back": False, "armrests": False, "seat": False, "heat": False, "fans": False}}}).status_code == 200
    r = client.post("/api/chair/connect", json={"port": chair.device})
    assert r.status_code == 200, r.text
    yield chair
    client.post("/api/chair/disconnect")


def composed(client, pid: str) -> Timeline:
    """The composed timeline as the service holds it (exact values, not the 4-decimal JSON)."""
    return client.app.state.composer.compose(pid).timeline


def play(client, pid: str, position_s: float, state: str = "play", **extra):
    r = client.post("/api/chair/playback", json={"project_id": pid, "state": state, "position_s": position_s, **extra})
    assert r.status_code == 200, r.text
    return r.json()


# -------------------------------------------------------------------------------- tests
def test_ports_list_a_running_virtual_chair(client, sim_binary):
    with VirtualChair(name=f"server-{uuid.uuid4().hex[:8]}", binary=sim_binary) as vc:
        ports = client.get("/api/chair/ports").json()
        found = [p for p in ports if p["device"] == vc.device]
        assert len(found) == 1 and found[0]["kind"] == "virtual" and found[0]["likely_chair"]


def test_connect_status_events_and_disconnect(client, chair):
    r = client.post("/api/chair/connect", json={"port": chair.device})
    assert r.status_code == 200, r.text
    st = r.json()
    assert st["connected"] and st["state"] == "connected" and st["port"] == chair.device
    assert st["capabilities"]["name"] == "virtual-chair" and st["capabilities"]["temp_max_c"] == 40.0
    chair.wait_for(lambda e: e["ev"] == "hello")
    # The chair's own counters arrive with its STATUS replies (every 0.5 s).
    st = wait_until(lambda: (s := client.get("/api/chair/status").json())["diagnostics"]["chair"] and s,
                    "the chair's STATUS reaches the service")
    diag = st["diagnostics"]["chair"]
    assert diag["crc_errors"] == 0 and diag["length_errors"] == 0 and diag["safe"] is True
    assert diag["safe_reason"] == "boot"
    with client.stream("GET", "/api/chair/events") as resp:
        assert resp.headers["content-type"].startswith("text/event-stream")
        lines = resp.iter_lines()
        assert next(lines) == "event: status"
        first = json.loads(next(lines)[len("data: "):])
        assert first["connected"] and first["port"] == chair.device
        client.post("/api/chair/stop")  # a change is published at once
        events = []
        for line in lines:
            if line.startswith("data: "):
                events.append(json.loads(line[len("data: "):]))
                if len(events) == 2:
                    break
        assert all(e["connected"] for e in events)
    r = client.post("/api/chair/disconnect")
    assert r.status_code == 200 and not r.json()["connected"] and r.json()["state"] == "idle"
    chair.wait_for(lambda e: e["ev"] == "stop")


def test_errors_are_one_clear_sentence(client, project, tmp_path):
    missing = tmp_path / "no-chair-here"
    r = client.post("/api/chair/connect", json={"port": str(missing)})
    assert r.status_code == 409 and str(missing) in r.json()["detail"]
    assert "cannot open" in client.get("/api/chair/status").json()["error"]
    r = client.post("/api/chair/playback", json={"project_id": project["id"], "state": "play", "position_s": 0})
    assert r.status_code == 409 and "no chair is connected" in r.json()["detail"]
    r = client.post("/api/chair/push", json={"project_id": project["id"], "start_s": 0, "end_s": 1})
    assert r.status_code == 409
    assert client.post("/api/chair/stop").status_code == 200  # always accepted
    for body in ({"project_id": project["id"], "state": "rewind", "position_s": 0},
                 {"project_id": project["id"], "state": "play", "position_s": -1},
                 {"project_id": project["id"], "state": "play"}):
        r = client.post("/api/chair/playback", json=body)
        assert r.status_code == 400 and r.json()["detail"].startswith("field '")


@pytest.mark.parametrize("body, field", [
    ({"latency_ms": 500.5}, "latency_ms"),
    ({"latency_ms": -501}, "latency_ms"),
    ({"latency_ms": "soon"}, "latency_ms"),
    ({"comfort": {"scale": 1.2}}, "comfort.scale"),
    ({"comfort": {"scale": -0.1}}, "comfort.scale"),
    ({"comfort": {"mute": {"legs": True}}}, "comfort.mute.legs"),
    ({"volume": 3}, "volume"),
])
def test_settings_validation(client, body, field):
    before = client.get("/api/chair/settings").json()
    r = client.put("/api/chair/settings", json=body)
    assert r.status_code == 400, r.text
    assert r.json()["detail"].startswith(f"field '{field}'")
    assert client.get("/api/chair/settings").json() == before


def test_settings_are_stored_and_survive_a_restart(tmp_path):
    settings = Settings(data_dir=tmp_path / "data", frontend_dir=None)
    with LocalClient(create_app(settings)) as c:
        assert c.get("/api/chair/settings").json() == {"latency_ms": 0.0, "comfort": {"scale": 1.0, "mute": {
            "back": False, "armrests": False, "seat": False, "heat": False, "fans": False}}}
        r = c.put("/api/chair/settings", json={"latency_ms": -120, "comfort": {"scale": 0.5, "mute": {"heat": True}}})
        assert r.status_code == 200
        r = c.put("/api/chair/settings", json={"comfort": {"mute": {"fans": True}}})  # fields left out stay
        want = {"latency_ms": -120.0, "comfort": {"scale": 0.5, "mute": {
            "back": False, "armrests": False, "seat": False, "heat": True, "fans": True}}}
        assert r.json() == want
        assert c.get("/api/chair/status").json()["settings"] == want
    with LocalClient(create_app(settings)) as c:
        assert c.get("/api/chair/settings").json() == want


def test_playback_sends_the_composed_timeline_with_comfort_clamps_seek_and_pause(client, project, connected):
    chair, pid = connected, project["id"]
    r = client.put("/api/chair/settings", json={"comfort": {"scale": 0.8, "mute": {"armrests": True}}})
    assert r.status_code == 200
    tl = composed(client, pid)
    np.testing.assert_array_equal(tl.vibration, known_timeline().vibration)  # the import is what plays
    assert tl.temperature_c.max() > 50  # above the chair's limit: the backend clamps to 40 C

    play(client, pid, 1.0)
    chair.wait_for(lambda e: e["ev"] == "frame" and e["tick"] >= 24)
    # A heartbeat a little off the chair's clock corrects it without resending or skipping a tick.
    st = client.get("/api/chair/status").json()
    assert st["playing"] and st["playback"]["project_id"] == pid and st["playback"]["revision"] == project["revision"]
    play(client, pid, st["position_s"] - 0.03, heartbeat=True)
    chair.wait_for(lambda e: e["ev"] == "frame" and e["tick"] >= 30)
    mark = len(chair.read_log())
    play(client, pid, 26.0, state="seek")
    chair.wait_for(lambda e: e["ev"] == "frame" and e["tick"] >= 266)
    st = play(client, pid, 26.65, state="pause")
    assert st["playback"]["state"] == "paused" and not st["playing"]
    stop = chair.wait_for(lambda e: e["ev"] == "stop")
    assert stop["motors"] == [0] * 9 and stop["fans"] == [0] * 153 and stop["temp_target_cc"] == 3300

    log = chair.read_log()
    before_seek = [e for e in log[:mark] if e["ev"] == "frame"]
    after_seek = [e for e in log[mark:] if e["ev"] == "frame"]
    a, b = [e["tick"] for e in before_seek], [e["tick"] for e in after_seek]
    skipped = client.get("/api/chair/status").json()["playback"]["ticks_skipped"]
    check_segment(a, 10, skipped)
    check_segment(b, 260, skipped)
    assert client.get("/api/chair/status").json()["playback"]["drift_seeks"] == 0
    for e in before_seek + after_seek:
        motors, fans, temp_cc = expected_frame(tl, e["tick"], 0.8, muted_motors=ARMRESTS)
        assert (e["motors"], e["fans"], e["temp_target_cc"]) == (motors, fans, temp_cc), e["tick"]
    assert max(e["temp_target_cc"] for e in after_seek) == 4000  # clamped to the chair's safe range
    # After the pause no new frames come.
    entries = len(chair.read_log())
    time.sleep(0.5)
    assert frames_after(chair, entries) == []


def test_a_new_revision_while_playing_is_played(client, project, connected):
    chair, pid = connected, project["id"]
    play(client, pid, 2.0)
    chair.wait_for(lambda e: e["ev"] == "frame" and e["tick"] >= 22)
    rev = client.get(f"/api/projects/{pid}").json()["revision"]
    r = client.post(f"/api/projects/{pid}/edits", json={"base_revision": rev, "op": {
        "op": "set", "lanes": ["A1", "fans"], "t0": 40, "t1": 80, "value": 1.0}})
    assert r.status_code == 200, r.text
    chair.wait_for(lambda e: e["ev"] == "frame" and e["tick"] >= 45, timeout_s=5.0)
    assert client.get("/api/chair/status").json()["playback"]["revision"] == r.json()["revision"]
    client.post("/api/chair/stop")
    tl = composed(client, pid)
    edited = [e for e in chair.frames() if 40 <= e["tick"] <= 45]
    assert edited
    for e in edited:
        assert e["motors"][0] == 255 and e["fans"] == [255] * 153
        assert (e["motors"], e["fans"], e["temp_target_cc"]) == expected_frame(tl, e["tick"], 1.0)
    r = client.post(f"/api/projects/{pid}/undo", json={"base_revision": r.json()["revision"]})
    assert r.status_code == 200


def test_stop_turns_everything_off_and_only_a_play_resumes(client, project, connected):
    chair, pid = connected, project["id"]
    play(client, pid, 5.0)
    chair.wait_for(lambda e: e["ev"] == "frame" and e["tick"] >= 55)
    st = client.post("/api/chair/stop").json()
    assert st["playback"]["state"] == "stopped" and not st["playing"]
    stop = chair.wait_for(lambda e: e["ev"] == "stop")
    assert stop["motors"] == [0] * 9 and stop["fans"] == [0] * 153 and stop["temp_target_cc"] == 3300
    entries = len(chair.read_log())
    play(client, pid, 6.0, heartbeat=True)  # the browser's once-a-second report does not restart it
    time.sleep(0.4)
    assert frames_after(chair, entries) == []
    play(client, pid, 6.0)  # the viewer presses play
    chair.wait_for(lambda e: e["ev"] == "frame" and e["tick"] >= 62)
    resumed = [e["tick"] for e in frames_after(chair, entries)]
    check_segment(resumed, 60, client.get("/api/chair/status").json()["playback"]["ticks_skipped"])


def test_the_service_reconnects_and_resumes_when_the_chair_comes_back(client, project, sim_binary, tmp_path):
    pid = project["id"]
    device = tmp_path / "chair"
    first = VirtualChair(link_path=device, log_path=tmp_path / "a.jsonl", binary=sim_binary).start()
    second = VirtualChair(link_path=device, log_path=tmp_path / "b.jsonl", binary=sim_binary)
    try:
        assert client.post("/api/chair/connect", json={"port": str(device)}).status_code == 200
        play(client, pid, 0.0)
        first.wait_for(lambda e: e["ev"] == "frame" and e["tick"] >= 5)
        first.kill()  # the pty closes mid-stream (crash, unplug)
        st = wait_until(lambda: (s := client.get("/api/chair/status").json())["state"] == "reconnecting" and s,
                        "the service reports the lost chair")
        assert not st["connected"] and st["playing"]
        second.start()  # a chair comes back under the same path
        st = wait_until(lambda: (s := client.get("/api/chair/status").json())["connected"] and s,
                        "the service reconnects")
        assert st["reconnects"] == 1 and st["playback"]["state"] == "playing"
        resumed = second.wait_for(lambda e: e["ev"] == "frame")
        second.wait_for(lambda e: e["ev"] == "frame" and e["tick"] >= resumed["tick"] + 3)
        a = [e["tick"] for e in first.frames()]
        b = [e["tick"] for e in second.frames()]
        assert a[0] == 0 and b[0] >= a[-1] > 0  # resumed at the current position (resent), not from the start
        assert all(y > x for x, y in zip(a, a[1:])) and all(y > x for x, y in zip(b, b[1:]))
        assert second.read_log()[1]["ev"] == "hello"
        client.post("/api/chair/stop")
        second.wait_for(lambda e: e["ev"] == "stop")
    finally:
        client.post("/api/chair/disconnect")
        first.kill()
        second.stop()


def test_a_pages_initial_report_leaves_a_push_running_and_a_viewers_report_stops_it(client, project, connected):
    chair, pid = connected, project["id"]
    r = client.post("/api/chair/push", json={"project_id": pid, "start_s": 10.0, "end_s": 30.0})
    assert r.status_code == 202, r.text
    chair.wait_for(lambda e: e["ev"] == "frame" and e["tick"] >= 102)
    for state in ("seek", "play"):  # a page that connects tells where its player is: no viewer's action
        st = play(client, pid, 3.0, state, initial=True)
        assert st["push"]["state"] == "running", st["push"]
    chair.wait_for(lambda e: e["ev"] == "frame" and e["tick"] >= 106)
    assert client.get("/api/chair/status").json()["push"]["state"] == "running"
    st = play(client, pid, 3.0, "seek")  # the viewer seeks: the player takes the chair over
    assert st["push"]["state"] == "cancelled"


def test_push_a_range_and_stop_cancels_a_push(client, project, connected):
    chair, pid = connected, project["id"]
    tl = composed(client, pid)
    r = client.post("/api/chair/push", json={"project_id": pid, "start_s": 5.0, "end_s": 6.5})
    assert r.status_code == 202, r.text
    assert r.json()["push"]["state"] == "running" and r.json()["playing"]
    r = client.post("/api/chair/push", json={"project_id": pid, "start_s": 0, "end_s": 1})
    assert r.status_code == 409
    st = wait_until(lambda: (s := client.get("/api/chair/status").json())["push"]["state"] != "running" and s,
                    "the push ends")
    assert st["push"]["state"] == "done" and st["push"]["progress"] == 1.0
    chair.wait_for(lambda e: e["ev"] == "stop")
    ticks = [e["tick"] for e in chair.frames()]
    assert ticks == list(range(50, 65))
    for e in chair.frames():
        assert (e["motors"], e["fans"], e["temp_target_cc"]) == expected_frame(tl, e["tick"], 1.0)
    r = client.post("/api/chair/push", json={"project_id": pid, "start_s": 10.0, "end_s": 30.0})
    assert r.status_code == 202
    chair.wait_for(lambda e: e["ev"] == "frame" and e["tick"] >= 103)
    st = client.post("/api/chair/stop").json()
    chair.wait_for(lambda e: e["ev"] == "stop", count=2)
    st = wait_until(lambda: (s := client.get("/api/chair/status").json())["push"]["state"] != "running" and s,
                    "the cancelled push ends")
    assert st["push"]["state"] == "cancelled"
    for body in ({"project_id": pid, "start_s": 40.0, "end_s": 50.0}, {"project_id": pid, "start_s": 3, "end_s": 2}):
        r = client.post("/api/chair/push", json=body)
        assert r.status_code == 400 and "push range is empty" in r.json()["detail"]
