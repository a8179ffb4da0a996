"""The editor walked as a designer (issue 18), what the view keeps and how its popups behave:
lane heights the user drags, the playhead across a reload, the Keys popup."""

from __future__ import annotations

import pytest

from browser_support import lane_rect, open_editor, state

pytestmark = pytest.mark.browser


def canvas_size(pg, lane: str) -> dict:
    return pg.evaluate("""(id) => { const c = document.querySelector(`canvas[data-lane="${id}"]`);
        return {pixels: c.height, css: c.getBoundingClientRect().height, dpr: window.devicePixelRatio}; }""", lane)


def drag_lower_edge(pg, lane: str, dy: float) -> None:
    handle = pg.locator(f"[data-testid=lane-resize-{lane}]")
    handle.scroll_into_view_if_needed()
    box = handle.bounding_box()
    x, y = box["x"] + 300, box["y"] + box["height"] / 2
    pg.mouse.move(x, y)
    pg.mouse.down()
    pg.mouse.move(x, y + dy, steps=6)
    pg.mouse.up()


def test_a_lane_dragged_by_its_lower_edge_keeps_its_height_after_reload(page, project_copy):
    open_editor(page, project_copy["id"])
    temp0 = lane_rect(page, "temperature")["height"]
    act0 = lane_rect(page, "actuators")["height"]
    fans0 = lane_rect(page, "fans")["height"]
    drag_lower_edge(page, "temperature", 60)
    drag_lower_edge(page, "actuators", -45)
    assert lane_rect(page, "temperature")["height"] == pytest.approx(temp0 + 60, abs=1)
    assert lane_rect(page, "actuators")["height"] == pytest.approx(act0 - 45, abs=1)
    assert lane_rect(page, "fans")["height"] == fans0, "the other lanes keep theirs"
    size = canvas_size(page, "temperature")
    assert size["pixels"] == round(size["css"] * size["dpr"]), "the canvas is drawn at the new height"
    # The heat map's rows follow its height: a drag over the last row still selects A9.
    r = lane_rect(page, "actuators")
    y = r["y"] + r["height"] - 5  # above the resize handle (the lowest 3 px)
    page.mouse.move(r["x"] + 100, y)
    page.mouse.down()
    page.mouse.move(r["x"] + 160, y, steps=3)
    page.mouse.up()
    assert state(page)["selection"]["lanes"] == ["A9"]
    # Kept across a reload (this browser), and the keyboard moves the edge by 8 px.
    page.reload()
    open_editor(page, project_copy["id"])
    assert lane_rect(page, "temperature")["height"] == pytest.approx(temp0 + 60, abs=1)
    assert lane_rect(page, "actuators")["height"] == pytest.approx(act0 - 45, abs=1)
    page.focus("[data-testid=lane-resize-temperature]")
    page.keyboard.press("ArrowUp")
    assert lane_rect(page, "temperature")["height"] == pytest.approx(temp0 + 52, abs=1)
    # A double-click gives the lane its own height back; far drags stop at the limits.
    page.dblclick("[data-testid=lane-resize-temperature]")
    assert lane_rect(page, "temperature")["height"] == pytest.approx(temp0, abs=1)
    drag_lower_edge(page, "fans", -200)
    assert lane_rect(page, "fans")["height"] == 24


def keys_open(pg) -> bool:
    return pg.evaluate("() => document.querySelector('[data-testid=keys-menu]').open")


def test_the_keys_popup_closes_on_escape_and_outside_and_lets_the_ruler_be_clicked(page, project_copy):
    open_editor(page, project_copy["id"])
    summary = "[data-testid=keys-menu] > summary"
    # Escape closes it (the focus back on its button) and does nothing else: the selection stays.
    r = lane_rect(page, "actuators")
    page.mouse.move(r["x"] + 100, r["y"] + 5)
    page.mouse.down()
    page.mouse.move(r["x"] + 200, r["y"] + 5, steps=3)
    page.mouse.up()
    selection = state(page)["selection"]
    assert selection is not None
    page.click(summary)
    assert keys_open(page)
    page.keyboard.press("Escape")
    assert not keys_open(page)
    assert page.evaluate("() => document.activeElement.matches('[data-testid=keys-menu] > summary')")
    assert state(page)["selection"] == selection
    # A press outside closes it.
    page.click(summary)
    assert keys_open(page)
    page.click("[data-testid=chair-diagram]")
    assert not keys_open(page)
    # A click on the ruler where the open list covers it moves the playhead there and closes the list.
    page.click(summary)
    spot = page.evaluate("""() => {
        const a = document.querySelector('.keys-list').getBoundingClientRect();
        const b = document.querySelector('[data-testid=ruler]').getBoundingClientRect();
        const x0 = Math.max(a.left, b.left), x1 = Math.min(a.right, b.right);
        const y0 = Math.max(a.top, b.top), y1 = Math.min(a.bottom, b.bottom);
        return x1 - x0 > 20 && y1 - y0 > 4 ? {x: (x0 + x1) / 2, y: (y0 + y1) / 2} : null;
    }""")
    assert spot is not None, "the open Keys list covers part of the ruler at this size"
    time_there = page.evaluate(f"() => {{ const r = document.querySelector('[data-testid=ruler]').getBoundingClientRect();"
                               f" return window.autohaptics.state().startS + ({spot['x']} - r.x) / window.autohaptics.state().pxPerS; }}")
    page.mouse.click(spot["x"], spot["y"])
    assert not keys_open(page)
    page.wait_for_function("(t) => Math.abs(window.autohaptics.state().playheadS - t) < 0.1", arg=time_there)


def test_the_playhead_survives_a_reload_per_project(page, api, project_copy):
    pid = project_copy["id"]
    other = api.post(f"/api/projects/{pid}/duplicate").json()
    try:
        open_editor(page, pid)
        page.evaluate("() => document.querySelector('[data-testid=video]').currentTime = 7.3")
        page.wait_for_function("() => Math.abs(window.autohaptics.state().playheadS - 7.3) < 0.01")
        page.reload()
        open_editor(page, pid)
        page.wait_for_function("() => Math.abs(window.autohaptics.state().playheadS - 7.3) < 0.01")
        assert page.text_content("[data-testid=time]").startswith("0:07.3 /")
        # Played on and stopped: the reload finds where it stopped.
        page.click("[data-testid=play]")
        page.wait_for_function("() => window.autohaptics.state().currentTime > 8.0")
        page.click("[data-testid=play]")
        page.wait_for_function("() => !window.autohaptics.state().playing")
        stopped = state(page)["currentTime"]
        page.reload()
        open_editor(page, pid)
        page.wait_for_function("(t) => Math.abs(window.autohaptics.state().playheadS - t) < 0.01", arg=stopped)
        # Per project: another project opens at its own (never moved) playhead.
        page.goto("/#/")
        open_editor(page, other["id"])
        page.wait_for_function("() => document.querySelector('[data-testid=video]').readyState >= 1")
        assert state(page)["playheadS"] == 0
    finally:
        api.delete(f"/api/projects/{other['id']}")
