"""Accessibility basics: every control has a name, keyboard focus is visible, lanes are labelled."""

from __future__ import annotations

import pytest

from browser_support import open_editor

pytestmark = pytest.mark.browser

UNNAMED = """() => {
    const name = (el) => {
        if (el.getAttribute('aria-label')) return el.getAttribute('aria-label');
        if (el.getAttribute('aria-labelledby')) return document.getElementById(el.getAttribute('aria-labelledby'))?.textContent;
        if (el.labels && el.labels.length) return el.labels[0].textContent;
        if (el.closest('label')) return el.closest('label').textContent;
        return el.textContent.trim() || el.getAttribute('title');
    };
    return Array.from(document.querySelectorAll('button, summary, a[href], input, select, canvas, [role=progressbar]'))
        .filter((el) => el.getClientRects().length && el.type !== 'hidden' && !el.classList.contains('visually-hidden'))
        .filter((el) => !(name(el) || '').trim())
        .map((el) => el.outerHTML.slice(0, 120));
}"""


def test_every_control_has_an_accessible_name(page, project_copy):
    page.goto("/")
    page.wait_for_selector("[data-testid=project-row]")
    assert page.evaluate(UNNAMED) == []
    open_editor(page, project_copy["id"])
    assert page.evaluate(UNNAMED) == []
    lanes = page.eval_on_selector_all("canvas[data-lane]", "els => els.map(e => [e.dataset.lane, e.getAttribute('role'), e.getAttribute('aria-label')])")
    assert {lane for lane, _, _ in lanes} >= {"waveform", "feature-loudness", "actuators", "temperature", "fans", "markers"}
    assert all(role == "img" and label for _, role, label in lanes)
    # The hidden file input behind Import… is not announced as a second button.
    assert page.get_by_role("button", name="Import", exact=False).count() == 1


def test_keyboard_focus_is_visible(page, project_copy):
    open_editor(page, project_copy["id"])
    page.focus("[data-testid=back]")
    page.keyboard.press("Tab")  # keyboard focus: :focus-visible applies
    focused = page.evaluate("""() => {
        const el = document.activeElement, cs = getComputedStyle(el);
        return {tag: el.tagName, outline: cs.outlineStyle, width: parseFloat(cs.outlineWidth)};
    }""")
    assert focused["tag"] in ("BUTTON", "A", "SUMMARY", "INPUT")
    assert focused["outline"] != "none" and focused["width"] >= 2


def described(pg, lane: str) -> str:
    """The text that describes a lane's canvas to assistive tech (its aria-describedby)."""
    return pg.evaluate("""(id) => {
        const c = document.querySelector(`canvas[data-lane="${id}"]`);
        const ref = c.getAttribute('aria-describedby');
        return ref ? document.getElementById(ref).textContent : '';
    }""", lane)


def test_every_lane_says_in_words_what_is_on_it_around_the_playhead(page, api, project_copy):
    pid = project_copy["id"]
    rev = api.get(f"/api/projects/{pid}").json()["revision"]
    r = api.post(f"/api/projects/{pid}/edits", json={"base_revision": rev, "op": {
        "op": "marker_add", "marker": {"id": "m-door", "t_s": 8.0, "label": "Door slam"}}})
    assert r.status_code == 200, r.text
    open_editor(page, pid)
    lanes = page.eval_on_selector_all("canvas[data-lane]", "els => els.map(e => e.dataset.lane)")
    page.evaluate("() => document.querySelector('[data-testid=video]').currentTime = 7.3")
    page.wait_for_function("() => /^At 0:07\\.3/.test(document.getElementById('lane-text-actuators').textContent)")
    page.wait_for_function("() => window.autohaptics.state().played !== null")
    for lane in lanes:
        assert described(page, lane).strip(), f"lane {lane} has no text alternative"
    v = page.evaluate("() => window.autohaptics.valuesAt(73)")
    ids = page.evaluate("() => Array.from(document.querySelectorAll('[data-testid^=chair-A]')).map(g => g.dataset.testid.slice(6))")
    text = described(page, "actuators")
    assert text.startswith("At 0:07.3: " + ", ".join(f"{a} {x:.2f}" for a, x in zip(ids, v["vibration"]))), text
    assert "strongest 0:05.3–0:09.4: A" in text, text
    thr = page.evaluate("() => window.autohaptics.state().thresholds.loudness")
    text = described(page, "feature-loudness")
    assert text.startswith(f"At 0:07.3: {v['features']['loudness']:.2f} (threshold {thr:.2f})"), text
    text = described(page, "temperature")
    assert f"target {v['temperature_c']:.1f} °C, the chair plays {v['played_c']:.1f} °C" in text, text
    assert f"{v['fans'] * 100:.0f} % of the fans on" in described(page, "fans")
    assert described(page, "markers") == 'Markers 0:05.3–0:09.4: "Door slam" at 0:08.0; 1 in all.'
    # Far from the marker the line says so; the lines follow the playhead.
    page.evaluate("() => document.querySelector('[data-testid=video]').currentTime = 20.0")
    page.wait_for_function("() => /^At 0:20\\.0/.test(document.getElementById('lane-text-actuators').textContent)")
    assert described(page, "markers") == "No marker 0:18.0–0:22.1; 1 in all."
