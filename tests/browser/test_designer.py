"""The editor walked as a designer (issue 18): dialogs answer Enter and Escape, values keep their
precision through copy and paste, the temperature lane shows what the chair plays."""

from __future__ import annotations

import csv
import io

import pytest

from browser_support import lane_rect, open_editor, sampled_ticks, state, wait_job, wait_revision_above

pytestmark = pytest.mark.browser


def select_time(pg, t0_s: float, t1_s: float) -> None:
    """Select [t0_s, t1_s) on A5 (drag over the middle row of the heat map)."""
    r = lane_rect(pg, "actuators")
    y = r["y"] + r["height"] / 2
    pg.mouse.move(pg.evaluate("(t) => window.autohaptics.clientXOf(t)", t0_s), y)
    pg.mouse.down()
    pg.mouse.move(pg.evaluate("(t) => window.autohaptics.clientXOf(t)", t1_s), y, steps=4)
    pg.mouse.up()


def test_enter_submits_and_escape_cancels_every_dialog(page, api, project_copy):
    pid = project_copy["id"]
    open_editor(page, pid)
    # Add marker: the focus starts in the label, Enter adds it.
    page.click("[data-testid=marker-add]")
    assert page.evaluate("() => document.activeElement.dataset.testid") == "dialog-input"
    page.keyboard.type("Door slam")
    s0 = state(page)
    page.keyboard.press("Enter")
    s1 = wait_revision_above(page, s0["revision"])
    assert [m["label"] for m in s1["markers"]] == ["Door slam"]
    # Escape cancels: nothing is sent.
    page.click("[data-testid=marker-add]")
    page.keyboard.type("Not this one")
    page.keyboard.press("Escape")
    page.wait_for_selector("dialog[open]", state="detached")
    assert state(page)["revision"] == s1["revision"]
    # Regenerate: focus in the first field, Escape cancels, Enter in a threshold starts the job.
    page.click("[data-testid=regenerate]")
    page.wait_for_selector("[data-testid=regenerate-dialog][open]")
    assert page.evaluate("() => document.activeElement.dataset.testid") == "regen-preset"
    page.keyboard.press("Escape")
    page.wait_for_selector("dialog[open]", state="detached")
    assert api.get(f"/api/projects/{pid}").json()["status"] == "ready"
    page.click("[data-testid=regenerate]")
    page.fill("[data-testid=regen-threshold-loudness]", "0.7")
    page.focus("[data-testid=regen-threshold-loudness]")
    page.keyboard.press("Enter")
    page.wait_for_selector("dialog[open]", state="detached")
    page.wait_for_function(f"() => fetch('/api/projects/{pid}').then(r => r.json())"
                           ".then(p => p.params.thresholds.loudness === 0.7)")
    # Rename on the projects page: Enter renames, Escape keeps the name.
    page.goto("/#/")
    row = page.locator(f"[data-testid=project-row][data-id='{pid}']")
    row.locator("[data-testid=project-rename]").click()
    page.keyboard.press("Control+A")
    page.keyboard.type("Renamed by Enter")
    page.keyboard.press("Enter")
    page.wait_for_function(f"() => fetch('/api/projects/{pid}').then(r => r.json())"
                           ".then(p => p.name === 'Renamed by Enter')")
    row.locator("[data-testid=project-rename]").click()
    page.keyboard.type("Not this name")
    page.keyboard.press("Escape")
    page.wait_for_selector("dialog[open]", state="detached")
    assert api.get(f"/api/projects/{pid}").json()["name"] == "Renamed by Enter"


def focused(pg) -> str | None:
    return pg.evaluate("() => document.activeElement.dataset.testid || null")


def test_the_rename_marker_and_delete_dialogs_answer_enter_and_escape(page, api, project_copy):
    pid = project_copy["id"]
    other = api.post(f"/api/projects/{pid}/duplicate").json()
    open_editor(page, pid)
    page.click("[data-testid=marker-add]")
    page.keyboard.type("Door")
    s0 = state(page)
    page.keyboard.press("Enter")
    s1 = wait_revision_above(page, s0["revision"])  # added, and selected
    # Rename: the focus in the label with its text selected, so typing replaces it; Enter renames.
    page.click("[data-testid=marker-rename]")
    assert focused(page) == "dialog-input"
    assert page.evaluate("() => { const i = document.activeElement; return [i.selectionStart, i.selectionEnd]; }") == [0, 4]
    page.keyboard.type("Window")
    page.keyboard.press("Enter")
    s2 = wait_revision_above(page, s1["revision"])
    assert [m["label"] for m in s2["markers"]] == ["Window"]
    assert api.get(f"/api/projects/{pid}/edits").json()["ops"][-1]["op"] == "marker_update"
    # Escape keeps the name: nothing is sent.
    page.click("[data-testid=marker-rename]")
    page.keyboard.type("Not this")
    page.keyboard.press("Escape")
    page.wait_for_selector("dialog[open]", state="detached")
    assert state(page)["revision"] == s2["revision"] and [m["label"] for m in state(page)["markers"]] == ["Window"]
    # Delete on the projects page: the focus starts on Cancel, so neither Enter nor Escape deletes.
    page.goto("/#/")
    row = page.locator(f"[data-testid=project-row][data-id='{other['id']}']")
    for key in ("Enter", "Escape"):
        row.locator("[data-testid=project-delete]").click()
        page.wait_for_selector("dialog[open]")
        assert focused(page) == "dialog-cancel"
        page.keyboard.press(key)
        page.wait_for_selector("dialog[open]", state="detached")
        assert api.get(f"/api/projects/{other['id']}").status_code == 200 and row.count() == 1
    # Tab to Delete, then Enter: deleted.
    row.locator("[data-testid=project-delete]").click()
    page.keyboard.press("Tab")
    assert focused(page) == "dialog-ok"
    page.keyboard.press("Enter")
    row.wait_for(state="detached")
    assert api.get(f"/api/projects/{other['id']}").status_code == 404


def test_the_temperature_lane_shows_what_the_chair_plays(page, api, project_copy):
    pid = project_copy["id"]
    # the thesis's colour rule: a timeline range of 30..55 C, wider than the device's 18..40 C
    r = api.put(f"/api/projects/{pid}/params", json={"overrides": {"thermal.mapping": "thesis"}})
    assert r.status_code == 200 and r.json()["job"] is None, r.text
    rev = api.get(f"/api/projects/{pid}").json()["revision"]
    r = api.post(f"/api/projects/{pid}/edits", json={"base_revision": rev, "op": {
        "op": "set", "lanes": ["temperature"], "t0": 100, "t1": 200, "value": 45.0}})
    assert r.status_code == 200, r.text
    open_editor(page, pid)
    page.wait_for_function("() => { const s = window.autohaptics.state(); return s.played && s.played.revision === s.revision; }")
    played = state(page)["played"]
    assert (played["minC"], played["maxC"]) == (18.0, 40.0)
    ticks = page.evaluate("() => Array.from({length: 300}, (_, k) => window.autohaptics.valuesAt(k))")
    target = [v["temperature_c"] for v in ticks]
    chair = [v["played_c"] for v in ticks]
    assert target[150] == pytest.approx(45.0)
    assert chair[199] == pytest.approx(40.0, abs=1e-3), "the chair plays its own maximum, not the 45 C target"
    assert max(chair) <= 40.0 + 1e-3
    assert max(abs(a - b) for a, b in zip(chair, chair[1:])) <= 0.1 + 1e-3, "at most 1 C/s"
    # The chair's limit is drawn: its label colour is on the lane.
    lit = page.evaluate("""() => {
        const c = document.querySelector('canvas[data-lane="temperature"]');
        const d = c.getContext('2d').getImageData(0, 0, c.width, c.height).data;
        let n = 0;
        for (let i = 0; i < d.length; i += 4) if (d[i] === 0xfb && d[i + 1] === 0x92 && d[i + 2] === 0x3c) n++;
        return n; }""")
    assert lit > 20


def test_a_pasted_half_is_a_half_in_the_csv(page, api, project_copy):
    pid = project_copy["id"]
    open_editor(page, pid)
    select_time(page, 20.05, 20.95)  # ticks 200..209
    page.fill("[data-testid=edit-value]", "0.5")
    s0 = state(page)
    page.click("[data-testid=edit-set]")
    s1 = wait_revision_above(page, s0["revision"])
    page.click("[data-testid=edit-copy]")  # the toolbar's Copy and Paste this time (test_tools uses the keys)
    page.wait_for_function("() => !document.querySelector('[data-testid=edit-paste]').disabled")
    page.evaluate("() => { document.querySelector('[data-testid=video]').currentTime = 0; }")
    page.wait_for_function("() => window.autohaptics.state().playheadS === 0")
    page.click("[data-testid=edit-paste]")
    wait_revision_above(page, s1["revision"])
    paste = api.get(f"/api/projects/{pid}/edits").json()["ops"][-1]
    assert paste["op"] == "paste" and paste["t0"] == 0
    assert paste["values"] == {"A5": [0.5] * 10}
    rows = list(csv.DictReader(io.StringIO(api.get(f"/api/projects/{pid}/export?format=csv").text)))
    assert [float(rows[k]["A5"]) for k in range(10)] == [0.5] * 10
    assert rows[0]["A5"] in ("0.5", "0.5000")


def overlay_cell_xy(pg, row: int, col: int) -> tuple[float, float]:
    """Client coordinates of the middle of one fan cell on the overlay (the picture inside the video)."""
    return tuple(pg.evaluate(
        """([row, col]) => {
            const c = document.querySelector('[data-testid=fan-overlay]');
            const v = document.querySelector('[data-testid=video]');
            const b = c.getBoundingClientRect();
            const s = Math.min(b.width / v.videoWidth, b.height / v.videoHeight);
            const pw = v.videoWidth * s, ph = v.videoHeight * s;
            const x0 = b.x + (b.width - pw) / 2, y0 = b.y + (b.height - ph) / 2;
            return [x0 + (col + 0.5) * pw / 17, y0 + (row + 0.5) * ph / 9];
        }""", [row, col]))


def export_rows(api, pid: str) -> list[dict]:
    """The project's CSV export, one dict per tick."""
    return list(csv.DictReader(io.StringIO(api.get(f"/api/projects/{pid}/export?format=csv").text)))


def fan_column(rows: list[dict], row: int, col: int) -> list[float]:
    return [float(r[f"fan_r{row}_c{col}"]) for r in rows]


def test_a_fan_region_edit_survives_reload_regeneration_and_export(page, api, project_copy):
    pid = project_copy["id"]
    open_editor(page, pid)
    before = export_rows(api, pid)
    r = lane_rect(page, "fans")
    y = r["y"] + r["height"] / 2
    page.mouse.move(page.evaluate("(t) => window.autohaptics.clientXOf(t)", 5.05), y)
    page.mouse.down()
    page.mouse.move(page.evaluate("(t) => window.autohaptics.clientXOf(t)", 7.95), y, steps=4)
    page.mouse.up()
    assert state(page)["selection"] == {"t0": 50, "t1": 80, "lanes": ["fans"]}
    page.click("[data-testid=toggle-fan-overlay]")
    page.wait_for_function("() => document.querySelector('[data-testid=video]').videoWidth > 0")
    # A rectangle of rows 1..2 x columns 3..5, then a brush stroke with Ctrl: along row 7 from
    # column 12 to 16, and down to row 8.
    page.mouse.move(*overlay_cell_xy(page, 1, 3))
    page.mouse.down()
    page.mouse.move(*overlay_cell_xy(page, 2, 5), steps=4)
    page.mouse.up()
    page.keyboard.down("Control")
    page.mouse.move(*overlay_cell_xy(page, 7, 12))
    page.mouse.down()
    page.mouse.move(*overlay_cell_xy(page, 7, 16), steps=16)
    page.mouse.move(*overlay_cell_xy(page, 8, 16), steps=4)
    page.mouse.up()
    page.keyboard.up("Control")
    assert "12 fans picked" in page.text_content("[data-testid=selection-info]")
    page.fill("[data-testid=edit-value]", "0.8")
    s0 = state(page)
    page.click("[data-testid=edit-set]")
    s1 = wait_revision_above(page, s0["revision"])
    op = api.get(f"/api/projects/{pid}/edits").json()["ops"][-1]
    picked = [[1, 3], [1, 4], [1, 5], [2, 3], [2, 4], [2, 5], *[[7, c] for c in range(12, 17)], [8, 16]]
    assert op == {"op": "set", "lanes": ["fans"], "t0": 50, "t1": 80, "value": 0.8, "cells": picked}

    def check() -> None:
        rows = export_rows(api, pid)
        for row, col in picked:
            assert fan_column(rows, row, col)[50:80] == [0.8] * 30
        for row, col in ((0, 0), (1, 2), (3, 4), (7, 11), (8, 15)):  # outside the region: as generated
            assert fan_column(rows, row, col) == fan_column(before, row, col)

    check()
    # Undo takes the region's values away (as generated again), redo brings them back.
    page.click("[data-testid=undo]")
    s2 = wait_revision_above(page, s1["revision"])
    undone = export_rows(api, pid)
    assert all(fan_column(undone, row, col) == fan_column(before, row, col) for row, col in picked)
    page.click("[data-testid=redo]")
    wait_revision_above(page, s2["revision"])
    check()
    page.reload()
    open_editor(page, pid)
    grid = page.evaluate("() => window.autohaptics.valuesAt(60).fan_grid")
    assert grid[1 * 17 + 4] == pytest.approx(0.8, abs=1 / 255) and grid[7 * 17 + 14] == pytest.approx(0.8, abs=1 / 255)
    # A threshold re-derive, then a real regeneration (a new analysis job, to done): still there.
    rev = api.get(f"/api/projects/{pid}").json()["revision"]
    r = api.put(f"/api/projects/{pid}/params", json={"thresholds": {"loudness": 0.5}})
    assert r.status_code in (200, 202), r.text
    if r.json().get("job"):
        assert wait_job(api, r.json()["job"]["id"])["status"] == "done"
    assert api.get(f"/api/projects/{pid}").json()["revision"] > rev
    check()
    page.reload()
    open_editor(page, pid)
    s3 = state(page)
    page.click("[data-testid=regenerate]")
    page.fill("[data-testid=regen-threshold-loudness]", "0.55")
    with page.expect_response(lambda res: res.url.endswith(f"/api/projects/{pid}/generate")) as answer:
        page.click("[data-testid=regen-start]")
    job = answer.value.json()["job"]
    assert job["params"]["thresholds"]["loudness"] == 0.55 and wait_job(api, job["id"])["status"] == "done"
    wait_revision_above(page, s3["revision"])
    assert api.get(f"/api/projects/{pid}").json()["params"]["thresholds"]["loudness"] == 0.55
    check()
    grid = page.evaluate("() => window.autohaptics.valuesAt(60).fan_grid")
    assert grid[8 * 17 + 16] == pytest.approx(0.8, abs=1 / 255), "the editor shows it after the regeneration"


CONTROLS_CLIPPED = """() => {
    // Every control of the header (buttons, the menus' summaries, the '<- Projects' link), the side
    // column, the transport and the toolbar, scrolled into view inside its own scroll area, must lie
    // inside the viewport and inside that area. Returns those clipped and the names of all checked.
    const out = [], checked = [];
    const scroller = (el) => {
        for (let p = el.parentElement; p; p = p.parentElement) {
            const o = getComputedStyle(p).overflowY;
            if ((o === 'auto' || o === 'scroll') && p.scrollHeight > p.clientHeight + 1) return p;
        }
        return null;
    };
    const sel = '.topbar button, .topbar a, summary, .side button, .side input, .side select, .transport button, .toolbar button, .toolbar input';
    for (const el of document.querySelectorAll(sel)) {
        if (el.closest('[hidden]') || el.offsetParent === null || el.classList.contains('visually-hidden')) continue;
        const name = el.dataset.testid || el.textContent.trim() || el.tagName;
        checked.push(name);
        el.scrollIntoView({block: 'nearest', inline: 'nearest'});
        const r = el.getBoundingClientRect();
        const box = scroller(el);
        const area = box ? box.getBoundingClientRect() : {top: 0, left: 0, bottom: innerHeight, right: innerWidth};
        const inside = (b) => r.top >= b.top - 1 && r.left >= b.left - 1 && r.bottom <= b.bottom + 1 && r.right <= b.right + 1;
        if (!inside(area) || !inside({top: 0, left: 0, bottom: innerHeight, right: innerWidth})) {
            out.push(`${name} at ${Math.round(r.top)}..${Math.round(r.bottom)}`);
        }
    }
    for (const panel of document.querySelectorAll('.side .panel')) {
        if (panel.scrollHeight > panel.clientHeight + 1) out.push(`panel ${panel.textContent.slice(0, 20)} scrolls on its own`);
    }
    return {clipped: out, checked};
}"""

LANES_VIEW = """() => {
    // The lanes' scroll area: its visible band (below the sticky ruler, above its own lower edge or
    // the viewport's) and every lane's id, top to bottom.
    const host = document.querySelector('.timeline-host');
    const b = host.getBoundingClientRect();
    return {
        scrollTop: host.scrollTop,
        top: document.querySelector('[data-testid=ruler]').getBoundingClientRect().bottom,
        bottom: Math.min(b.top + host.clientTop + host.clientHeight, innerHeight),
        lanes: [...host.querySelectorAll('canvas[data-lane]')].filter((c) => !c.closest('[hidden]')).map((c) => c.dataset.lane),
    };
}"""


@pytest.mark.parametrize("width, height", [(1366, 768), (1440, 900), (1920, 1080)])
def test_no_panel_is_clipped_and_the_ruler_stays(page, project_copy, width, height):
    page.set_viewport_size({"width": width, "height": height})
    open_editor(page, project_copy["id"])
    controls = page.evaluate(CONTROLS_CLIPPED)
    assert controls["clipped"] == []
    assert {"Export", "Lanes", "Keys", "back", "regenerate", "undo", "chair-push"} <= set(controls["checked"]), controls["checked"]
    for name in ("sharpness", "booming", "low_energy", "loudness"):
        assert page.is_visible(f"[data-testid=threshold-{name}]")
    host = page.locator(".timeline-host")
    host.evaluate("(el) => { el.scrollTop = el.scrollHeight; }")
    view = page.evaluate(LANES_VIEW)
    assert view["scrollTop"] > 0, "the lanes scrolled (they are taller than their area at this size)"
    ruler = page.locator("[data-testid=ruler]").bounding_box()
    top = host.bounding_box()["y"]
    assert top - 1 <= ruler["y"] <= top + 2, "the ruler stays at the top of the scrolled lanes"
    assert {"waveform", "feature-loudness", "actuators", "temperature", "fans", "markers"} <= set(view["lanes"])
    for lane in reversed(view["lanes"]):  # from the bottom up: each one scrolled to, below the ruler
        r = lane_rect(page, lane)
        band = page.evaluate(LANES_VIEW)
        assert band["top"] - 1 <= r["y"] and r["y"] + r["height"] <= band["bottom"] + 1, \
            f"{lane} lane reachable: {r} in {band['top']}..{band['bottom']}"


def test_a_threshold_drag_with_shift_is_ten_times_finer(page, project_copy):
    open_editor(page, project_copy["id"])
    s0 = state(page)
    thr0 = s0["thresholds"]["booming"]
    r = lane_rect(page, "feature-booming")
    y0 = r["y"] + r["height"] - 3 - thr0 * (r["height"] - 6)
    x = r["x"] + r["width"] * 0.4
    page.mouse.move(x, y0)
    page.keyboard.down("Shift")
    page.mouse.down()
    page.mouse.move(x, y0 + 15, steps=5)
    page.mouse.up()
    page.keyboard.up("Shift")
    s1 = wait_revision_above(page, s0["revision"])
    moved = thr0 - s1["thresholds"]["booming"]
    full = 15 / (r["height"] - 6)  # what 15 px move without Shift
    assert moved == pytest.approx(full / 10, abs=0.002)


def test_a_cancelled_regeneration_leaves_the_labels_of_the_timeline_on_show(page, api, project_copy):
    pid = project_copy["id"]
    other = api.post(f"/api/projects/{pid}/duplicate").json()
    p0 = api.get(f"/api/projects/{pid}").json()
    shown = f"Preset {p0['params']['preset']} · mode {p0['params']['mode']}"
    assert p0["params"]["preset"] != "reference"
    open_editor(page, pid)
    assert page.text_content("[data-testid=params-info]") == shown
    # One job runs at a time: another project's job keeps the worker busy, so ours is cancelled for sure.
    busy = api.post(f"/api/projects/{other['id']}/generate", json={}).json()["job"]
    page.click("[data-testid=regenerate]")
    page.select_option("[data-testid=regen-preset]", "reference")
    page.click("[data-testid=regen-start]")
    slot = "[data-testid=job-slot]"
    page.wait_for_function(f"() => {{ const b = document.querySelector('{slot} [data-testid=generation-cancel]');"
                           " return b && !b.disabled; }")
    page.click(f"{slot} [data-testid=generation-cancel]")
    page.wait_for_function(f"() => document.querySelector('{slot} [data-testid=generation-status]')"
                           ".textContent.startsWith('Generation cancelled')")
    assert page.text_content(f"{slot} [data-testid=generation-progress]").endswith("cancelled")
    page.wait_for_function(f"() => document.querySelector('{slot}').hidden")  # no bar left behind at its last figure
    assert page.text_content("[data-testid=params-info]") == shown, "the preset of the timeline on screen"
    project = api.get(f"/api/projects/{pid}").json()
    assert project["status"] == "ready" and project["job"]["status"] == "cancelled"
    assert project["params"] == p0["params"] and project["revision"] == p0["revision"]
    assert api.patch(f"/api/projects/{other['id']}", json={"name": project["name"]}).status_code == 200
    page.goto("/#/")
    row = page.locator(f"[data-testid=project-row][data-id='{pid}']")
    assert row.get_attribute("data-status") == "ready"
    assert "Last regeneration cancelled" in row.locator("[data-testid=project-note]").text_content()
    # The duplicate bears the same name: the two rows are told apart.
    twin = page.locator(f"[data-testid=project-row][data-id='{other['id']}']")
    metas = {row.locator("[data-testid=project-meta]").text_content(), twin.locator("[data-testid=project-meta]").text_content()}
    assert len(metas) == 2 and any(pid[:6] in m for m in metas)
    assert wait_job(api, busy["id"])["status"] == "done"
    api.delete(f"/api/projects/{other['id']}")


def test_a_regeneration_cancelled_mid_run_leaves_the_labels_of_the_timeline_on_show(page, api, project_copy):
    pid = project_copy["id"]
    p0 = api.get(f"/api/projects/{pid}").json()
    shown = f"Preset {p0['params']['preset']} · mode {p0['params']['mode']}"
    open_editor(page, pid)
    before = sampled_ticks(page)
    page.click("[data-testid=regenerate]")
    page.select_option("[data-testid=regen-preset]", "reference")  # every frame analysed: a long job
    page.click("[data-testid=regen-start]")
    slot = "[data-testid=job-slot]"
    # Cancelled once it has got somewhere: the bar shows a figure above 0 %.
    page.wait_for_function(f"() => {{ const b = document.querySelector('{slot} [data-testid=generation-progress]');"
                           " return b && Number(b.getAttribute('aria-valuenow')) > 0; }", timeout=60_000)
    assert api.get(f"/api/projects/{pid}").json()["job"]["status"] == "running"
    page.click(f"{slot} [data-testid=generation-cancel]")
    page.wait_for_function(f"() => document.querySelector('{slot} [data-testid=generation-status]')"
                           ".textContent.startsWith('Generation cancelled')")
    figure = page.text_content(f"{slot} [data-testid=generation-progress]")
    assert figure.endswith("cancelled") and int(figure.split(" %")[0]) > 0, figure
    page.wait_for_function(f"() => document.querySelector('{slot}').hidden")  # the bar goes
    assert page.is_hidden(f"{slot} [data-testid=generation-progress]")
    assert page.text_content("[data-testid=params-info]") == shown, "the preset of the timeline on screen"
    project = api.get(f"/api/projects/{pid}").json()
    assert project["status"] == "ready" and project["job"]["status"] == "cancelled"
    assert project["params"] == p0["params"] and project["revision"] == p0["revision"]
    assert sampled_ticks(page) == before
    assert page.is_disabled("[data-testid=undo]"), "a cancelled attempt is no step of the history"
    assert page.is_enabled("[data-testid=regenerate]")
