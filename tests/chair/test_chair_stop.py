"""STOP is final (docs/API.md "Chair", issue 17): against the virtual chair, 20 rounds of a push
stopped at a different phase of the 100 ms tick each time. Once ``POST /api/chair/stop`` has
answered, no frame of that push reaches the chair, the answer says the push is cancelled, and the
next push, sent at once, is accepted (202)."""

from __future__ import annotations

import time


from test_chair_server import TERMINAL, client, film, project  # noqa: F401 (fixtures: the known 30 s timeline)

ROUNDS = 20
ROUND_TICKS = 14  # each round pushes its own 1.4 s of the 30 s timeline, so a frame names its round


def push(client, pid: str, k: int) -> dict:
    start = k * ROUND_TICKS / 10
    r = client.post("/api/chair/push", json={"project_id": pid, "start_s": start, "end_s": start + 1.3})
    assert r.status_code == 202, (k, r.status_code, r.text)
    return r.json()


def test_no_frame_of_a_stopped_push_reaches_the_chair(client, project, chair):
    pid = project["id"]
    assert client.put("/api/chair/settings", json={"latency_ms": 0}).status_code == 200
    assert client.post("/api/chair/connect", json={"port": chair.device}).status_code == 200
    try:
        push(client, pid, 0)
        for k in range(ROUNDS):
            chair.wait_for(lambda e: e["ev"] == "frame" and e["tick"] // ROUND_TICKS == k)
            time.sleep((k % 5) * 0.021)  # STOP at another phase of the tick each round
            r = client.post("/api/chair/stop")
            assert r.status_code == 200, r.text
            assert r.json()["push"]["state"] == "cancelled" and not r.json()["playing"], r.json()
            if k + 1 < ROUNDS:
                push(client, pid, k + 1)  # right after the STOP: accepted, no 409
        time.sleep(0.4)  # a late frame would be in the log by now
        assert client.get("/api/chair/status").json()["push"]["state"] in TERMINAL
    finally:
        client.post("/api/chair/disconnect")
    rounds_played, stopped = [], set()
    for entry in chair.read_log():
        if entry["ev"] == "stop" and rounds_played:
            stopped.add(rounds_played[-1])
        elif entry["ev"] == "frame":
            k = entry["tick"] // ROUND_TICKS
            assert k not in stopped, f"a frame of round {k} (tick {entry['tick']}) reached the chair after its STOP"
            rounds_played.append(k)
    assert sorted(set(rounds_played)) == list(range(ROUNDS))
    assert len(stopped) == ROUNDS
