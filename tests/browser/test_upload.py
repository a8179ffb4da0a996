"""Projects screen: upload with progress, generation with progress, open; rename, duplicate, delete."""

from __future__ import annotations

import pytest

from browser_support import media_clip, screenshot, state, upload, wait_job

pytestmark = pytest.mark.browser


def test_upload_shows_upload_and_generation_progress_then_opens(page, api):
    clip = media_clip("bbb_1s_1280x720_vp8_vorbis.webm")
    page.goto("/")
    page.wait_for_selector("[data-testid=projects-page]")
    screenshot(page, "projects-empty-or-list")
    # Progress values as the user sees them (aria-valuenow), recorded from the first change on.
    page.evaluate("""() => {
        window.__seen = {upload: [], generation: []};
        const watch = (testid, key) => new MutationObserver(() => {
            const el = document.querySelector(`[data-testid=upload-box] [data-testid=${testid}]`);
            if (el) window.__seen[key].push(Number(el.getAttribute('aria-valuenow')));
        }).observe(document.body, {subtree: true, attributes: true, attributeFilter: ['aria-valuenow'], childList: true});
        watch('upload-progress', 'upload');
        watch('generation-progress', 'generation');
    }""")
    page.set_input_files("[data-testid=file-input]", str(clip))
    box = page.locator("[data-testid=upload-box]")
    page.wait_for_function(
        "() => document.querySelector('[data-testid=upload-box] [data-testid=upload-progress]')"
        ".getAttribute('aria-valuenow') === '100'")
    page.wait_for_function(
        "() => { const el = document.querySelector('[data-testid=upload-box] [data-testid=generation-progress]');"
        " return el && el.getAttribute('aria-valuenow') === '100'; }", timeout=90_000)
    page.wait_for_function(
        "() => document.querySelector('[data-testid=upload-status]').textContent.startsWith('Ready')")
    row = page.locator("[data-testid=project-row]", has_text=clip.stem)
    page.wait_for_function(
        "(name) => [...document.querySelectorAll('[data-testid=project-row]')]"
        ".some((r) => r.textContent.includes(name) && r.dataset.status === 'ready')", arg=clip.stem)
    screenshot(page, "projects-upload-done")
    seen = page.evaluate("() => window.__seen")
    assert seen["upload"] and seen["upload"][-1] == 100
    assert seen["generation"] and max(seen["generation"]) == 100
    assert seen["generation"] == sorted(seen["generation"]), "generation progress went backwards"

    assert row.get_attribute("data-status") == "ready"
    assert box.locator("[data-testid=upload-cancel]").is_hidden()
    project_id = row.get_attribute("data-id")
    box.locator("[data-testid=open-uploaded]").click()
    page.wait_for_selector("#app[data-ready='true']")
    s = state(page)
    assert s["projectId"] == project_id
    assert s["nTicks"] == api.get(f"/api/projects/{project_id}").json()["n_ticks"]
    page.wait_for_function("() => document.querySelector('[data-testid=video]').readyState >= 1")


def test_rejected_upload_shows_the_servers_reason(page, tmp_path):
    bogus = tmp_path / "notes.mp4"
    bogus.write_text("this is not a video\n" * 50)
    page.goto("/")
    page.set_input_files("[data-testid=file-input]", str(bogus))
    status = page.locator("[data-testid=upload-status]")
    page.wait_for_function("() => document.querySelector('[data-testid=upload-status]').classList.contains('error')")
    assert "not a readable media file" in status.text_content()
    assert page.locator("[data-testid=project-row]", has_text="notes").count() == 0


def test_rename_duplicate_and_delete_with_confirmation(page, api):
    project = upload(api, media_clip("bbb_1s_1280x720_vp8_vorbis.webm"), name="list-ops", generate=False)
    pid = project["id"]
    page.goto("/")
    row = page.locator(f"[data-testid=project-row][data-id='{pid}']")
    row.wait_for()

    row.locator("[data-testid=project-rename]").click()
    page.fill("[data-testid=dialog-input]", "renamed clip")
    page.click("[data-testid=dialog-ok]")
    page.wait_for_function(
        f"() => document.querySelector(\"[data-id='{pid}'] [data-testid=project-open]\").textContent === 'renamed clip'")
    assert api.get(f"/api/projects/{pid}").json()["name"] == "renamed clip"

    before = {p["id"] for p in api.get("/api/projects").json()}
    row.locator("[data-testid=project-duplicate]").click()
    page.locator("[data-testid=project-row]", has_text="renamed clip (copy)").wait_for()
    copies = [p for p in api.get("/api/projects").json() if p["id"] not in before]
    assert [c["name"] for c in copies] == ["renamed clip (copy)"]

    row.locator("[data-testid=project-delete]").click()
    screenshot(page, "projects-delete-confirmation")
    page.click("[data-testid=dialog-cancel]")
    assert api.get(f"/api/projects/{pid}").status_code == 200
    assert row.count() == 1

    row.locator("[data-testid=project-delete]").click()
    page.click("[data-testid=dialog-ok]")
    row.wait_for(state="detached")
    assert api.get(f"/api/projects/{pid}").status_code == 404
    api.delete(f"/api/projects/{copies[0]['id']}")


def test_open_unknown_project_says_so(page):
    page.goto("/#/project/" + "0" * 32)
    assert "does not exist" in page.locator("[data-testid=editor-error]").text_content()


def test_cancel_a_queued_generation(page, api, project_copy):
    # One job runs at a time: keep the worker busy with another project so the upload's job waits
    # in the queue, where cancelling it is certain to take effect.
    busy = api.post(f"/api/projects/{project_copy['id']}/generate", json={}).json()["job"]
    clip = media_clip("bbb_1s_1280x720_vp8_vorbis.webm")
    page.goto("/")
    page.set_input_files("[data-testid=file-input]", str(clip))
    cancel = page.locator("[data-testid=upload-box] [data-testid=generation-cancel]")
    cancel.wait_for()
    page.wait_for_function("() => { const b = document.querySelector('[data-testid=upload-box] [data-testid=generation-cancel]');"
                           " return b && !b.disabled; }")
    cancel.click()
    page.wait_for_function(
        "() => /^(Generation (cancelled|failed)|Ready)/.test(document.querySelector('[data-testid=upload-status]').textContent)")
    assert page.text_content("[data-testid=upload-status]") == "Generation cancelled."
    pid = page.get_attribute("[data-testid=open-uploaded]", "href").rsplit("/", 1)[-1]
    page.wait_for_function(f"() => document.querySelector(\"[data-id='{pid}']\").dataset.status === 'cancelled'")
    project = api.get(f"/api/projects/{pid}").json()
    assert project["job"]["status"] == "cancelled" and not project["has_timeline"]
    assert wait_job(api, busy["id"])["status"] == "done"
    api.delete(f"/api/projects/{project['id']}")


def test_a_project_without_a_timeline_is_generated_from_the_editor(page, api):
    project = upload(api, media_clip("bbb_1s_1280x720_vp8_vorbis.webm"), name="not yet generated", generate=False)
    page.goto(f"/#/project/{project['id']}")
    notice = page.locator("[data-testid=editor-notice]")
    notice.wait_for()
    assert "no timeline yet" in notice.text_content()
    assert state(page)["ready"] is False
    assert page.is_disabled("[data-testid=edit-set]")
    page.click("[data-testid=regenerate]")
    page.fill("[data-testid=regen-threshold-loudness]", "0.6")
    page.click("[data-testid=regen-start]")
    page.wait_for_selector("#app[data-ready='true']", timeout=90_000)
    s = state(page)
    assert s["ready"] is True and s["nTicks"] == project["n_ticks"]
    assert notice.is_hidden()
    assert api.get(f"/api/projects/{project['id']}").json()["params"]["thresholds"]["loudness"] == 0.6
    api.delete(f"/api/projects/{project['id']}")


def test_drag_and_drop_upload(page, api):
    clip = media_clip("bbb_1s_1280x720_vp8_vorbis.webm")
    page.goto("/")
    page.wait_for_selector("[data-testid=dropzone]")
    data = list(clip.read_bytes())
    transfer = page.evaluate_handle(
        """([bytes, name]) => {
            const dt = new DataTransfer();
            dt.items.add(new File([new Uint8Array(bytes)], name, {type: 'video/webm'}));
            return dt;
        }""",
        [data, "dropped clip.webm"])
    page.dispatch_event("[data-testid=dropzone]", "dragover", {"dataTransfer": transfer})
    assert "dragging" in page.get_attribute("[data-testid=dropzone]", "class")
    page.dispatch_event("[data-testid=dropzone]", "drop", {"dataTransfer": transfer})
    page.wait_for_function(
        "() => document.querySelector('[data-testid=upload-status]').textContent.startsWith('Ready')", timeout=90_000)
    assert "dragging" not in page.get_attribute("[data-testid=dropzone]", "class")
    pid = page.get_attribute("[data-testid=open-uploaded]", "href").rsplit("/", 1)[-1]
    project = api.get(f"/api/projects/{pid}").json()
    assert project["name"] == "dropped clip" and project["status"] == "ready"
    api.delete(f"/api/projects/{pid}")


PROGRESS_PAIRS = """() => {
    // Every figure either bar shows while the uploaded project's job runs, read together:
    // [the upload box's, the project row's] (aria-valuenow and the figure of the text).
    window.__pairs = [];
    const figure = (bar) => [bar.getAttribute('aria-valuenow'), bar.textContent.split(' %')[0]];
    new MutationObserver(() => {
        const link = document.querySelector('[data-testid=open-uploaded]');
        const id = link && link.getAttribute('href') && link.getAttribute('href').split('/').pop();
        const box = document.querySelector('[data-testid=upload-box] [data-testid=generation-progress]');
        const row = id && document.querySelector(`[data-testid=project-row][data-id='${id}'] [data-testid=row-progress]`);
        if (box && row) window.__pairs.push([figure(box), figure(row)]);
    }).observe(document.body, {subtree: true, childList: true, characterData: true, attributes: true,
                               attributeFilter: ['aria-valuenow']});
}"""


def test_the_project_row_shows_the_upload_boxs_progress_figure(page, api):
    clip = media_clip("bbb_opening_30s_1280x720_vp8_vorbis.webm")  # long enough for several figures
    page.goto("/")
    page.wait_for_selector("[data-testid=projects-page]")
    page.evaluate(PROGRESS_PAIRS)
    page.set_input_files("[data-testid=file-input]", str(clip))
    page.wait_for_function(
        "() => document.querySelector('[data-testid=upload-status]').textContent.startsWith('Ready')", timeout=120_000)
    pid = page.get_attribute("[data-testid=open-uploaded]", "href").rsplit("/", 1)[-1]
    pairs = page.evaluate("() => window.__pairs")
    running = [box for box, _ in pairs if 0 < int(box[0]) < 100]
    assert len({b[0] for b in running}) >= 2, f"too few figures while the job ran: {pairs}"
    assert all(box == row for box, row in pairs), [p for p in pairs if p[0] != p[1]]
    assert all(box[0] == box[1] for box, _ in pairs)
    api.delete(f"/api/projects/{pid}")
