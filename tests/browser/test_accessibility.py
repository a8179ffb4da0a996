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
