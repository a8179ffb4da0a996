"""The density control beside the threshold sliders: the share of the film that vibrates, asked
for and shown (the `intensity.density` override, re-derived by the server)."""

from __future__ import annotations

import re

import pytest

from browser_support import open_editor, screenshot, state, wait_jobs_settled, wait_revision_above, wait_until

pytestmark = pytest.mark.browser


def shown_share(pg) -> float:
    """The share the panel says vibrates, 0..1."""
    text = pg.text_content("[data-testid=vibration-share]") or ""
    m = re.search(r"(\d+) %", text)
    assert m, f"no share in {text!r}"
    return int(m.group(1)) / 100


def density(api, pid: str) -> float | None:
    """The density the project asks for (None: off)."""
    return api.get(f"/api/projects/{pid}").json()["params"]["overrides"].get("intensity.density")


def server_share(api, pid: str) -> float:
    """The share of the composed timeline's ticks on which some actuator vibrates."""
    rows = api.get(f"/api/projects/{pid}/timeline").json()["tracks"]["vibration"]  # [n_ticks][9]
    return sum(1 for row in rows if max(row) > 0) / len(rows)


def test_density_asks_for_a_share_and_the_panel_shows_what_vibrates(page, api, project_copy):
    pid = project_copy["id"]
    open_editor(page, pid)
    before = shown_share(page)
    assert before == pytest.approx(server_share(api, pid), abs=0.006)
    assert page.get_attribute("[data-testid=density-on]", "aria-label")
    assert page.is_disabled("[data-testid=density]")
    assert page.text_content("[data-testid=density] ~ output") == "off"

    s0 = state(page)
    page.check("[data-testid=density-on]")  # on at the slider's value, 25 %
    wait_revision_above(page, s0["revision"])
    assert density(api, pid) == pytest.approx(0.25)
    assert page.text_content("[data-testid=density] ~ output") == "25 %"
    assert shown_share(page) == pytest.approx(0.25, abs=0.03)
    assert shown_share(page) == pytest.approx(server_share(api, pid), abs=0.006)
    screenshot(page, "editor-density")

    wait_jobs_settled(page)  # the first change may refine ticks in the background
    s1 = state(page)
    page.focus("[data-testid=density]")
    page.keyboard.press("ArrowRight")  # one step, a `change` event: 25 % -> 26 %
    wait_until(lambda: density(api, pid) == pytest.approx(0.26), "the density saved")
    wait_revision_above(page, s1["revision"])
    assert page.text_content("[data-testid=density] ~ output") == "26 %"
    assert shown_share(page) == pytest.approx(0.26, abs=0.03)
    wait_jobs_settled(page)

    s2 = state(page)
    page.uncheck("[data-testid=density-on]")  # off: the thresholds alone again
    wait_revision_above(page, s2["revision"])
    assert density(api, pid) is None
    assert shown_share(page) == pytest.approx(before, abs=0.006)
    wait_jobs_settled(page)


def test_the_density_survives_a_reload(page, api, project_copy):
    pid = project_copy["id"]
    r = api.put(f"/api/projects/{pid}/params", json={"overrides": {"intensity.density": 0.4}})
    assert r.status_code in (200, 202), r.text
    open_editor(page, pid)
    assert page.is_checked("[data-testid=density-on]")
    assert page.text_content("[data-testid=density] ~ output") == "40 %"
    assert shown_share(page) == pytest.approx(0.4, abs=0.04)
