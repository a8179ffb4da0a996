"""Shots in the editor (issue 33): the Shots lane (filmstrip) and the shot lines, selecting shots
(click, Shift-click, double-click to play), selections snapping to shot boundaries (Alt: not),
split and merge at the playhead, the Shots panel, operations on several shots as one undo step,
copying a shot's effects onto other shots fitted to each, and selecting similar shots. Every
gesture at 1366x768 and 1920x1080; results read from the composed timeline the server returns."""

from __future__ import annotations

import pytest

from browser_support import checked_page, lane_rect, next_frame, open_editor, screenshot, state, wait_revision_above, wait_until

pytestmark = pytest.mark.browser

VIEWPORTS = [pytest.param({"width": 1366, "height": 768}, id="1366x768"),
             pytest.param({"width": 1920, "height": 1080}, id="1920x1080")]
LANE_BG = (18, 21, 28)


@pytest.fixture(params=VIEWPORTS)
def vpage(request, browser, server):
    with checked_page(browser, server, request.param) as pg:
        yield pg


def shots_of(api, pid: str) -> dict:
    r = api.get(f"/api/projects/{pid}/shots")
    assert r.status_code == 200, r.text
    return r.json()


def open_with_shots(pg, api, pid: str) -> dict:
    """Open the editor and wait until it holds the server's shot list; returns that list."""
    doc = shots_of(api, pid)
    open_editor(pg, pid)
    pg.wait_for_function("(n) => { const s = window.autohaptics.state(); return s.shots.count === n; }", arg=len(doc["shots"]))
    return doc


def actuators(pg) -> list[str]:
    return pg.eval_on_selector_all("[data-testid^=lane-chip-]", "cs => cs.map((c) => c.dataset.testid.slice(10))")[:9]


def values(api, pid: str, lanes: list[str], t0: int, t1: int) -> dict:
    r = api.get(f"/api/projects/{pid}/timeline/values", params={"lanes": ",".join(lanes), "t0": t0, "t1": t1})
    assert r.status_code == 200, r.text
    return r.json()["values"]


def shot_x(pg, shot: dict, tick_s: float, at: float = 0.5) -> float:
    """Client x inside a shot (``at``: 0 its start .. 1 its end)."""
    return pg.evaluate("(t) => window.autohaptics.clientXOf(t)", (shot["t0"] + at * (shot["t1"] - shot["t0"])) * tick_s)


def lane_y(pg, lane: str) -> float:
    r = lane_rect(pg, lane)
    return r["y"] + r["height"] / 2


def click_shot(pg, shot: dict, tick_s: float, modifiers: list[str] | None = None) -> None:
    pg.mouse.move(shot_x(pg, shot, tick_s), lane_y(pg, "shots"))
    for m in modifiers or []:
        pg.keyboard.down(m)
    pg.mouse.down()
    pg.mouse.up()
    for m in modifiers or []:
        pg.keyboard.up(m)


def lane_pixel(pg, lane: str, x: float, y: float) -> tuple[int, int, int]:
    return tuple(pg.evaluate(
        """([lane, x, y]) => {
            const c = document.querySelector(`canvas[data-lane="${lane}"]`);
            const r = c.getBoundingClientRect();
            const k = c.width / r.width;
            return Array.from(c.getContext('2d').getImageData(Math.floor((x - r.x) * k), Math.floor((y - r.y) * k), 1, 1).data.slice(0, 3));
        }""", [lane, x, y]))


def wide_shots(doc: dict, n: int, min_ticks: int = 12) -> list[dict]:
    """``n`` shots of at least ``min_ticks`` ticks, not neighbours of each other, in film order."""
    out, last = [], -10
    for i, s in enumerate(doc["shots"]):
        if s["t1"] - s["t0"] >= min_ticks and i > last + 1:
            out.append(s)
            last = i
        if len(out) == n:
            return out
    pytest.skip(f"the film has fewer than {n} separate shots of {min_ticks} ticks")


def test_shots_lane_draws_the_film_and_shot_lines_cross_every_lane(vpage, api, project_copy):
    pid = project_copy["id"]
    doc = open_with_shots(vpage, api, pid)
    assert len(doc["shots"]) >= 4
    vpage.wait_for_function("() => window.autohaptics.state().shots.pictures.ready > 0")
    next_frame(vpage)
    rect = lane_rect(vpage, "shots")
    lit = vpage.evaluate(
        """() => { const c = document.querySelector('canvas[data-lane="shots"]');
            const d = c.getContext('2d').getImageData(0, 0, c.width, c.height).data; const seen = new Set();
            for (let i = 0; i < d.length; i += 4 * 97) seen.add((d[i] << 16) | (d[i + 1] << 8) | d[i + 2]);
            return seen.size; }""")
    assert lit > 20, "the Shots lane shows pictures, not flat colour"
    screenshot(vpage, f"shots-lane-{vpage.viewport_size['width']}")
    tick_s = doc["tick_s"]
    # A faint line at a boundary on an empty lane (markers: no markers in this project), none mid-shot.
    shots = doc["shots"]
    s = next((shots[i] for i in range(1, len(shots)) if shots[i]["t1"] - shots[i]["t0"] >= 12
              and shots[i - 1]["t1"] - shots[i - 1]["t0"] >= 4), None)
    assert s is not None
    mr = lane_rect(vpage, "markers")
    y = mr["y"] + mr["height"] - 3
    x_line = vpage.evaluate("(t) => Math.round(window.autohaptics.clientXOf(t))", s["t0"] * tick_s)
    assert lane_pixel(vpage, "markers", x_line + 0.5, y) != LANE_BG
    assert lane_pixel(vpage, "markers", shot_x(vpage, s, tick_s), y) == LANE_BG
    # The lane follows zoom: zoomed in, it draws another part of the film (and finer filmstrip steps).
    before = vpage.evaluate("() => document.querySelector('canvas[data-lane=\"shots\"]').toDataURL().length")
    st0 = state(vpage)["shots"]
    for _ in range(3):
        vpage.keyboard.press("+")
    next_frame(vpage)
    st1 = state(vpage)["shots"]
    after = vpage.evaluate("() => document.querySelector('canvas[data-lane=\"shots\"]').toDataURL().length")
    assert after != before
    if st0["filmstrip"]:
        assert st1["step"] < st0["step"], (st0, st1)
    assert rect["height"] >= 40


def test_click_shift_click_and_set_on_several_shots_is_one_undo_step(vpage, api, project_copy):
    pid = project_copy["id"]
    doc = open_with_shots(vpage, api, pid)
    tick_s = doc["tick_s"]
    a, b, c = wide_shots(doc, 3)
    lanes = actuators(vpage)
    click_shot(vpage, a, tick_s)
    sel = state(vpage)["selection"]
    assert sel["ranges"] == [[a["t0"], a["t1"]]] and sel["lanes"] == lanes
    click_shot(vpage, c, tick_s, ["Shift"])
    sel = state(vpage)["selection"]
    assert sel["ranges"] == [[a["t0"], a["t1"]], [c["t0"], c["t1"]]]
    assert "2 shots" in vpage.text_content("[data-testid=selection-info]")
    before = values(api, pid, lanes, 0, doc["n_ticks"])
    s0 = state(vpage)
    for button, check in [
        ("edit-set", lambda v, t: v == pytest.approx(0.5)),
        ("edit-scale", lambda v, t: v == pytest.approx(0.75)),
        ("edit-fade-in", None),
        ("edit-fade-out", None),
        ("edit-clear", lambda v, t: v == 0.0),
    ]:
        if button == "edit-scale":
            vpage.fill("[data-testid=edit-factor]", "1.5")
        s_before = state(vpage)
        vpage.click(f"[data-testid={button}]")
        s_after = wait_revision_above(vpage, s_before["revision"])
        assert s_after["cursor"] == s_before["cursor"] + 1, button
        op = api.get(f"/api/projects/{pid}/edits").json()["ops"][-1]
        assert op["op"] == "group" and len(op["ops"]) == 2, op
        assert [(o["t0"], o["t1"]) for o in op["ops"]] == [(a["t0"], a["t1"]), (c["t0"], c["t1"])]
        now = values(api, pid, lanes, 0, doc["n_ticks"])
        for lane in lanes:
            for shot in (a, c):
                if check:
                    assert all(check(v, t) for t, v in enumerate(now[lane][shot["t0"]:shot["t1"]])), (button, lane)
                elif button == "edit-fade-out":
                    assert now[lane][shot["t1"] - 1] == 0.0
                else:
                    assert now[lane][shot["t0"]] == 0.0
            assert now[lane][b["t0"]:b["t1"]] == before[lane][b["t0"]:b["t1"]], "the shot between is unchanged"
    # Undo: each operation on both shots is one step.
    for k in range(5):
        s_before = state(vpage)
        vpage.keyboard.press("Control+z")
        s_after = wait_revision_above(vpage, s_before["revision"])
        assert s_after["cursor"] == s_before["cursor"] - 1
    assert values(api, pid, lanes, 0, doc["n_ticks"]) == before
    assert state(vpage)["cursor"] == s0["cursor"]
    # Shift-click a selected shot takes it out.
    click_shot(vpage, a, tick_s, ["Shift"])
    assert state(vpage)["selection"]["ranges"] == [[c["t0"], c["t1"]]]
    # A drag across the lane selects the run of shots it crosses, each shot a range of its own.
    y = lane_y(vpage, "shots")
    vpage.mouse.move(shot_x(vpage, a, tick_s), y)
    vpage.mouse.down()
    vpage.mouse.move(shot_x(vpage, c, tick_s), y, steps=6)
    vpage.mouse.up()
    run = [[s["t0"], s["t1"]] for s in doc["shots"] if a["t0"] <= s["t0"] <= c["t0"]]
    assert state(vpage)["selection"]["ranges"] == run


def test_double_click_plays_the_shot_and_stops_at_its_end(vpage, api, project_copy):
    pid = project_copy["id"]
    doc = open_with_shots(vpage, api, pid)
    tick_s = doc["tick_s"]
    shot = min(wide_shots(doc, 3, min_ticks=8), key=lambda s: s["t1"] - s["t0"])
    vpage.mouse.dblclick(shot_x(vpage, shot, tick_s), lane_y(vpage, "shots"))
    vpage.wait_for_function("() => window.autohaptics.state().playing")
    t = state(vpage)["currentTime"]
    assert shot["t0"] * tick_s - 0.05 <= t <= shot["t1"] * tick_s
    assert state(vpage)["selection"]["ranges"] == [[shot["t0"], shot["t1"]]]
    vpage.wait_for_function("() => !window.autohaptics.state().playing", timeout=(shot["t1"] - shot["t0"]) * tick_s * 1000 + 15_000)
    end = state(vpage)["currentTime"]
    assert shot["t1"] * tick_s - 0.3 <= end <= shot["t1"] * tick_s + 0.05, (end, shot)


def test_a_drag_snaps_to_shot_boundaries_unless_alt_is_held(vpage, api, project_copy):
    pid = project_copy["id"]
    doc = open_with_shots(vpage, api, pid)
    tick_s = doc["tick_s"]
    px_per_tick = state(vpage)["pxPerS"] * tick_s
    assert 1.5 * px_per_tick < 6, "the test drags 1.5 ticks from a boundary, inside the snap distance"
    shot = wide_shots(doc, 2, min_ticks=20)[1]
    y = lane_y(vpage, "actuators")
    x = lambda tick: vpage.evaluate("(t) => window.autohaptics.clientXOf(t)", tick * tick_s)  # noqa: E731

    def drag(alt: bool) -> dict:
        vpage.mouse.move(x(shot["t0"] + 1.5), y)
        vpage.mouse.down()
        if alt:
            vpage.keyboard.down("Alt")
        vpage.mouse.move(x(shot["t1"] - 1.5), y, steps=6)
        vpage.mouse.up()
        if alt:
            vpage.keyboard.up("Alt")
        return state(vpage)["selection"]

    sel = drag(alt=False)
    assert (sel["t0"], sel["t1"]) == (shot["t0"], shot["t1"])
    vpage.keyboard.press("Escape")
    sel = drag(alt=True)
    assert (sel["t0"], sel["t1"]) == (shot["t0"] + 1, shot["t1"] - 1)


def test_split_and_merge_at_the_playhead_by_key_toolbar_and_context_menu(vpage, api, project_copy):
    pid = project_copy["id"]
    doc = open_with_shots(vpage, api, pid)
    tick_s = doc["tick_s"]
    shot = wide_shots(doc, 2, min_ticks=20)[1]
    n = len(doc["shots"])
    mid = (shot["t0"] + shot["t1"]) // 2
    ruler = vpage.evaluate("() => document.querySelector('[data-testid=ruler]').getBoundingClientRect().toJSON()")

    def seek(tick: int) -> None:
        vpage.mouse.click(vpage.evaluate("(t) => window.autohaptics.clientXOf(t)", (tick + 0.5) * tick_s), ruler["y"] + ruler["height"] / 2)
        wait_until(lambda: round(state(vpage)["currentTime"] / tick_s - 0.5) == tick, f"the playhead at tick {tick}")

    def changed(action, step: int = 1) -> dict:
        s0 = state(vpage)
        action()
        s1 = wait_revision_above(vpage, s0["revision"])
        assert s1["cursor"] == s0["cursor"] + step
        vpage.wait_for_function("(r) => window.autohaptics.state().shots.revision === r", arg=s1["revision"])
        return shots_of(api, pid)

    seek(mid)
    after = changed(lambda: vpage.keyboard.press("s"))
    assert len(after["shots"]) == n + 1
    assert any(s["t0"] == mid and s["kind"] == "split" for s in after["shots"])
    assert state(vpage)["shots"]["count"] == n + 1
    after = changed(lambda: vpage.keyboard.press("m"))  # the playhead's shot starts at mid: merged with the next
    assert len(after["shots"]) == n
    after = changed(lambda: vpage.keyboard.press("Control+z"), -1)
    assert len(after["shots"]) == n + 1
    after = changed(lambda: vpage.keyboard.press("Control+z"), -1)
    assert [s["t0"] for s in after["shots"]] == [s["t0"] for s in doc["shots"]]
    # The toolbar's Split, then the context menu's Merge (the shot at the playhead with the next).
    seek(mid + 3)
    after = changed(lambda: vpage.click("[data-testid=shot-split]"))
    assert any(s["t0"] == mid + 3 for s in after["shots"])
    vpage.mouse.click(shot_x(vpage, shot, tick_s, 0.2), lane_y(vpage, "shots"), button="right")
    vpage.wait_for_selector("[data-testid=shots-menu]")
    seek(shot["t0"] + 1)
    vpage.mouse.click(shot_x(vpage, shot, tick_s, 0.2), lane_y(vpage, "shots"), button="right")
    after = changed(lambda: vpage.click("[data-testid=shots-menu-merge]"))
    assert not any(s["t0"] == mid + 3 for s in after["shots"])
    assert any(s["t0"] == shot["t0"] for s in after["shots"])


def test_shots_panel_sorts_filters_and_jumps(vpage, api, project_copy):
    pid = project_copy["id"]
    doc = open_with_shots(vpage, api, pid)
    tick_s = doc["tick_s"]
    shots = doc["shots"]
    vpage.click("[data-testid=toggle-shots]")
    vpage.wait_for_selector("[data-testid=shots-panel]:not([hidden])")
    assert vpage.text_content("[data-testid=shots-count]") == str(len(shots))
    first_ids = lambda: vpage.eval_on_selector_all("[data-testid=shot-row]", "rs => rs.map((r) => Number(r.dataset.id))")  # noqa: E731
    assert first_ids()[:3] == [s["id"] for s in shots[:3]]
    for sort, key in [("loudest", "loudness_sone"), ("warmest", "temperature_mean_c"), ("vibration", "vibration_mean"),
                      ("fans", "fans_share"), ("motion", "motion")]:
        vpage.select_option("[data-testid=shots-sort]", sort)
        want = sorted(shots, key=lambda s: (-(s[key] if s[key] is not None else -1e9), s["t0"]))
        assert first_ids()[:3] == [s["id"] for s in want[:3]], sort
    vpage.select_option("[data-testid=shots-filter]", "vibration")
    kept = [s for s in shots if (s["vibration_peak"] or 0) > 0]
    assert vpage.text_content("[data-testid=shots-count]") == (str(len(shots)) if len(kept) == len(shots) else f"{len(kept)} of {len(shots)}")
    target, other = sorted(kept, key=lambda s: (-s["motion"], s["t0"]))[:2]
    assert first_ids()[0] == target["id"]
    vpage.click(f"[data-testid=shot-row][data-id='{target['id']}']")
    s = state(vpage)
    assert s["selection"]["ranges"] == [[target["t0"], target["t1"]]]
    wait_until(lambda: abs(state(vpage)["currentTime"] - target["t0"] * tick_s) < 0.06, "the playhead at the shot")
    assert vpage.get_attribute(f"[data-testid=shot-row][data-id='{target['id']}']", "aria-selected") == "true"
    vpage.click(f"[data-testid=shot-row][data-id='{other['id']}']", modifiers=["Shift"])
    assert state(vpage)["selection"]["ranges"] == sorted([[target["t0"], target["t1"]], [other["t0"], other["t1"]]])
    # The panel's state is a view setting: a reload finds it open.
    wait_until(lambda: (api.get(f"/api/projects/{pid}").json().get("view") or {}).get("shots_panel") is True, "the view saved")
    open_editor(vpage, pid)
    vpage.wait_for_selector("[data-testid=shots-panel]:not([hidden])")


def test_copy_a_shots_effects_and_paste_them_fitted_onto_selected_shots(vpage, api, project_copy):
    pid = project_copy["id"]
    doc = open_with_shots(vpage, api, pid)
    tick_s = doc["tick_s"]
    src, b, c = wide_shots(doc, 3)
    lanes = actuators(vpage)
    click_shot(vpage, src, tick_s)
    vpage.fill("[data-testid=edit-value]", "0.7")
    s0 = state(vpage)
    vpage.click("[data-testid=edit-set]")
    wait_revision_above(vpage, s0["revision"])
    vpage.keyboard.press("Control+c")
    vpage.wait_for_selector("[data-testid=edit-paste]:not([disabled])")
    before = values(api, pid, lanes, 0, doc["n_ticks"])
    click_shot(vpage, b, tick_s)
    click_shot(vpage, c, tick_s, ["Shift"])
    s1 = state(vpage)
    vpage.keyboard.press("Control+v")
    s2 = wait_revision_above(vpage, s1["revision"])
    assert s2["cursor"] == s1["cursor"] + 1
    op = api.get(f"/api/projects/{pid}/edits").json()["ops"][-1]
    assert op["op"] == "group" and [(o["op"], o["t0"], o["t1"]) for o in op["ops"]] == [
        ("paste", b["t0"], b["t1"]), ("paste", c["t0"], c["t1"])]
    now = values(api, pid, lanes, 0, doc["n_ticks"])
    for lane in lanes:
        for shot in (b, c):
            assert now[lane][shot["t0"]:shot["t1"]] == pytest.approx([0.7] * (shot["t1"] - shot["t0"]))
        assert now[lane][:b["t0"]] == before[lane][:b["t0"]]
    vpage.keyboard.press("Control+z")
    wait_revision_above(vpage, s2["revision"])
    assert values(api, pid, lanes, 0, doc["n_ticks"]) == before


def test_select_similar_previews_the_count_then_one_operation_changes_them_all(vpage, api, project_copy):
    pid = project_copy["id"]
    doc = open_with_shots(vpage, api, pid)
    tick_s = doc["tick_s"]
    src = wide_shots(doc, 1)[0]
    r = api.get(f"/api/projects/{pid}/shots/{src['id']}/similar")
    assert r.status_code == 200, r.text
    similar = r.json()["similar"]
    assert len(similar) >= 3
    lanes = actuators(vpage)
    # From the lane's context menu, then from the panel's button with the shot selected.
    vpage.mouse.click(shot_x(vpage, src, tick_s), lane_y(vpage, "shots"), button="right")
    vpage.click("[data-testid=shots-menu-similar]")
    vpage.wait_for_selector("[data-testid=shots-similar]:not([hidden])")
    assert state(vpage)["shots"]["similar"]["shot"] == src["id"]
    vpage.click("[data-testid=shots-similar-cancel]")
    assert state(vpage)["shots"]["similar"] is None
    click_shot(vpage, src, tick_s)
    vpage.click("[data-testid=shots-similar-open]")
    vpage.wait_for_selector("[data-testid=shots-similar]:not([hidden])")
    s0 = state(vpage)
    for v in (int((1 - similar[2]["distance"]) * 100), int((1 - similar[0]["distance"]) * 100)):
        vpage.eval_on_selector("[data-testid=shots-similar-slider]",
                               "(el, v) => { el.value = String(v); el.dispatchEvent(new Event('input', {bubbles: true})); }", v)
        want = sorted(s["id"] for s in similar if s["distance"] <= 1 - v / 100 + 1e-12)
        assert state(vpage)["shots"]["similar"]["ids"] == want
        assert vpage.text_content("[data-testid=shots-similar-count]").startswith(f"picks {len(want)} shot")
    picked = state(vpage)["shots"]["similar"]["ids"]
    assert len(picked) >= 1
    assert state(vpage)["revision"] == s0["revision"], "the preview changes nothing"
    vpage.click("[data-testid=shots-similar-apply]")
    by_id = {s["id"]: s for s in doc["shots"]}
    ranges = sorted([[by_id[i]["t0"], by_id[i]["t1"]] for i in picked + [src["id"]]])
    assert state(vpage)["selection"]["ranges"] == ranges
    before = values(api, pid, lanes, 0, doc["n_ticks"])
    s1 = state(vpage)
    vpage.keyboard.press("Delete")
    s2 = wait_revision_above(vpage, s1["revision"])
    assert s2["cursor"] == s1["cursor"] + 1
    now = values(api, pid, lanes, 0, doc["n_ticks"])
    for lane in lanes:
        for t0, t1 in ranges:
            assert now[lane][t0:t1] == [0.0] * (t1 - t0)
    vpage.keyboard.press("Control+z")
    wait_revision_above(vpage, s2["revision"])
    assert values(api, pid, lanes, 0, doc["n_ticks"]) == before
