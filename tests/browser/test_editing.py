"""Thresholds, range edits, undo/redo, persistence, regeneration keeping edits, export, conflicts."""

from __future__ import annotations

import csv
import json

import numpy as np
import pytest

from autohaptics.timeline import Timeline
from browser_support import (
    copy_to_docs, lane_pixels, lane_rect, next_frame, open_editor, screenshot, settled_lane_pixels, state, upload,
    values_at, wait_revision_above,
)

pytestmark = pytest.mark.browser

FULL = (252, 245, 168)  # the heat map's colour at 1.0


def pixel(pg, lane: str, x: float, y: float) -> tuple[int, int, int]:
    """Colour of one lane pixel at client coordinates."""
    return tuple(pg.evaluate(
        """([lane, x, y]) => {
            const c = document.querySelector(`canvas[data-lane="${lane}"]`);
            const r = c.getBoundingClientRect();
            const k = c.width / r.width;
            return Array.from(c.getContext('2d').getImageData(Math.floor((x - r.x) * k), Math.floor((y - r.y) * k), 1, 1).data.slice(0, 3));
        }""",
        [lane, x, y]))


def threshold_y(rect: dict, value: float) -> float:
    """Client y of a threshold line (features lane: 3 px padding top and bottom)."""
    return rect["y"] + rect["height"] - 3 - value * (rect["height"] - 6)


def row_y(rect: dict, index: int) -> float:
    """Client y of the middle of heat-map row ``index`` (A1 = 0)."""
    return rect["y"] + (index + 0.5) * rect["height"] / 9


def select_rows(pg, t0: float, t1: float, first_row: int, last_row: int) -> None:
    """Drag on the heat map from (t0, first_row) to (t1, last_row)."""
    r = lane_rect(pg, "actuators")
    pg.mouse.move(pg.evaluate("(t) => window.autohaptics.clientXOf(t)", t0), row_y(r, first_row))
    pg.mouse.down()
    pg.mouse.move(pg.evaluate("(t) => window.autohaptics.clientXOf(t)", t1), row_y(r, last_row), steps=5)
    pg.mouse.up()


def vibration_column(pg, actuator: int) -> list[float]:
    return pg.evaluate(
        """(a) => { const s = window.autohaptics.state(); const out = [];
            for (let k = 0; k < s.nTicks; k++) out.push(window.autohaptics.valuesAt(k).vibration[a]);
            return out; }""",
        actuator)


def test_threshold_drag_previews_live_then_rederives_the_vibration(page, api, project_copy):
    pid = project_copy["id"]
    open_editor(page, pid)
    s0 = state(page)
    thr0 = s0["thresholds"]["loudness"]
    vib_before = settled_lane_pixels(page, "actuators")
    feat_before = settled_lane_pixels(page, "feature-loudness")
    r = lane_rect(page, "feature-loudness")
    x = r["x"] + r["width"] * 0.3
    page.mouse.move(x, threshold_y(r, thr0))
    page.mouse.down()
    page.mouse.move(x, threshold_y(r, 0.4), steps=6)
    # While dragging: the feature lane redraws around the moving line, the slider follows, and
    # nothing is saved or re-derived yet.
    page.wait_for_function("() => document.querySelector('[data-testid=threshold-loudness]').value === '0.4'")
    assert lane_pixels(page, "feature-loudness")["hash"] != feat_before["hash"]
    assert lane_pixels(page, "actuators") == vib_before
    assert api.get(f"/api/projects/{pid}").json()["params"]["thresholds"]["loudness"] == thr0
    screenshot(page, "editor-threshold-drag")
    page.mouse.up()
    s1 = wait_revision_above(page, s0["revision"])
    assert s1["thresholds"]["loudness"] == pytest.approx(0.4)
    assert api.get(f"/api/projects/{pid}").json()["params"]["thresholds"]["loudness"] == pytest.approx(0.4)
    vib_after = lane_pixels(page, "actuators")
    assert vib_after["hash"] != vib_before["hash"]
    assert vib_after["lit"] > vib_before["lit"], "a lower threshold should switch on more vibration"
    # Only the changed curves' pyramids were rebuilt (the temperature, fans and sound features were kept).
    assert 0 < s1["pyramidsBuilt"] < s0["pyramidsBuilt"], (s0["pyramidsBuilt"], s1["pyramidsBuilt"])
    # After the first load (all but the fans, then the fans) only the changed blocks were fetched
    # (since the revision on screen); the kept ones are the server's.
    asked = page.evaluate("() => performance.getEntriesByType('resource').map((e) => e.name)"
                          ".filter((n) => n.includes('timeline.bin'))")
    assert len(asked) > 2 and all("since=" in url for url in asked[2:]), asked
    doc = api.get(f"/api/projects/{pid}/timeline").json()["tracks"]
    for tick in (0, len(doc["vibration"]) // 3, len(doc["vibration"]) - 1):
        held = values_at(page, tick)
        assert held["vibration"] == pytest.approx(doc["vibration"][tick], abs=0.5 / 255 + 1e-4)
        assert held["temperature_c"] == pytest.approx(doc["temperature_c"][tick], abs=1e-3)
        assert held["fan_grid"] == pytest.approx(np.ravel(doc["fans"][tick]).tolist(), abs=0.5 / 255 + 1e-4)


def test_threshold_slider_commits_from_the_keyboard(page, api, project_copy):
    pid = project_copy["id"]
    open_editor(page, pid)
    s0 = state(page)
    page.focus("[data-testid=threshold-booming]")
    page.keyboard.press("ArrowLeft")  # one step: 0.65 -> 0.64, a `change` event
    s1 = wait_revision_above(page, s0["revision"])
    assert s1["thresholds"]["booming"] == pytest.approx(0.64)
    assert api.get(f"/api/projects/{pid}").json()["params"]["thresholds"]["booming"] == pytest.approx(0.64)


def test_edit_undo_redo_reload_and_regenerate_keep_the_edit(page, api, project_copy):
    pid = project_copy["id"]
    open_editor(page, pid)
    s0 = state(page)
    original = values_at(page, 40)
    r = lane_rect(page, "actuators")
    x40 = page.evaluate("() => window.autohaptics.clientXOf(4.05)")
    pixel_before = pixel(page, "actuators", x40, row_y(r, 0))
    select_rows(page, 2.0, 6.0, 0, 1)  # A1..A2, ticks 20..60
    sel = state(page)["selection"]
    assert sel["lanes"] == ["A1", "A2"]
    assert sel["t0"] == 20 and sel["t1"] == 61
    assert page.get_attribute("[data-testid=lane-chip-A1]", "aria-pressed") == "true"
    assert page.get_attribute("[data-testid=lane-chip-A3]", "aria-pressed") == "false"
    page.fill("[data-testid=edit-value]", "1")
    page.click("[data-testid=edit-set]")
    s1 = wait_revision_above(page, s0["revision"])
    assert s1["cursor"] == 1
    assert page.text_content("[data-testid=save-state]") == "All changes saved"
    v = values_at(page, 40)
    assert v["vibration"][:2] == [1.0, 1.0]
    assert v["vibration"][2:] == original["vibration"][2:]
    page.keyboard.press("Escape")  # drop the selection so its tint does not cover the cell
    next_frame(page)
    assert state(page)["selection"] is None
    assert pixel(page, "actuators", x40, row_y(r, 0)) == FULL
    screenshot(page, "editor-after-set")

    page.click("[data-testid=undo]")
    s2 = wait_revision_above(page, s1["revision"])
    assert s2["cursor"] == 0
    assert values_at(page, 40)["vibration"] == original["vibration"]
    assert pixel(page, "actuators", x40, row_y(r, 0)) == pixel_before
    assert page.is_enabled("[data-testid=redo]")

    page.locator("[data-testid=timeline]").focus()
    page.keyboard.press("Control+Shift+Z")
    s3 = wait_revision_above(page, s2["revision"])
    assert s3["cursor"] == 1
    assert values_at(page, 40)["vibration"][:2] == [1.0, 1.0]

    page.reload()
    open_editor(page, pid)
    assert values_at(page, 40)["vibration"][:2] == [1.0, 1.0]
    assert state(page)["cursor"] == 1 and page.is_enabled("[data-testid=undo]")

    a5_before = vibration_column(page, 4)
    page.click("[data-testid=regenerate]")
    page.wait_for_selector("[data-testid=regenerate-dialog]")
    page.fill("[data-testid=regen-threshold-loudness]", "0.5")
    screenshot(page, "editor-regenerate-dialog")
    s4 = state(page)
    page.click("[data-testid=regen-start]")
    page.wait_for_function(
        "() => { const el = document.querySelector('[data-testid=job-slot] [data-testid=generation-progress]');"
        " return el && el.getAttribute('aria-valuenow') === '100'; }",
        timeout=90_000)
    s5 = wait_revision_above(page, s4["revision"])
    assert s5["thresholds"]["loudness"] == pytest.approx(0.5)
    assert s5["cursor"] == 2, "the regeneration is one more step of the history, on top of the edit"
    params = api.get(f"/api/projects/{pid}").json()["params"]
    assert params["thresholds"]["loudness"] == pytest.approx(0.5)
    assert values_at(page, 40)["vibration"][:2] == [1.0, 1.0], "the manual edit must survive regeneration"
    assert vibration_column(page, 4) != a5_before, "the new threshold must change the generated vibration"


def test_export_json_and_csv_downloads_are_valid(page, project_copy, tmp_path):
    pid = project_copy["id"]
    open_editor(page, pid)
    s0 = state(page)
    select_rows(page, 1.0, 2.0, 4, 4)  # A5, ticks 10..20
    page.fill("[data-testid=edit-value]", "0.25")
    page.click("[data-testid=edit-set]")
    wait_revision_above(page, s0["revision"])
    n = state(page)["nTicks"]

    page.click("[data-testid=export-menu] summary")
    formats = page.eval_on_selector_all("[data-testid=export-menu] a", "els => els.map(e => e.dataset.testid)")
    assert {"export-json", "export-csv"} <= set(formats)
    screenshot(page, "editor-export-menu")
    with page.expect_download() as dl:
        page.click("[data-testid=export-json]")
    json_path = tmp_path / dl.value.suggested_filename
    dl.value.save_as(json_path)
    assert json_path.suffix == ".json"
    tl = Timeline.load(json_path)
    assert tl.n_ticks == n
    assert tl.vibration[10:21, 4].tolist() == pytest.approx([0.25] * 11)
    doc = json.loads(json_path.read_text())
    assert doc["edits"][-1]["op"] == "set"

    page.click("[data-testid=export-menu] summary")
    with page.expect_download() as dl:
        page.click("[data-testid=export-csv]")
    csv_path = tmp_path / dl.value.suggested_filename
    dl.value.save_as(csv_path)
    rows = list(csv.reader(csv_path.open(newline="")))
    assert len(rows) == n + 1
    assert rows[0][:11] == ["time_s", "A1", "A2", "A3", "A4", "A5", "A6", "A7", "A8", "A9", "temperature_c"]
    assert len(rows[0]) == 11 + 9 * 17
    assert all(len(row) == len(rows[0]) for row in rows)
    assert float(rows[1 + 15][5]) == pytest.approx(0.25)


def test_a_concurrent_edit_is_reported_and_reloaded(page, api, project_copy):
    pid = project_copy["id"]
    open_editor(page, pid)
    s0 = state(page)
    # Someone else (another tab) sets A9 at ticks 100..110 behind the editor's back.
    r = api.post(f"/api/projects/{pid}/edits", json={
        "base_revision": s0["revision"], "op": {"op": "set", "lanes": ["A9"], "t0": 100, "t1": 110, "value": 0.75}})
    assert r.status_code == 200, r.text
    select_rows(page, 2.0, 3.0, 0, 0)
    page.fill("[data-testid=edit-value]", "0.5")
    page.click("[data-testid=edit-set]")
    page.wait_for_selector("[data-testid=toast-warn]")
    assert "reloaded" in page.text_content("[data-testid=toast-warn]")
    s1 = wait_revision_above(page, s0["revision"])
    assert s1["revision"] == r.json()["revision"]
    assert values_at(page, 105)["vibration"][8] == pytest.approx(0.75, abs=1 / 255)
    assert values_at(page, 25)["vibration"][0] != 0.5, "the refused edit must not show as applied"
    assert api.get(f"/api/projects/{pid}/edits").json()["cursor"] == 1


def test_main_screen_screenshot(page, project_copy):
    """The README screenshot: the editor at a strong moment, the fan grid on, a selection made."""
    open_editor(page, project_copy["id"])
    page.wait_for_function("() => window.autohaptics.state().waveformReady")
    page.click("[data-testid=toggle-fan-overlay]")
    assert page.get_attribute("[data-testid=toggle-fan-overlay]", "aria-pressed") == "true"
    assert page.is_visible("[data-testid=fan-overlay]")
    a1 = vibration_column(page, 0)
    tick = max(range(200, 350), key=lambda k: a1[k])
    page.evaluate("(t) => { document.querySelector('[data-testid=video]').currentTime = t; }", tick * 0.1 + 0.05)
    page.wait_for_function(f"() => Math.abs(window.autohaptics.state().playheadS - {tick * 0.1 + 0.05}) < 0.01")
    page.wait_for_function("() => document.querySelector('[data-testid=video]').readyState >= 2")
    assert float(page.get_attribute("[data-testid=chair-A1]", "data-value")) == pytest.approx(a1[tick], abs=1e-3)
    select_rows(page, 30.0, 34.0, 0, 4)
    copy_to_docs(screenshot(page, "editor"), "editor.png")


def test_import_a_timeline_file_and_undo_it(page, api, project_copy, tmp_path):
    pid = project_copy["id"]
    doc = api.get(f"/api/projects/{pid}/timeline").json()
    tl = Timeline.from_dict(doc)
    tl.vibration[:, 8] = 0.5  # A9
    tl.extra = {}
    path = tl.save(tmp_path / "designed.timeline.json")
    open_editor(page, pid)
    before = values_at(page, 100)["vibration"][8]
    assert abs(before - 0.5) > 0.1
    s0 = state(page)
    page.set_input_files("[data-testid=import-input]", str(path))
    s1 = wait_revision_above(page, s0["revision"])
    assert s1["cursor"] == 1
    assert [values_at(page, k)["vibration"][8] for k in (0, 100, s1["nTicks"] - 1)] == pytest.approx([0.5] * 3, abs=1 / 255)
    assert "Imported designed.timeline.json" in page.text_content("[data-testid=toast-info]")
    page.click("[data-testid=undo]")
    wait_revision_above(page, s1["revision"])
    assert values_at(page, 100)["vibration"][8] == before


def test_importing_a_broken_file_says_why(page, project_copy, tmp_path):
    bad = tmp_path / "broken.csv"
    bad.write_text("time_s,A1\n0.0,not-a-number\n")
    open_editor(page, project_copy["id"])
    page.set_input_files("[data-testid=import-input]", str(bad))
    page.wait_for_selector("[data-testid=toast-error]")
    assert page.text_content("[data-testid=toast-error]").startswith("Not saved: ")
    assert page.get_attribute("[data-testid=save-state]", "data-state") == "error"
    assert state(page)["cursor"] == 0


def test_the_fan_grid_lies_on_the_picture_the_analysis_read(page, api, tmp_path):
    """A 2.4:1 film letterboxed in 16:9: the fans are the active picture's, so the overlay's grid covers it
    and not the black bars (the timeline's header says where: ``picture``); it covered the whole frame."""
    from autohaptics import testing as synth
    from autohaptics.testing.reencode import reencode
    from autohaptics.testing.scenes import material_scene

    wide = synth.write_scene(tmp_path / "wide.mp4", material_scene(4.0), width=320, height=132, fps=25)
    film = reencode(wide, tmp_path / "letterboxed.mp4", width=320, height=180, fit="pad")
    project = upload(api, film, name="letterboxed")
    try:
        head = api.get(f"/api/projects/{project['id']}/timeline.bin?blocks=vibration").content
        header = json.loads(head[12:12 + int.from_bytes(head[8:12], "little")])
        box = header["picture"]
        assert box["x"] == 0 and box["w"] == 1 and 0.1 < box["y"] < 0.15 and box["y"] + box["h"] < 0.9
        open_editor(page, project["id"])
        page.click("[data-testid=toggle-fan-overlay]")
        page.wait_for_function("() => document.querySelector('[data-testid=video]').videoWidth > 0")
        next_frame(page)
        rows = page.evaluate("""() => {
            const c = document.querySelector('[data-testid=fan-overlay]');
            const v = document.querySelector('[data-testid=video]');
            const k = c.width / c.getBoundingClientRect().width;
            const s = Math.min(v.clientWidth / v.videoWidth, v.clientHeight / v.videoHeight);
            const top = (v.clientHeight - v.videoHeight * s) / 2, ph = v.videoHeight * s;
            const lit = (y) => { const d = c.getContext('2d').getImageData(0, Math.floor(y * k), c.width, 1).data;
                                 let n = 0; for (let i = 3; i < d.length; i += 4) n += d[i] > 0; return n; };
            return {bar: lit(top + 0.05 * ph), picture: lit(top + 0.5 * ph), low_bar: lit(top + 0.95 * ph)};
        }""")
        assert rows["picture"] > 0 and rows["bar"] == 0 and rows["low_bar"] == 0, rows
    finally:
        api.delete(f"/api/projects/{project['id']}")
