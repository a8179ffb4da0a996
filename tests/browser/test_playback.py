"""Playback, scrubbing, zoom and pan: the playhead follows video.currentTime."""

from __future__ import annotations

import pytest

from browser_support import client_x, lane_rect, open_editor, screenshot, state, wait_until

pytestmark = pytest.mark.browser


def playhead_x(pg) -> float:
    return pg.evaluate(
        "() => new DOMMatrixReadOnly(getComputedStyle(document.querySelector('[data-testid=playhead]')).transform).m41")


def video_time(pg) -> float:
    return pg.evaluate("() => document.querySelector('[data-testid=video]').currentTime")


def test_play_pause_and_the_playhead_follows(page, project_copy):
    open_editor(page, project_copy["id"])
    page.wait_for_function("() => document.querySelector('[data-testid=video]').readyState >= 2")
    x0 = playhead_x(page)
    page.click("[data-testid=play]")
    page.wait_for_function("() => document.querySelector('[data-testid=video]').currentTime > 0.6")
    assert state(page)["playing"] is True
    assert page.get_attribute("[data-testid=play]", "aria-label") == "Pause (Space)"
    page.keyboard.press("Space")
    page.wait_for_function("() => document.querySelector('[data-testid=video]').paused")
    s = state(page)
    t = video_time(page)
    assert s["playing"] is False
    assert s["playheadS"] == pytest.approx(t, abs=0.05)
    assert playhead_x(page) > x0
    # The chair diagram shows the composed values at the playhead's tick.
    tick = int(t / 0.1 + 1e-9)
    values = page.evaluate("(k) => window.autohaptics.valuesAt(k)", tick)
    shown = float(page.get_attribute("[data-testid=chair-A1]", "data-value"))
    assert shown == pytest.approx(values["vibration"][0], abs=1e-3)
    assert page.text_content("[data-testid=chair-temperature]") == f"{values['temperature_c']:.1f} °C"


def test_scrub_on_the_ruler_and_keyboard_navigation(page, project_copy):
    open_editor(page, project_copy["id"])
    ruler = lane_rect(page, "waveform")
    y = page.evaluate("() => document.querySelector('[data-testid=ruler]').getBoundingClientRect().y + 10")
    page.mouse.move(client_x(page, 5.0), y)
    page.mouse.down()
    page.mouse.move(client_x(page, 12.0), y, steps=4)
    assert state(page)["playheadS"] == pytest.approx(12.0, abs=0.2)  # live while dragging
    page.mouse.move(client_x(page, 20.0), y, steps=4)
    page.mouse.up()
    page.wait_for_function("() => Math.abs(document.querySelector('[data-testid=video]').currentTime - 20) < 0.2")
    assert state(page)["playheadS"] == pytest.approx(20.0, abs=0.2)
    assert ruler["width"] > 500

    page.locator("[data-testid=timeline]").focus()
    page.keyboard.press("ArrowRight")
    page.wait_for_function("() => Math.abs(window.autohaptics.state().currentTime - 20.1) < 0.051")
    page.keyboard.press("Shift+ArrowLeft")
    page.wait_for_function("() => Math.abs(window.autohaptics.state().currentTime - 19.1) < 0.051")
    page.keyboard.press("End")
    page.wait_for_function("() => window.autohaptics.state().currentTime > window.autohaptics.state().durationS - 0.2")
    page.keyboard.press("Home")
    page.wait_for_function("() => window.autohaptics.state().currentTime === 0")

    fit = state(page)["pxPerS"]
    page.keyboard.press("+")
    assert state(page)["pxPerS"] == pytest.approx(fit * 1.5)
    page.keyboard.press("-")
    assert state(page)["pxPerS"] == pytest.approx(fit)


def test_wheel_zooms_with_ctrl_and_pans_without(page, api, project_copy):
    open_editor(page, project_copy["id"])
    wave = lane_rect(page, "waveform")
    cx, cy = wave["x"] + wave["width"] / 2, wave["y"] + wave["height"] / 2
    before = state(page)
    anchor_t = before["startS"] + (cx - wave["x"]) / before["pxPerS"]
    page.mouse.move(cx, cy)
    page.keyboard.down("Control")
    page.mouse.wheel(0, -300)
    page.keyboard.up("Control")
    page.wait_for_function(f"() => window.autohaptics.state().pxPerS > {before['pxPerS'] * 1.5}")
    zoomed = state(page)
    # Zooming keeps the time under the pointer in place.
    assert zoomed["startS"] + (cx - wave["x"]) / zoomed["pxPerS"] == pytest.approx(anchor_t, abs=0.05)
    page.mouse.wheel(0, 200)
    page.wait_for_function(f"() => window.autohaptics.state().startS > {zoomed['startS'] + 1}")
    panned = state(page)
    assert panned["pxPerS"] == pytest.approx(zoomed["pxPerS"])
    assert panned["startS"] == pytest.approx(zoomed["startS"] + 200 / zoomed["pxPerS"], abs=0.05)
    screenshot(page, "editor-zoomed")
    # The view is a saved setting: after a reload it comes back.
    pid = project_copy["id"]
    wait_until(lambda: abs(api.get(f"/api/projects/{pid}").json()["view"].get("px_per_s", 0) - panned["pxPerS"]) < 0.01,
               "the view settings reach the server")
    open_editor(page, project_copy["id"])
    page.wait_for_function(f"() => Math.abs(window.autohaptics.state().pxPerS - {panned['pxPerS']}) < 0.01")
    assert state(page)["startS"] == pytest.approx(panned["startS"], abs=0.01)
