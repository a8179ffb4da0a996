"""Learned styles in the editor (issue 32): learn a style on one project (name it, see the report
before saving), upload a second film with it, see the style's effect, undo the style choice."""

from __future__ import annotations

import json
import re

import numpy as np
import pytest

from autohaptics.testing import scenes, write_scene
from browser_support import (
    ARTIFACTS, copy_to_docs, open_editor, state, upload, wait_jobs_settled, wait_revision_above,
)

pytestmark = pytest.mark.browser

VIBRATION = [f"A{i}" for i in range(1, 10)]


def editor_vibration(pg, n_ticks: int) -> np.ndarray:
    """The composed vibration the editor holds, (n_ticks, 9)."""
    rows = pg.evaluate("(n) => Array.from({length: n}, (_, k) => window.autohaptics.valuesAt(k).vibration)", n_ticks)
    return np.asarray(rows, dtype=np.float64)


def guide_shot(element, name: str) -> None:
    """test-artifacts/screenshots/<name>.png of an element, copied to docs/img for docs/GUIDE.md
    when AUTOHAPTICS_UPDATE_DOCS_IMG=1."""
    ARTIFACTS.mkdir(parents=True, exist_ok=True)
    path = ARTIFACTS / f"{name}.png"
    element.screenshot(path=str(path))
    copy_to_docs(path, f"{name}.png")


def api_vibration(api, pid: str) -> np.ndarray:
    return np.asarray(api.get(f"/api/projects/{pid}/timeline").json()["tracks"]["vibration"], dtype=np.float64)


def test_learn_a_style_upload_a_film_in_it_and_undo_the_choice(page, api, tmp_path):
    learned_on = write_scene(tmp_path / "designed.mp4", scenes.sample_scene(8.0), width=96, height=54, fps=10,
                             quality="low")
    second = write_scene(tmp_path / "second film.mp4", scenes.left_boom_right_hum_scene(), width=96, height=54,
                         fps=10, quality="low")
    designed = upload(api, learned_on, name="designed")
    r = api.post(f"/api/projects/{designed['id']}/edits", json={"base_revision": designed["revision"], "op": {
        "op": "scale", "lanes": VIBRATION, "t0": 0, "t1": designed["n_ticks"], "factor": 0.5}})
    assert r.status_code == 200, r.text  # the designer's taste: everything at half
    plain = upload(api, second, name="second plain")
    styles_before = api.get("/api/styles").json()

    # Learn style... on the designed project: name it, learn (the report), then save.
    page.goto("/")
    page.wait_for_selector("[data-testid=projects-page]")
    page.locator(f"[data-testid=project-row][data-id='{designed['id']}'] [data-testid=project-learn-style]").click()
    dialog = page.locator("[data-testid=learn-style-dialog]")
    dialog.locator("[data-testid=style-name]").fill("half")
    assert dialog.locator("[data-testid=style-save]").is_disabled()
    dialog.locator("[data-testid=style-learn]").click()
    explained = dialog.locator("[data-testid=style-explained]")
    explained.wait_for()
    share = float(explained.get_attribute("data-explained"))
    assert share > 0.8
    summary = dialog.locator("[data-testid=style-summary]").inner_text()
    assert 45 <= int(re.search(r"full vibration becomes (\d+) %", summary).group(1)) <= 55, summary
    assert api.get("/api/styles").json() == styles_before  # nothing stored before Save
    guide_shot(dialog, "guide_learn_style")
    dialog.locator("[data-testid=style-save]").click()
    dialog.wait_for(state="detached")
    stored = [s for s in api.get("/api/styles").json() if s["name"] == "half"]
    assert len(stored) == 1 and stored[0]["films"][0]["project_id"] == designed["id"]
    style_id = stored[0]["id"]
    row = page.locator(f"[data-testid=style-row][data-id='{style_id}']")
    assert f"designed (explains {int(share * 100 + 0.5)} %)" in row.inner_text(), row.inner_text()

    # The style file: download it, import it again (a second style), delete the copy.
    with page.expect_download() as got:
        row.locator("[data-testid=style-download]").click()
    saved = tmp_path / "half.style.json"
    got.value.save_as(saved)
    assert json.loads(saved.read_text()) == api.get(f"/api/styles/{style_id}").json()["document"]
    page.set_input_files("[data-testid=style-import-input]", str(saved))
    page.wait_for_function("() => document.querySelectorAll('[data-testid=style-row]').length === 2")
    copy = page.locator("[data-testid=style-row]", has_text="imported")
    copy_id = copy.get_attribute("data-id")
    copy.locator("[data-testid=style-delete]").click()
    page.click("[data-testid=dialog-ok]")
    page.wait_for_function("() => document.querySelectorAll('[data-testid=style-row]').length === 1")
    assert api.get(f"/api/styles/{copy_id}").status_code == 404

    # Upload the second film in that style.
    page.select_option("[data-testid=upload-style]", label="half")
    page.set_input_files("[data-testid=file-input]", str(second))
    page.wait_for_function("() => document.querySelector('[data-testid=upload-status]').textContent.startsWith('Ready')",
                           timeout=120_000)
    href = page.locator("[data-testid=open-uploaded]").get_attribute("href")
    pid = href.rsplit("/", 1)[-1]
    assert api.get(f"/api/projects/{pid}").json()["params"]["style"]["id"] == style_id

    # The style's effect: the header names it, the editor's vibration is half the plain film's.
    open_editor(page, pid)
    badge = page.locator("[data-testid=style-badge]")
    assert badge.inner_text() == "Style: half"
    n = plain["n_ticks"]
    reference = api_vibration(api, plain["id"])
    assert reference.max() > 0.3
    np.testing.assert_allclose(editor_vibration(page, n), reference * 0.5, atol=0.03)
    guide_shot(page.locator("header.topbar"), "guide_style_header")

    # Drop the style in Regenerate (a settings change), then undo that choice.
    page.click("[data-testid=regenerate]")
    regen = page.locator("[data-testid=regenerate-dialog]")
    assert regen.locator("[data-testid=regen-style]").input_value() == style_id
    regen.locator("[data-testid=regen-style]").select_option(label="None")
    before = state(page)["revision"]
    regen.locator("[data-testid=regen-start]").click()
    wait_revision_above(page, before)
    wait_jobs_settled(page)
    page.wait_for_function("() => document.querySelector('[data-testid=style-badge]').textContent === 'No style'")
    assert "style" not in api.get(f"/api/projects/{pid}").json()["params"]
    np.testing.assert_allclose(editor_vibration(page, n), reference, atol=0.01)

    before = state(page)["revision"]
    page.click("[data-testid=undo]")
    wait_revision_above(page, before)
    page.wait_for_function("() => document.querySelector('[data-testid=style-badge]').textContent === 'Style: half'")
    assert api.get(f"/api/projects/{pid}").json()["params"]["style"]["id"] == style_id
    np.testing.assert_allclose(editor_vibration(page, n), reference * 0.5, atol=0.03)
