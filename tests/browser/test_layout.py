"""The chair the editor shows is the one GET /api/config describes: the frontend declares no
actuator, zone or edit lane of its own, and a configuration without the layout is reported."""

from __future__ import annotations

import json

import pytest

from browser_support import open_editor, state

pytestmark = pytest.mark.browser


def serve_config(pg, api, change) -> dict:
    """Answer the page's GET /api/config with the server's configuration, changed by ``change``."""
    config = api.get("/api/config").json()
    change(config)
    body = json.dumps(config)
    pg.route("**/api/config", lambda route: route.fulfill(status=200, content_type="application/json", body=body))
    return config


def test_actuator_ids_and_places_come_from_the_config(page, api, project_copy):
    def rename(config):
        for i, a in enumerate(config["layout"]["actuators"]):
            a["id"] = f"S{i + 1}"
            a["body"] = f"seat point {i + 1}"
        config["lanes"] = [a["id"] for a in config["layout"]["actuators"]] + ["temperature", "fans"]

    config = serve_config(page, api, rename)
    ids = [a["id"] for a in config["layout"]["actuators"]]
    open_editor(page, project_copy["id"])
    chair = page.eval_on_selector_all("[data-testid^=chair-S]", "gs => gs.map((g) => g.dataset.testid)")
    assert chair == [f"chair-{i}" for i in ids]
    assert page.text_content("[data-testid=chair-S3] title").startswith("S3 (seat point 3)")
    assert page.eval_on_selector_all("[data-testid=detail-actuator] option", "os => os.map((o) => o.value)") == ids
    chips = page.eval_on_selector_all("[data-testid^=lane-chip-]", "cs => cs.map((c) => c.dataset.testid)")
    assert chips == [f"lane-chip-{lane}" for lane in config["lanes"]]
    pressed = page.eval_on_selector_all("[data-testid^=lane-chip-][aria-pressed=true]", "cs => cs.map((c) => c.textContent)")
    assert pressed == ids, "a selection made of time alone applies to every actuator"
    rows = page.eval_on_selector_all("[data-testid=lane-actuators] .tl-sublabels span", "ss => ss.map((s) => s.title)")
    assert rows == [f"{i}: seat point {k + 1}" for k, i in enumerate(ids)]
    assert state(page)["ready"]


def test_a_config_without_the_chair_layout_is_reported(page, api):
    serve_config(page, api, lambda config: config.pop("layout"))
    page.goto("/")
    fatal = page.wait_for_selector("[data-testid=fatal]")
    assert 'no usable "layout"' in fatal.text_content()
