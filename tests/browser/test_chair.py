"""The chair in the editor, end to end: a real browser plays a clip while the editor is connected
(through its chair panel) to a virtual chair, and the chair's own log is checked frame by frame
against the composed timeline after comfort scaling and clamps (autohaptics/chair/comfort.py);
seek, pause, STOP (button and Escape), the panel's settings and pushing a selection.

The module runs its own ``autohaptics serve`` so the test can read the composed timeline exactly
(from the data folder) rather than through the 4-decimal JSON.
"""

from __future__ import annotations

import math
import time
import uuid

import httpx
import numpy as np
import pytest

from autohaptics.chair import VirtualChair
from autohaptics.server.chair import DRIFT_SEEK_S
from autohaptics.server.store import Store
from autohaptics.server.composer import Composer
from browser_support import (
    ServerError, api_client, checked_page, media_clip, open_editor, start_server, stop_server, upload, wait_until,
)

pytestmark = pytest.mark.browser

CLIP = "sintel_trailer_480x204_h264_aac.mp4"
ARMRESTS = (2, 6)  # A3, A7 (layout zone "armrests")
VIEWPORT = {"width": 1440, "height": 900}


@pytest.fixture(scope="module")
def chair_server(tmp_path_factory):
    root = tmp_path_factory.mktemp("chair-e2e")
    try:
        proc, url = start_server(root)
    except ServerError as exc:
        pytest.fail(str(exc))
    yield url, root / "data"
    stop_server(proc)


@pytest.fixture(scope="module")
def chair_api(chair_server):
    with api_client(chair_server[0], timeout=60.0) as client:
        yield client


@pytest.fixture(scope="module")
def film(chair_api) -> dict:
    return upload(chair_api, media_clip(CLIP), name="sintel")


@pytest.fixture
def chair(tmp_path):
    """A virtual chair under a unique name, so the server's port list shows it."""
    with VirtualChair(name=f"e2e-{uuid.uuid4().hex[:8]}", log_path=tmp_path / "chair.jsonl") as vc:
        yield vc


@pytest.fixture
def cpage(browser, chair_server, chair_api):
    try:
        with checked_page(browser, chair_server[0], VIEWPORT) as pg:
            yield pg
    finally:
        chair_api.post("/api/chair/disconnect")


def composed(data_dir, pid: str):
    """The composed timeline exactly as the server composes it (same files, same code)."""
    store = Store(data_dir)
    try:
        return Composer(store).compose(pid).timeline
    finally:
        store.close()


def expected_frame(tl, k: int, scale: float, muted_motors=(), neutral=33.0, lo=18.0, hi=40.0):
    """The documented quantisation (chair/comfort.py), written out independently."""
    motors = [0 if i in muted_motors else int(math.floor(min(max(float(v) * scale, 0.0), 1.0) * 255 + 0.5))
              for i, v in enumerate(tl.vibration[k].astype(np.float64))]
    fans = [int(math.floor(min(max(float(v) * scale, 0.0), 1.0) * 255 + 0.5)) for v in tl.fans[k].ravel()]
    t = min(max(neutral + scale * (float(tl.temperature_c[k]) - neutral), lo), hi)
    return motors, fans, int(math.floor(t * 100 + 0.5))


def connect_in_the_panel(pg, device: str) -> None:
    pg.click("[data-testid=chair-refresh]")
    pg.wait_for_selector(f"[data-testid=chair-port] option[value='{device}']", state="attached")
    pg.select_option("[data-testid=chair-port]", device)
    pg.click("[data-testid=chair-connect]")
    pg.wait_for_selector("[data-testid=chair-state][data-state=connected]")
    pg.wait_for_function("() => window.autohaptics.state().chair && window.autohaptics.state().chair.reporting")


def video_time(pg) -> float:
    return pg.evaluate("() => document.querySelector('[data-testid=video]').currentTime")


def seek_video(pg, t: float) -> None:
    pg.evaluate("(t) => { document.querySelector('[data-testid=video]').currentTime = t; }", t)
    pg.wait_for_function("(t) => { const v = document.querySelector('[data-testid=video]');"
                         " return !v.seeking && Math.abs(v.currentTime - t) < 0.5; }", arg=t)


def clocks(pg) -> tuple[float, float]:
    """(the page's clock, the video's position), s, read together."""
    wall, pos = pg.evaluate("() => [performance.now() / 1000, document.querySelector('[data-testid=video]').currentTime]")
    return float(wall), float(pos)


def log_index(chair) -> int:
    return len(chair.read_log())


def frames_since(chair, index: int) -> list[dict]:
    return [e for e in chair.read_log()[index:] if e["ev"] == "frame"]


def runs(entries: list[dict]) -> list[list[int]]:
    """Tick runs of the log: a new run after every STOP and wherever the tick does not go up by one."""
    out: list[list[int]] = []
    current: list[int] = []
    for e in entries:
        if e["ev"] == "stop":
            if current:
                out.append(current)
            current = []
        elif e["ev"] == "frame":
            if current and e["tick"] != current[-1] + 1:
                out.append(current)
                current = []
            current.append(e["tick"])
    if current:
        out.append(current)
    return out


DIAGRAM_SHOWS = """() => {
    const host = document.querySelector('[data-testid=chair-diagram]');
    const tick = Number(host.dataset.tick);
    const ids = Array.from(host.querySelectorAll('[data-testid^=chair-A]')).map((g) => g.dataset.testid.slice(6));
    const v = window.autohaptics.valuesAt(tick);
    return {source: host.dataset.source, tick, title: document.querySelector('[data-testid=chair-diagram-title]').textContent,
            values: Array.from(host.querySelectorAll('[data-testid^=chair-A]')).map((g) => g.dataset.value),
            expected: ids.map((_, i) => v.vibration[i].toFixed(3))};
}"""


def test_the_editor_plays_on_the_virtual_chair(cpage, chair_api, chair_server, film, chair):
    pg, pid = cpage, film["id"]
    open_editor(pg, pid)
    pg.wait_for_function("() => document.querySelector('[data-testid=video]').readyState >= 2")
    assert pg.is_visible("[data-testid=chair-stop]")
    connect_in_the_panel(pg, chair.device)
    chair.wait_for(lambda e: e["ev"] == "hello")

    # Comfort from the panel: intensity 0.8 (four keyboard steps of 0.05), armrests muted, 0 ms.
    pg.focus("[data-testid=chair-intensity]")
    for _ in range(4):
        pg.keyboard.press("ArrowLeft")
    pg.click("[data-testid=chair-mute-armrests]")
    pg.fill("[data-testid=chair-latency]", "0")
    pg.press("[data-testid=chair-latency]", "Enter")
    wait_until(lambda: chair_api.get("/api/chair/settings").json()["comfort"] == {
        "scale": 0.8, "mute": {"back": False, "armrests": True, "seat": False, "heat": False, "fans": False}},
        "the panel's comfort settings reach the server")
    # the chip shows what the server answered (its answer may come a moment after the server has it)
    pg.wait_for_function("() => document.querySelector('[data-testid=chair-mute-armrests]')"
                         ".getAttribute('aria-pressed') === 'true'")

    seek_video(pg, 2.0)
    start = log_index(chair)
    pg.click("[data-testid=play]")
    a0 = clocks(pg)
    chair.wait_for(lambda e: e["ev"] == "frame" and e["tick"] >= 48, timeout_s=15.0)  # 2.8 s of film played

    # A seek while playing: the ticks jump to the new position.
    a1 = clocks(pg)
    seek_video(pg, 30.0)
    b0 = clocks(pg)
    first = chair.wait_for(lambda e: e["ev"] == "frame" and e["tick"] >= 300, timeout_s=15.0)["tick"]
    video_then = clocks(pg)[1]  # where the video is once the chair has its first frame after the seek
    chair.wait_for(lambda e: e["ev"] == "frame" and e["tick"] >= 318, timeout_s=15.0)
    assert pg.evaluate("() => window.autohaptics.state().playing")
    b1 = clocks(pg)
    # how far the video itself fell behind the page's clock while playing (a starved browser
    # stalls its video; the server then moves the chair back to where the video is: a drift seek)
    lag = max(0.0, (a1[0] - a0[0]) - (a1[1] - a0[1])) + max(0.0, (b1[0] - b0[0]) - (b1[1] - b0[1]))

    # Pause: STOP on the chair and no frames afterwards. The STOP waited for is the pause's: a starved
    # browser that stalled its video earlier had the chair stopped then too (a pause on stall).
    def is_stop(e: dict) -> bool:
        return e["ev"] == "stop" and e["t_ms"] > 0

    stops_before = sum(1 for e in chair.read_log() if is_stop(e))
    pg.click("[data-testid=play]")
    pg.wait_for_function("() => document.querySelector('[data-testid=video]').paused")
    chair.wait_for(is_stop, count=stops_before + 1)
    paused_at = log_index(chair)
    time.sleep(0.6)
    assert frames_since(chair, paused_at) == []

    entries = chair.read_log()[start:]
    status = chair_api.get("/api/chair/status").json()
    skipped = status["playback"]["ticks_skipped"]
    # a video that stalls waiting for data pauses the chair and plays it again from where the video
    # is (a STOP before the one of the pause): the ticks may then go back, as after a re-seek
    stalls = sum(e["ev"] == "stop" for e in chair.read_log()[start:paused_at]) - 1
    seeks = status["playback"]["drift_seeks"]
    restarts = seeks + stalls
    if lag <= DRIFT_SEEK_S:  # the video kept time: the chair follows it without a single re-seek
        assert seeks == 0, (status["playback"], lag)
    else:  # at most one re-seek per drift limit the video fell behind, and one for where it ended
        assert seeks <= lag / DRIFT_SEEK_S + 1, (status["playback"], lag)
    ticks = runs(entries)
    before = [r for r in ticks if r[0] < 300]
    after = [r for r in ticks if r[0] >= 300]
    # Before the seek: one run from the play position (2.0 s) without duplicates or gaps (a gap only
    # where the server skipped ticks after a stall, which it counts; a new run where it re-seeks).
    assert before and 20 <= before[0][0] <= 21, ticks
    assert sum(len(r) for r in before) + skipped >= before[-1][-1] - before[0][0] + 1, ticks
    flat = [t for r in before for t in r]
    if not restarts:
        assert all(b > a for a, b in zip(flat, flat[1:])), ticks
    assert len(before) <= 1 + skipped + restarts, ticks
    # After the seek: from 30.0 s on, in order. The chair starts where the video is when the page
    # reports it: 30.0 s, or a little later on a busy machine where the report (or a play report after
    # the video waited for data) goes out once the video has moved on; never ahead of the video.
    assert after and after[0][0] == first and 300 <= first <= math.floor(video_then * 10) + 1, (ticks, video_then)
    flat = [t for r in after for t in r]
    if not restarts:
        assert all(b > a for a, b in zip(flat, flat[1:])), ticks

    # Every frame holds the composed timeline after comfort and the device's clamps.
    tl = composed(chair_server[1], pid)
    frames = [e for e in entries if e["ev"] == "frame"]
    assert len(frames) > 30
    for e in frames:
        assert (e["motors"], e["fans"], e["temp_target_cc"]) == expected_frame(tl, e["tick"], 0.8, ARMRESTS), e["tick"]
    assert all(e["motors"][i] == 0 for e in frames for i in ARMRESTS)

    # The panel shows what the chair got.
    pg.wait_for_function("() => Number(document.querySelector('[data-testid=chair-frames]').textContent) > 30")
    last = status["last_tick"]
    assert pg.text_content("[data-testid=chair-last-tick]").startswith(str(last))
    assert pg.text_content("[data-testid=chair-errors]") == "CRC 0 · length 0"


def test_stop_button_and_escape_turn_everything_off_at_once(cpage, chair_api, film, chair):
    pg, pid = cpage, film["id"]
    open_editor(pg, pid)
    pg.wait_for_function("() => document.querySelector('[data-testid=video]').readyState >= 2")
    connect_in_the_panel(pg, chair.device)
    for press in (lambda: pg.click("[data-testid=chair-stop]"), lambda: pg.keyboard.press("Escape")):
        seek_video(pg, 10.0)
        start = log_index(chair)
        pg.click("[data-testid=play]")
        played = [e for e in chair.read_log()[:start] if e["ev"] == "frame" and 105 <= e["tick"] < 200]
        chair.wait_for(lambda e: e["ev"] == "frame" and 105 <= e["tick"] < 200, timeout_s=15.0,
                       count=len(played) + 1)  # a frame of this round's playing
        pg.locator("[data-testid=timeline]").focus()
        before = log_index(chair)
        t0 = time.monotonic()
        press()
        press_s = time.monotonic() - t0  # the click or key going through the browser, slow on a busy machine
        stop = chair.wait_for(lambda e: e["ev"] == "stop" and e["t_ms"] > 0, count=len(
            [e for e in chair.read_log()[:before] if e["ev"] == "stop"]) + 1)
        assert stop["motors"] == [0] * 9 and stop["fans"] == [0] * 153 and stop["temp_target_cc"] == 3300
        assert stop["safe"] is True
        pg.wait_for_function("() => document.querySelector('[data-testid=video]').paused")
        settled = log_index(chair)
        time.sleep(1.3)  # longer than a heartbeat: the heartbeat does not restart a stopped chair
        late = frames_since(chair, settled)
        assert not late, [(e["tick"], e["seq"], e["t_ms"]) for e in late]
        # At most the frame that was on the wire when the button was pressed comes before the STOP,
        # plus one per 100 ms tick the press itself took to go through Playwright and the browser
        # (on a loaded CI machine that took longer than a tick once: frame, frame, stop)
        between = [e for e in chair.read_log()[before:] if e["ev"] in ("frame", "stop")]
        assert [e["ev"] for e in between].index("stop") <= 1 + int(press_s / 0.1), (between, press_s)
    st = chair_api.get("/api/chair/status").json()
    assert st["playback"]["state"] in ("stopped", "paused") and not st["playing"]


def test_stop_wins_over_a_play_report_that_arrives_after_it(cpage, chair_api, film, chair):
    """A play report already on its way when STOP is pressed may reach the server after the STOP
    (separate connections) and restart the chair; the editor stops again once it has landed, and
    does not count on the pause report that follows (held here until the end)."""
    pg, pid = cpage, film["id"]
    open_editor(pg, pid)
    pg.wait_for_function("() => document.querySelector('[data-testid=video]').readyState >= 2")
    connect_in_the_panel(pg, chair.device)
    seek_video(pg, 10.0)
    held = []

    def hold(route):
        if not held and '"play"' not in (route.request.post_data or ""):
            route.continue_()  # a report of the seek before it, sent late: let it through
        else:
            held.append(route)  # the play report and every report after it held on the wire

    pg.route("**/api/chair/playback", hold)
    pg.click("[data-testid=play]")
    pg.wait_for_function("() => !document.querySelector('[data-testid=video]').paused")
    deadline = time.monotonic() + 10
    while not held and time.monotonic() < deadline:
        pg.wait_for_timeout(20)
    assert held and '"play"' in (held[0].request.post_data or ""), "the play report never went out"
    stops = len([e for e in chair.read_log() if e["ev"] == "stop"])
    pg.click("[data-testid=chair-stop]")
    chair.wait_for(lambda e: e["ev"] == "stop", count=stops + 1)
    pg.wait_for_function("() => document.querySelector('[data-testid=video]').paused")
    late = log_index(chair)
    # the late play report: the server starts playing (whether a frame goes out before the editor's
    # second STOP lands is a matter of timing) ...
    held.pop(0).continue_()
    chair.wait_for(lambda e: e["ev"] == "stop", count=stops + 2, timeout_s=10.0)  # ... and STOP again
    assert len(frames_since(chair, late)) <= 3
    settled = log_index(chair)
    time.sleep(1.3)
    after = frames_since(chair, settled)
    assert not after, [(e["tick"], e["seq"], e["t_ms"]) for e in after]
    assert not chair_api.get("/api/chair/status").json()["playing"]
    pg.unroute("**/api/chair/playback", hold)
    for route in held:
        route.continue_()


def test_the_port_list_defaults_to_a_chair_that_appears_after_the_page_opened(cpage, film, request):
    """The editor opens with a plain serial port alone in the list; a virtual chair starts; ↻ picks
    the chair, not the port the list showed first. A port the user picked stays picked."""
    pg, mine = cpage, {}
    plain = "/dev/ttyS0"

    def ports(route) -> None:  # the real list, with only this test's chair and always a plain port
        listed = [p for p in route.fetch().json() if not p["likely_chair"] or p["device"] == mine.get("device")]
        if not any(p["device"] == plain for p in listed):
            listed.append({"device": plain, "description": "n/a", "kind": "serial", "likely_chair": False})
        route.fulfill(json=listed)

    pg.route("**/api/chair/ports", ports)
    open_editor(pg, film["id"])
    pg.wait_for_selector(f"[data-testid=chair-port] option[value='{plain}']", state="attached")
    assert pg.input_value("[data-testid=chair-port]") == plain
    mine["device"] = request.getfixturevalue("chair").device  # the virtual chair starts now
    pg.click("[data-testid=chair-refresh]")
    pg.wait_for_selector(f"[data-testid=chair-port] option[value='{mine['device']}']", state="attached")
    assert pg.input_value("[data-testid=chair-port]") == mine["device"]
    # Picked by the user: kept through a refresh although a chair is listed.
    pg.select_option("[data-testid=chair-port]", plain)
    pg.evaluate("() => document.querySelectorAll('[data-testid=chair-port] option').forEach((o) => { o.dataset.old = '1'; })")
    pg.click("[data-testid=chair-refresh]")
    pg.wait_for_function("() => !document.querySelector('[data-testid=chair-port] option[data-old]')")  # listed anew
    assert pg.input_value("[data-testid=chair-port]") == plain


def test_push_the_selection_and_disconnect(cpage, chair_api, film, chair):
    pg, pid = cpage, film["id"]
    open_editor(pg, pid)
    connect_in_the_panel(pg, chair.device)
    assert pg.text_content("[data-testid=chair-push]") == "Push whole film"
    pg.evaluate("() => window.autohaptics.state()")
    rect = pg.evaluate("() => window.autohaptics.laneRect('actuators')")
    x0 = pg.evaluate("() => window.autohaptics.clientXOf(4.0)")
    x1 = pg.evaluate("() => window.autohaptics.clientXOf(5.0)")
    pg.mouse.move(x0, rect["y"] + 5)
    pg.mouse.down()
    pg.mouse.move(x1, rect["y"] + 5, steps=4)
    pg.mouse.up()
    sel = pg.evaluate("() => window.autohaptics.state().selection")
    assert sel is not None
    assert pg.text_content("[data-testid=chair-push]") == "Push selection"
    pg.click("[data-testid=chair-push]")
    pg.wait_for_selector("[data-testid=chair-push-progress]:not([hidden])")
    chair.wait_for(lambda e: e["ev"] == "stop", timeout_s=10.0)
    ticks = [e["tick"] for e in chair.frames()]
    assert ticks == list(range(sel["t0"], sel["t1"])), ticks
    pg.wait_for_function("() => document.querySelector('[data-testid=chair-push-progress]')"
                         ".getAttribute('aria-valuenow') === '100'")
    pg.click("[data-testid=chair-connect]")  # now "Disconnect"
    pg.wait_for_selector("[data-testid=chair-state][data-state=idle]")
    assert pg.text_content("[data-testid=chair-indicator]") == "Chair off"


def test_a_push_shows_where_the_chair_is_and_how_far_it_has_got(cpage, chair_api, film, chair):
    pg, pid = cpage, film["id"]
    open_editor(pg, pid)
    connect_in_the_panel(pg, chair.device)
    rect = pg.evaluate("() => window.autohaptics.laneRect('actuators')")
    pg.mouse.move(pg.evaluate("() => window.autohaptics.clientXOf(2.0)"), rect["y"] + 5)
    pg.mouse.down()
    pg.mouse.move(pg.evaluate("() => window.autohaptics.clientXOf(6.0)"), rect["y"] + 5, steps=4)
    pg.mouse.up()
    sel = pg.evaluate("() => window.autohaptics.state().selection")
    playhead = pg.evaluate("() => window.autohaptics.state().playheadS")
    pg.click("[data-testid=chair-push]")
    # While it plays: the chair's own playhead on the timeline, and in words where it is and how far.
    pg.wait_for_function("() => /^Chair at \\d+:\\d\\d\\.\\d · \\d+ % of /.test("
                         "document.querySelector('[data-testid=chair-push-text]').textContent)")
    head = pg.locator("[data-testid=chair-head]")
    assert head.is_visible()
    x = head.bounding_box()["x"] + 1
    t0, t1 = sel["t0"] * 0.1, sel["t1"] * 0.1
    assert pg.evaluate("() => window.autohaptics.clientXOf(%f)" % (t0 - 0.15)) <= x <= pg.evaluate(
        "() => window.autohaptics.clientXOf(%f)" % (t1 + 0.15))
    assert pg.evaluate("() => window.autohaptics.state().playheadS") == playhead, "the player stays where it was"
    text = pg.text_content("[data-testid=chair-push-text]")
    def clock(t: float) -> str:
        return f"{int(t // 60)}:{t % 60:04.1f}"

    assert text.endswith(f"of {clock(t0)}–{clock(t1)}"), text
    # The "At the playhead" diagram follows the chair, not the player: its values are those at the
    # chair's tick (inside the pushed range), read in one go with the editor's own values there.
    shown = pg.evaluate(DIAGRAM_SHOWS)
    assert shown["source"] == "chair" and shown["title"].startswith("At the chair · "), shown
    assert sel["t0"] <= shown["tick"] < sel["t1"], (shown, sel)
    assert shown["values"] == shown["expected"], shown
    chair.wait_for(lambda e: e["ev"] == "stop", timeout_s=15.0)
    pg.wait_for_function("() => document.querySelector('[data-testid=chair-push-text]').textContent.endsWith('done')")
    assert not head.is_visible(), "the chair's playhead goes when the push ends"
    pg.wait_for_function("() => document.querySelector('[data-testid=chair-diagram]').dataset.source === 'playhead'")
    shown = pg.evaluate(DIAGRAM_SHOWS)
    assert shown["title"] == "At the playhead" and shown["values"] == shown["expected"], shown
    assert pg.text_content("[data-testid=chair-frames]") != "–"


def test_the_editors_report_on_connecting_leaves_a_running_push_alone(cpage, chair_api, film, chair):
    pg, pid = cpage, film["id"]
    # The editor's first report (where its player is) held back until the push below is under way.
    pg.add_init_script("""(() => { const send = window.fetch; window.fetch = async (...args) => {
        if (String(args[0] && args[0].url || args[0]).includes('/api/chair/playback'))
            await new Promise((done) => setTimeout(done, 250));
        return send(...args); }; })()""")
    open_editor(pg, pid)
    connect_in_the_panel(pg, chair.device)
    r = chair_api.post("/api/chair/push", json={"project_id": pid, "start_s": 1.0, "end_s": 2.0})
    assert r.status_code == 202, r.text
    pg.wait_for_function("() => !window.autohaptics.state().chair.reportsPending")  # the report landed
    assert chair_api.get("/api/chair/status").json()["push"]["state"] in ("running", "done")
    chair.wait_for(lambda e: e["ev"] == "stop", timeout_s=10.0)
    pg.wait_for_function("() => document.querySelector('[data-testid=chair-push-text]').textContent.endsWith('done')")
    assert [e["tick"] for e in chair.frames()] == list(range(10, 20)), "the whole range reached the chair"


def test_the_chair_counters_are_the_open_projects_own(cpage, chair_api, film, chair):
    pg, pid = cpage, film["id"]
    other = chair_api.post(f"/api/projects/{pid}/duplicate").json()
    try:
        open_editor(pg, pid)
        connect_in_the_panel(pg, chair.device)
        r = chair_api.post("/api/chair/push", json={"project_id": pid, "start_s": 1.0, "end_s": 1.5})
        assert r.status_code == 202, r.text
        chair.wait_for(lambda e: e["ev"] == "stop", timeout_s=10.0)
        pg.wait_for_function("() => document.querySelector('[data-testid=chair-push-text]').textContent.endsWith('done')")
        frames = pg.text_content("[data-testid=chair-frames]")
        assert frames.isdigit() and int(frames) >= 5, frames
        assert pg.text_content("[data-testid=chair-last-tick]") == "14 (0:01.4)"
        # Another project opened in the same page: the chair's counters are not its own.
        pg.goto("/#/")
        open_editor(pg, other["id"])
        pg.wait_for_selector("[data-testid=chair-state][data-state=connected]")
        assert pg.text_content("[data-testid=chair-frames]") == "–"
        assert pg.text_content("[data-testid=chair-last-tick]") == "–"
        assert pg.locator("[data-testid=chair-push-text]").is_hidden(), "the other project's push is not shown"
        # Back on the first project, they are its again.
        pg.goto("/#/")
        open_editor(pg, pid)
        pg.wait_for_selector("[data-testid=chair-state][data-state=connected]")
        assert pg.text_content("[data-testid=chair-frames]") == frames
        assert pg.text_content("[data-testid=chair-last-tick]") == "14 (0:01.4)"
    finally:
        chair_api.delete(f"/api/projects/{other['id']}")
