"""The editor walked as a designer (issue 18), its settings in the edit history: a typed threshold,
the density and a regeneration with another preset are undone and redone like the edits, each
bringing back its parameters and the timeline made with them."""

from __future__ import annotations

import pytest

from browser_support import open_editor, sampled_ticks, state, wait_jobs_settled, wait_revision_above

pytestmark = pytest.mark.browser


def click_when_enabled(pg, testid: str) -> None:
    pg.wait_for_function(f"() => !document.querySelector('[data-testid={testid}]').disabled")
    pg.click(f"[data-testid={testid}]")


def test_a_typed_threshold_is_undone_and_redone(page, api, project_copy):
    pid = project_copy["id"]
    open_editor(page, pid)
    s0 = state(page)
    before = s0["thresholds"]["loudness"]
    assert page.is_disabled("[data-testid=undo]")
    page.fill("[data-testid=threshold-value-loudness]", "0.437")
    page.press("[data-testid=threshold-value-loudness]", "Enter")
    s1 = wait_revision_above(page, s0["revision"])
    assert s1["thresholds"]["loudness"] == pytest.approx(0.437)
    assert api.get(f"/api/projects/{pid}").json()["params"]["thresholds"]["loudness"] == pytest.approx(0.437)
    page.wait_for_function("() => !document.querySelector('[data-testid=undo]').disabled")
    ops = api.get(f"/api/projects/{pid}/edits").json()["ops"]
    assert [op["op"] for op in ops] == ["params"] and ops[0]["to"]["thresholds"]["loudness"] == 0.437
    # A typed value outside 0..1 is refused with a warning and nothing is sent.
    page.fill("[data-testid=threshold-value-loudness]", "7")
    page.press("[data-testid=threshold-value-loudness]", "Enter")
    page.wait_for_selector(".toast >> text=A threshold is a number from 0 to 1")
    assert page.input_value("[data-testid=threshold-value-loudness]") == "0.437"
    assert len(api.get(f"/api/projects/{pid}/edits").json()["ops"]) == 1
    # Undo: the previous threshold is in force again, in the panel and on the server.
    s1 = state(page)
    page.click("[data-testid=undo]")
    s2 = wait_revision_above(page, s1["revision"])
    page.wait_for_function(f"() => window.autohaptics.state().thresholds.loudness === {before}")
    assert api.get(f"/api/projects/{pid}").json()["params"]["thresholds"]["loudness"] == pytest.approx(before)
    assert page.input_value("[data-testid=threshold-value-loudness]") == str(before)
    assert page.input_value("[data-testid=threshold-loudness]") == str(before)
    # Redo brings the typed value back.
    page.wait_for_function("() => !document.querySelector('[data-testid=redo]').disabled")
    page.click("[data-testid=redo]")
    wait_revision_above(page, s2["revision"])
    page.wait_for_function("() => window.autohaptics.state().thresholds.loudness === 0.437")
    assert api.get(f"/api/projects/{pid}").json()["params"]["thresholds"]["loudness"] == pytest.approx(0.437)



def test_the_density_is_undone_and_redone(page, api, project_copy):
    pid = project_copy["id"]
    open_editor(page, pid)
    share_text = page.text_content("[data-testid=vibration-share]")
    s0 = state(page)
    page.check("[data-testid=density-on]")  # on at the slider's value, 25 %
    wait_revision_above(page, s0["revision"])
    s1 = wait_jobs_settled(page)  # the change may refine ticks in the background
    assert api.get(f"/api/projects/{pid}").json()["params"]["overrides"] == {"intensity.density": 0.25}
    assert page.text_content("[data-testid=vibration-share]") != share_text
    click_when_enabled(page, "undo")
    s2 = wait_revision_above(page, s1["revision"])
    wait_jobs_settled(page)
    assert api.get(f"/api/projects/{pid}").json()["params"]["overrides"] == {}
    assert not page.is_checked("[data-testid=density-on]")
    assert page.text_content("[data-testid=density] ~ output") == "off"
    assert page.text_content("[data-testid=vibration-share]") == share_text, "the share of the thresholds alone"
    click_when_enabled(page, "redo")
    wait_revision_above(page, s2["revision"])
    wait_jobs_settled(page)
    assert api.get(f"/api/projects/{pid}").json()["params"]["overrides"] == {"intensity.density": 0.25}
    assert page.is_checked("[data-testid=density-on]")
    assert page.text_content("[data-testid=density] ~ output") == "25 %"


def test_a_regeneration_with_another_preset_is_undone_and_redone(page, api, project_copy):
    pid = project_copy["id"]
    p0 = api.get(f"/api/projects/{pid}").json()["params"]
    assert p0["preset"] == "balanced"
    open_editor(page, pid)
    info = "[data-testid=params-info]"
    assert page.text_content(info) == f"Preset balanced · mode {p0['mode']}"
    assert page.is_disabled("[data-testid=undo]")
    before = sampled_ticks(page)
    s0 = state(page)
    page.click("[data-testid=regenerate]")
    page.select_option("[data-testid=regen-preset]", "fast")
    page.click("[data-testid=regen-start]")
    page.wait_for_function("() => document.querySelector('[data-testid=job-slot] [data-testid=generation-status]')"
                           "?.textContent === 'Generation finished.'", timeout=120_000)
    s1 = wait_revision_above(page, s0["revision"])
    s1 = wait_jobs_settled(page)
    assert page.text_content(info) == f"Preset fast · mode {p0['mode']}"
    regenerated = sampled_ticks(page)
    assert regenerated != before, "the fast preset's timeline is on show"
    assert s1["nOps"] == 1 and s1["cursor"] == 1
    # Undo: the balanced preset and its timeline again (from the analysis the regeneration kept).
    click_when_enabled(page, "undo")
    s2 = wait_revision_above(page, s1["revision"])
    s2 = wait_jobs_settled(page)
    assert page.text_content(info) == f"Preset balanced · mode {p0['mode']}"
    assert api.get(f"/api/projects/{pid}").json()["params"] == p0
    assert sampled_ticks(page) == before
    # Redo: the regeneration's preset and timeline again.
    click_when_enabled(page, "redo")
    wait_revision_above(page, s2["revision"])
    wait_jobs_settled(page)
    assert page.text_content(info) == f"Preset fast · mode {p0['mode']}"
    assert api.get(f"/api/projects/{pid}").json()["params"]["preset"] == "fast"
    assert sampled_ticks(page) == regenerated
