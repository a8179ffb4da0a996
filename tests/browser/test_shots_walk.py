"""Shots as a designer walks them, at 1366x768 and 1920x1080: the Shots panel and the similar-shots
box by keyboard alone (focus order, arrows, Enter / Space, Escape closes the box, visible focus),
the panel's head and rows staying in view with the box open, Copy asking for one shot when several
are selected, and the editing toolbar on one line."""

from __future__ import annotations

import pytest

from browser_support import state, wait_until
from test_shots import click_shot, open_with_shots, vpage, wide_shots  # noqa: F401 (vpage: the fixture)

pytestmark = pytest.mark.browser

FOCUS = """() => { const e = document.activeElement, cs = getComputedStyle(e);
    return {testid: e.dataset.testid || '', outline: cs.outlineStyle, width: parseFloat(cs.outlineWidth),
            active: e.getAttribute('aria-activedescendant')}; }"""


def focused(pg) -> dict:
    return pg.evaluate(FOCUS)


def open_panel(pg) -> None:
    if not state(pg)["shots"]["panelOpen"]:
        pg.click("[data-testid=toggle-shots]")
    pg.wait_for_selector("[data-testid=shots-panel]:not([hidden])")


def tab_to(pg, testid: str, back: bool = False, limit: int = 60) -> None:
    for _ in range(limit):
        pg.keyboard.press("Shift+Tab" if back else "Tab")
        if focused(pg)["testid"] == testid:
            return
    pytest.fail(f"{testid} is not reached by {'Shift+' if back else ''}Tab")


def test_the_shots_list_works_by_keyboard(vpage, api, project_copy):
    pid = project_copy["id"]
    doc = open_with_shots(vpage, api, pid)
    shots, tick_s = doc["shots"], doc["tick_s"]
    open_panel(vpage)
    vpage.focus("[data-testid=toggle-shots]")
    tab_to(vpage, "shots-list", back=True)
    f = focused(vpage)
    assert f["outline"] != "none" and f["width"] >= 2, "the list shows keyboard focus"
    row = lambda: vpage.evaluate("() => document.getElementById(document.activeElement.getAttribute('aria-activedescendant'))?.dataset.id")  # noqa: E731
    assert row() == str(shots[0]["id"]), "the first shot is the active one"
    vpage.keyboard.press("ArrowDown")
    vpage.keyboard.press("ArrowDown")
    assert row() == str(shots[2]["id"])
    assert state(vpage)["currentTime"] == 0, "arrows move in the list, not the playhead"
    vpage.keyboard.press("Enter")
    assert state(vpage)["selection"]["ranges"] == [[shots[2]["t0"], shots[2]["t1"]]]
    wait_until(lambda: abs(state(vpage)["currentTime"] - shots[2]["t0"] * tick_s) < 0.06, "the playhead at the shot")
    assert vpage.get_attribute(f"[data-testid=shot-row][data-id='{shots[2]['id']}']", "aria-selected") == "true"
    vpage.keyboard.press("ArrowDown")
    vpage.keyboard.press("Shift+Space")  # Shift: add it; Space does not play here
    assert state(vpage)["selection"]["ranges"] == [[s["t0"], s["t1"]] for s in shots[2:4]]
    assert not state(vpage)["playing"]
    vpage.keyboard.press("End")
    assert row() == str(shots[-1]["id"])
    vpage.keyboard.press("Home")
    assert row() == str(shots[0]["id"])
    assert focused(vpage)["testid"] == "shots-list"


def test_the_similar_box_by_keyboard_and_escape_closes_it(vpage, api, project_copy):
    pid = project_copy["id"]
    doc = open_with_shots(vpage, api, pid)
    src = wide_shots(doc, 1)[0]
    open_panel(vpage)
    click_shot(vpage, src, doc["tick_s"])
    vpage.focus("[data-testid=shots-list]")
    tab_to(vpage, "shots-similar-open", back=True)
    vpage.keyboard.press("Enter")
    vpage.wait_for_selector("[data-testid=shots-similar]:not([hidden])")
    vpage.wait_for_function("() => document.activeElement.dataset.testid === 'shots-similar-slider'")
    order = []
    for _ in range(2):
        vpage.keyboard.press("Tab")
        order.append(focused(vpage)["testid"])
    assert order == ["shots-similar-apply", "shots-similar-cancel"]
    vpage.keyboard.press("Shift+Tab")
    vpage.keyboard.press("Shift+Tab")
    f = focused(vpage)
    assert f["testid"] == "shots-similar-slider" and f["outline"] != "none" and f["width"] >= 2
    vpage.keyboard.press("ArrowLeft")
    assert state(vpage)["shots"]["similar"]["maxDistance"] == pytest.approx(0.21)
    # The panel's head and at least two rows stay in view with the box open.
    geo = vpage.evaluate("""() => {
        const r = (s) => document.querySelector(`[data-testid=${s}]`).getBoundingClientRect();
        const panel = r('shots-panel'), head = r('shots-count'), list = r('shots-list');
        return {scrolled: document.querySelector('[data-testid=shots-panel]').scrollTop, headTop: head.top - panel.top,
                listH: list.height, listBottom: panel.bottom - list.bottom};
    }""")
    assert geo["scrolled"] == 0 and geo["headTop"] >= 0, geo
    assert geo["listH"] >= 2 * 46 and geo["listBottom"] >= 0, geo
    vpage.keyboard.press("Escape")
    assert state(vpage)["shots"]["similar"] is None
    assert vpage.is_hidden("[data-testid=shots-similar]")
    assert state(vpage)["selection"]["ranges"] == [[src["t0"], src["t1"]]], "Escape closed the box, the selection stays"
    assert focused(vpage)["testid"] == "shots-similar-open", "focus goes back to the button that opened it"
    # Select them by keyboard: the box closes, focus lands in the list.
    vpage.keyboard.press("Enter")
    vpage.wait_for_function("() => document.activeElement.dataset.testid === 'shots-similar-slider'")
    tab_to(vpage, "shots-similar-apply")
    vpage.keyboard.press("Enter")
    assert state(vpage)["shots"]["similar"] is None
    assert len(state(vpage)["selection"]["ranges"]) >= 2
    assert focused(vpage)["testid"] == "shots-list"


def test_copy_with_several_shots_selected_asks_for_one(vpage, api, project_copy):
    pid = project_copy["id"]
    doc = open_with_shots(vpage, api, pid)
    a, c = wide_shots(doc, 2)
    click_shot(vpage, a, doc["tick_s"])
    click_shot(vpage, c, doc["tick_s"], ["Shift"])
    vpage.keyboard.press("Control+c")
    warn = vpage.wait_for_selector("[data-testid=toast-warn]")
    assert "2 shots are selected" in warn.text_content()
    assert vpage.is_disabled("[data-testid=edit-paste]"), "nothing was copied (not the shots between them either)"
    click_shot(vpage, a, doc["tick_s"])
    vpage.keyboard.press("Control+c")
    vpage.wait_for_selector("[data-testid=edit-paste]:not([disabled])")


ROWS = """() => Object.fromEntries(['.transport', '.toolbar'].map((bar) => {
    const el = document.querySelector(bar);
    const centres = [...el.querySelectorAll('button, input, summary, .selection-info')].filter((e) => e.checkVisibility())
        .map((e) => { const r = e.getBoundingClientRect(); return Math.round(r.top + r.height / 2); });
    const right = Math.max(...[...el.children].map((e) => e.getBoundingClientRect().right));
    return [bar, {lines: new Set(centres.map((c) => Math.round(c / 12))).size, spread: Math.max(...centres) - Math.min(...centres), right}];
}))"""


def test_the_editing_toolbar_and_the_transport_are_one_line_each(vpage, api, project_copy):
    pid = project_copy["id"]
    doc = open_with_shots(vpage, api, pid)
    a, c = wide_shots(doc, 2)
    click_shot(vpage, a, doc["tick_s"])
    click_shot(vpage, c, doc["tick_s"], ["Shift"])
    width = vpage.viewport_size["width"]
    for tool in ("select", "points"):
        vpage.click(f"[data-testid=tool-{tool}]")
        rows = vpage.evaluate(ROWS)
        for bar, r in rows.items():
            assert r["spread"] <= 4 and r["right"] <= width, (tool, bar, r)
    info = vpage.locator("[data-testid=selection-info]")
    vpage.click("[data-testid=tool-select]")
    assert info.is_visible() and "2 shots" in info.text_content() and info.get_attribute("title") == info.text_content()
    assert "on A1–A9" in info.text_content()
