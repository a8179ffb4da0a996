"""Editing tools: pencil, temperature points, range operations, copy/paste, markers, fans and the overlay."""

from __future__ import annotations

import pytest

from browser_support import (
    client_x, lane_pixels, lane_rect, next_frame, open_editor, screenshot, state, values_at, wait_revision_above,
)

pytestmark = pytest.mark.browser

BYTE = 1 / 255 + 1e-6  # vibration and fans travel as bytes


def drag(pg, x0: float, y0: float, x1: float, y1: float, steps: int = 8) -> None:
    pg.mouse.move(x0, y0)
    pg.mouse.down()
    pg.mouse.move(x1, y1, steps=steps)
    pg.mouse.up()


def submit(pg, action) -> dict:
    """Run a UI action that saves one change and wait until it is saved and drawn."""
    before = state(pg)["revision"]
    action()
    return wait_revision_above(pg, before)


def test_pencil_draws_values_on_the_detail_lane(page, project_copy):
    open_editor(page, project_copy["id"])
    page.select_option("[data-testid=detail-actuator]", "A3")  # off everywhere in audio mode
    page.click("[data-testid=tool-pencil]")
    assert page.get_attribute("[data-testid=tool-pencil]", "aria-pressed") == "true"
    r = lane_rect(page, "detail")
    y_of = lambda v: r["y"] + r["height"] - 4 - v * (r["height"] - 8)  # noqa: E731
    s = submit(page, lambda: drag(page, client_x(page, 10.05), y_of(0.8), client_x(page, 12.05), y_of(0.2), steps=12))
    op = page.evaluate("() => fetch(`/api/projects/${window.autohaptics.state().projectId}/edits`).then(r => r.json())")
    assert op["ops"][-1]["op"] == "pencil" and op["ops"][-1]["lane"] == "A3"
    assert op["ops"][-1]["t0"] == 100 and len(op["ops"][-1]["values"]) == 21
    a3 = [values_at(page, k)["vibration"][2] for k in range(100, 121)]
    assert a3[0] == pytest.approx(0.8, abs=0.03)
    assert a3[-1] == pytest.approx(0.2, abs=0.03)
    assert all(b <= a + BYTE for a, b in zip(a3, a3[1:])), "a straight stroke downwards gives falling values"
    assert values_at(page, 99)["vibration"][2] == 0 and values_at(page, 121)["vibration"][2] == 0
    assert s["cursor"] == 1


def test_temperature_points_become_one_piecewise_linear_edit(page, project_copy):
    open_editor(page, project_copy["id"])
    page.click("[data-testid=tool-points]")
    r = lane_rect(page, "temperature")
    y_of = lambda c: r["y"] + r["height"] - 5 - (c - 30) / 25 * (r["height"] - 10)  # noqa: E731  (30..55 C)
    page.mouse.click(client_x(page, 5.05), y_of(40))
    page.mouse.click(client_x(page, 15.05), y_of(36))
    page.wait_for_function("() => !document.querySelector('[data-testid=points-apply]').disabled")
    screenshot(page, "editor-temperature-points")
    outside = values_at(page, 151)["temperature_c"]  # the generated value, after the edited range
    submit(page, lambda: page.click("[data-testid=points-apply]"))
    assert values_at(page, 50)["temperature_c"] == pytest.approx(40, abs=0.3)
    assert values_at(page, 100)["temperature_c"] == pytest.approx(38, abs=0.3)
    assert values_at(page, 150)["temperature_c"] == pytest.approx(36, abs=0.3)
    assert values_at(page, 151)["temperature_c"] == outside
    assert page.is_disabled("[data-testid=points-apply]"), "the applied draft is cleared"


def test_range_operations_set_fade_scale_clear(page, project_copy):
    open_editor(page, project_copy["id"])
    r = lane_rect(page, "actuators")
    y_a5 = r["y"] + 4.5 * r["height"] / 9
    drag(page, client_x(page, 40.05), y_a5, client_x(page, 41.95), y_a5)  # A5, ticks 400..419
    assert state(page)["selection"] == {"t0": 400, "t1": 420, "lanes": ["A5"]}
    page.fill("[data-testid=edit-value]", "0.8")
    submit(page, lambda: page.click("[data-testid=edit-set]"))
    assert values_at(page, 410)["vibration"][4] == pytest.approx(0.8, abs=BYTE)
    submit(page, lambda: page.click("[data-testid=edit-fade-in]"))
    assert values_at(page, 400)["vibration"][4] == 0
    assert values_at(page, 419)["vibration"][4] == pytest.approx(0.8, abs=BYTE)
    page.fill("[data-testid=edit-factor]", "0.5")
    submit(page, lambda: page.click("[data-testid=edit-scale]"))
    assert values_at(page, 419)["vibration"][4] == pytest.approx(0.4, abs=BYTE)
    page.locator("[data-testid=timeline]").focus()
    submit(page, lambda: page.keyboard.press("Delete"))
    assert all(values_at(page, k)["vibration"][4] == 0 for k in (400, 410, 419))
    assert state(page)["cursor"] == 4

    # One value cannot mean 0..1 and degrees at once: Set is refused for a mixed selection.
    page.click("[data-testid=lane-chip-temperature]")
    assert state(page)["selection"]["lanes"] == ["A5", "temperature"]
    assert page.is_disabled("[data-testid=edit-set]")
    page.click("[data-testid=lane-chip-A5]")
    assert page.is_enabled("[data-testid=edit-set]")
    assert page.get_attribute("[data-testid=edit-value]", "aria-label") == "Temperature to set, °C"


def test_set_and_scale_without_a_number_warn_and_write_nothing(page, api, project_copy):
    pid = project_copy["id"]
    open_editor(page, pid)
    r = lane_rect(page, "actuators")
    y_a5 = r["y"] + 4.5 * r["height"] / 9
    drag(page, client_x(page, 40.05), y_a5, client_x(page, 41.95), y_a5)  # A5, ticks 400..419
    assert state(page)["selection"] == {"t0": 400, "t1": 420, "lanes": ["A5"]}
    s0 = state(page)
    before = values_at(page, 410)["vibration"][4]

    def refused(field: str, typed: str, button: str, message: str) -> None:
        page.fill(f"[data-testid={field}]", "")
        page.focus(f"[data-testid={field}]")
        page.keyboard.type(typed)  # what a number field lets through: "" and "1e" are no number
        page.click(f"[data-testid={button}]")
        toast = page.locator("[data-testid=toast-warn]", has_text=message).last
        toast.wait_for()
        page.evaluate("(el) => el.remove()", toast.element_handle())

    for typed in ("", "1e", "-"):
        refused("edit-value", typed, "edit-set", "Enter a number to set.")
        refused("edit-factor", typed, "edit-scale", "The scale factor must be a number ≥ 0.")
    page.wait_for_timeout(300)  # a request sent anyway would have moved the revision by now
    s1 = state(page)
    assert (s1["revision"], s1["cursor"], s1["saveState"]) == (s0["revision"], 0, "saved")
    assert api.get(f"/api/projects/{pid}/edits").json()["ops"] == []
    assert api.get(f"/api/projects/{pid}").json()["revision"] == s0["revision"]
    assert values_at(page, 410)["vibration"][4] == before


def test_copy_and_paste_at_the_playhead(page, project_copy):
    open_editor(page, project_copy["id"])
    r = lane_rect(page, "actuators")
    y_a1 = r["y"] + 0.5 * r["height"] / 9
    a1 = [values_at(page, k)["vibration"][0] for k in range(250, 300)]
    start = 250 + max(range(len(a1)), key=lambda i: a1[i]) - 5
    source = [values_at(page, k)["vibration"][0] for k in range(start, start + 10)]
    assert max(source) > 0, "the copied range should hold some vibration"
    drag(page, client_x(page, start * 0.1 + 0.05), y_a1, client_x(page, (start + 9) * 0.1 + 0.05), y_a1)
    page.locator("[data-testid=timeline]").focus()
    page.keyboard.press("Control+c")
    page.wait_for_function("() => !document.querySelector('[data-testid=edit-paste]').disabled")
    page.keyboard.press("Home")
    page.wait_for_function("() => window.autohaptics.state().currentTime === 0")
    submit(page, lambda: page.keyboard.press("Control+v"))
    pasted = [values_at(page, k)["vibration"][0] for k in range(0, 10)]
    assert pasted == pytest.approx(source, abs=BYTE)


def test_markers_add_rename_move_delete_and_undo(page, project_copy):
    open_editor(page, project_copy["id"])
    ruler_y = page.evaluate("() => document.querySelector('[data-testid=ruler]').getBoundingClientRect().y + 10")
    page.mouse.click(client_x(page, 12.0), ruler_y)
    page.wait_for_function("() => Math.abs(window.autohaptics.state().currentTime - 12) < 0.1")
    page.click("[data-testid=marker-add]")
    page.fill("[data-testid=dialog-input]", "Dragon")
    submit(page, lambda: page.click("[data-testid=dialog-ok]"))
    markers = state(page)["markers"]
    assert [m["label"] for m in markers] == ["Dragon"]
    assert markers[0]["t_s"] == pytest.approx(12.0, abs=0.1)

    page.click("[data-testid=marker-rename]")
    page.fill("[data-testid=dialog-input]", "Dragon attack")
    submit(page, lambda: page.click("[data-testid=dialog-ok]"))
    assert state(page)["markers"][0]["label"] == "Dragon attack"

    lane = lane_rect(page, "markers")
    y = lane["y"] + lane["height"] / 2
    submit(page, lambda: drag(page, client_x(page, markers[0]["t_s"]), y, client_x(page, 20.0), y))
    assert state(page)["markers"][0]["t_s"] == pytest.approx(20.0, abs=0.15)

    page.mouse.dblclick(client_x(page, 30.0), y)
    page.fill("[data-testid=dialog-input]", "Finale")
    submit(page, lambda: page.click("[data-testid=dialog-ok]"))
    assert [m["label"] for m in state(page)["markers"]] == ["Dragon attack", "Finale"]
    screenshot(page, "editor-markers")

    page.locator("[data-testid=timeline]").focus()
    submit(page, lambda: page.keyboard.press("Delete"))  # the new marker is selected
    assert [m["label"] for m in state(page)["markers"]] == ["Dragon attack"]
    submit(page, lambda: page.click("[data-testid=undo]"))
    assert [m["label"] for m in state(page)["markers"]] == ["Dragon attack", "Finale"]


def test_fans_edit_shows_in_the_lane_the_overlay_and_the_chair(page, project_copy):
    open_editor(page, project_copy["id"])
    fans_before = lane_pixels(page, "fans")
    r = lane_rect(page, "fans")
    y = r["y"] + r["height"] / 2
    drag(page, client_x(page, 5.05), y, client_x(page, 7.95), y)
    assert state(page)["selection"]["lanes"] == ["fans"]
    page.fill("[data-testid=edit-value]", "0.8")
    submit(page, lambda: page.click("[data-testid=edit-set]"))
    v = values_at(page, 60)
    assert v["fans"] == 1.0
    assert v["fan_grid"] == pytest.approx([0.8] * 153, abs=BYTE)
    page.keyboard.press("Escape")
    next_frame(page)
    assert lane_pixels(page, "fans")["lit"] > fans_before["lit"]

    page.click("[data-testid=toggle-fan-overlay]")
    page.evaluate("() => { document.querySelector('[data-testid=video]').currentTime = 6.05; }")
    page.wait_for_function("() => Math.abs(window.autohaptics.state().playheadS - 6.05) < 0.01")
    page.wait_for_function("() => document.querySelector('[data-testid=video]').videoWidth > 0")
    assert page.text_content("[data-testid=chair-fans]") == "Fans on: 100 %"
    centre = page.evaluate("""() => {
        const c = document.querySelector('[data-testid=fan-overlay]');
        const d = c.getContext('2d').getImageData(Math.floor(c.width / 2) + 3, Math.floor(c.height / 2) + 3, 1, 1).data;
        return Array.from(d);
    }""")
    assert centre[3] > 100 and centre[2] > centre[0], "a cyan fan cell is drawn over the picture"
    screenshot(page, "editor-fan-grid")
