"""The GUIDE's Shots screenshots, a step of tests/browser/test_guide_screenshots.py kept apart so
that module stays short."""

from __future__ import annotations


def guide_shots(page, api, pid: str, shot, union) -> None:
    """The Shots section's screenshots (``shot(page, name, clip=...)`` takes one, ``union(page,
    *selectors)`` frames elements): two shots selected, the panel open; then the similarity
    slider's preview. Leaves the panel closed and nothing selected, as it found them."""
    from browser_support import lane_rect, next_frame, state

    doc = api.get(f"/api/projects/{pid}/shots").json()
    shots = [s for s in doc["shots"] if s["t1"] - s["t0"] >= 15]
    assert len(shots) >= 3, doc
    page.locator(".timeline-host").evaluate("(el) => { el.scrollTop = 0; }")
    page.wait_for_function("(n) => window.autohaptics.state().shots.count === n", arg=len(doc["shots"]))
    page.wait_for_function("() => window.autohaptics.state().shots.pictures.ready >= 1 && window.autohaptics.state().shots.pictures.inFlight === 0")
    lane = lane_rect(page, "shots")
    x = lambda s: page.evaluate("(t) => window.autohaptics.clientXOf(t)", (s["t0"] + s["t1"]) / 2 * doc["tick_s"])  # noqa: E731
    page.mouse.click(x(shots[0]), lane["y"] + lane["height"] / 2)
    page.keyboard.down("Shift")
    page.mouse.click(x(shots[2]), lane["y"] + lane["height"] / 2)
    page.keyboard.up("Shift")
    assert len(state(page)["selection"]["ranges"]) == 2
    page.click("[data-testid=toggle-shots]")
    page.select_option("[data-testid=shots-sort]", "loudest")
    page.wait_for_function("() => [...document.querySelectorAll('[data-testid=shot-row] img')].slice(0, 3).every((i) => i.complete && i.naturalWidth > 0)")
    next_frame(page)
    shot(page, "guide_shots")
    page.mouse.click(x(shots[0]), lane["y"] + lane["height"] / 2)
    page.click("[data-testid=shots-similar-open]")
    page.wait_for_selector("[data-testid=shots-similar]:not([hidden])")
    similar = api.get(f"/api/projects/{pid}/shots/{shots[0]['id']}/similar").json()["similar"]
    v = int((1 - similar[min(5, len(similar) - 1)]["distance"]) * 100)
    page.eval_on_selector("[data-testid=shots-similar-slider]",
                          "(el, v) => { el.value = String(v); el.dispatchEvent(new Event('input', {bubbles: true})); }", v)
    assert len(state(page)["shots"]["similar"]["ids"]) >= 1
    next_frame(page)
    shot(page, "guide_shots_similar", clip=union(page, "[data-testid=shots-panel]", "[data-testid=lane-shots]"))
    page.click("[data-testid=shots-similar-cancel]")
    page.click("[data-testid=toggle-shots]")
    page.keyboard.press("Escape")
    assert state(page)["selection"] is None
