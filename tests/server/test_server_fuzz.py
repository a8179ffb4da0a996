"""Every JSON route's body, fuzzed (hypothesis, bounded, derandomised so CI sees the same 2,100
requests): arbitrary JSON (huge integers, NaN, Infinity, deep nesting, wrong types) and bodies
shaped like the route's schema with arbitrary values (edit ops by their real names and fields,
parameter overrides by their real dotted names, style files by their real fields). No response is a 500; every refusal is a 4xx
with one line of ``detail`` that names no server path."""

from __future__ import annotations

import json
import time
from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings, strategies as st

from autohaptics.params import GenerateParams
from autohaptics.records import params_to_dict
from autohaptics.server.app import create_app
from autohaptics.server.settings import Settings
from autohaptics.testing import Scene, Segment, Tone, write_scene
from autohaptics.timeline.edit_ops import REQUIRED

from service_client import LocalClient

EXAMPLES = 2100
TERMINAL = ("done", "failed", "cancelled")
SENT: list[int] = []  # responses of the fuzz test, counted by the test after it


def _dotted(doc: dict, prefix: str = "") -> list[str]:
    out = []
    for key, value in doc.items():
        out += _dotted(value, f"{prefix}{key}.") if isinstance(value, dict) else [f"{prefix}{key}"]
    return out


PARAM_NAMES = sorted(_dotted(params_to_dict(GenerateParams())))
GROUPS = sorted(k for k, v in params_to_dict(GenerateParams()).items() if isinstance(v, dict))
scalars = (st.none() | st.booleans() | st.integers(min_value=-10**450, max_value=10**450)
           | st.integers(min_value=-5, max_value=400) | st.floats() | st.text(max_size=12)
           | st.sampled_from(["A1", "fans", "temperature_c", "play", "balanced", "audio", "", "0" * 4400]))
values = st.recursive(scalars, lambda inner: st.lists(inner, max_size=5)
                      | st.dictionaries(st.text(max_size=8), inner, max_size=4), max_leaves=16)


def shaped(fields: dict) -> st.SearchStrategy:
    """Objects with some of ``fields`` (name -> strategy) and now and then an unknown one."""
    return st.fixed_dictionaries({}, optional={**fields, "extra": values})


def op_bodies() -> st.SearchStrategy:
    ops = [shaped({"op": st.just(name), **{f: values for f in fields}}) for name, fields in REQUIRED.items()]
    return st.one_of(*ops, values)


def routes(pid: str) -> list[tuple[str, str, st.SearchStrategy]]:
    revision = st.integers(min_value=-2, max_value=12) | values
    params = shaped({"preset": values | st.sampled_from(["fast", "balanced", "x"]),
                     "mode": values | st.sampled_from(["audio", "random", "x"]),
                     "thresholds": st.dictionaries(st.sampled_from(["loudness", "sharpness", "x"]), values) | values,
                     "overrides": st.dictionaries(st.sampled_from(PARAM_NAMES + GROUPS + ["x.y"]), values) | values,
                     "style": values})
    curve = st.lists(st.floats(min_value=-0.5, max_value=1.5) | values, max_size=13) | values
    style_file = values | shaped({"format": st.just("autohaptics.style") | values, "version": st.just(1) | values,
                                  "name": values, "threshold_scale": values, "knots": curve,
                                  "vibration": st.dictionaries(st.sampled_from(["A1", "A9", "x"]), curve) | values,
                                  "fans": curve, "temperature": shaped({"scale": values, "offset_c": values}) | values,
                                  "overrides": st.dictionaries(st.sampled_from(PARAM_NAMES + ["x.y"]), values) | values,
                                  "learned": values})
    return [
        ("PATCH", f"/api/projects/{pid}", shaped({"name": values, "view": values})),
        ("PUT", f"/api/projects/{pid}/params", params),
        ("POST", f"/api/projects/{pid}/generate", params),
        ("POST", f"/api/projects/{pid}/edits", shaped({"base_revision": revision, "op": op_bodies()})),
        ("POST", f"/api/projects/{pid}/undo", shaped({"base_revision": revision})),
        ("POST", f"/api/projects/{pid}/redo", shaped({"base_revision": revision})),
        ("POST", "/api/chair/connect", shaped({"port": values})),
        ("POST", "/api/chair/playback", shaped({"project_id": st.just(pid) | values, "state": values
                                                | st.sampled_from(["play", "pause", "seek"]),
                                                "position_s": values, "heartbeat": values})),
        ("POST", "/api/chair/push", shaped({"project_id": st.just(pid) | values, "start_s": values, "end_s": values})),
        ("PUT", "/api/chair/settings", shaped({"latency_ms": values, "comfort": shaped({
            "scale": values, "mute": shaped({z: values for z in ("back", "seat", "heat", "fans")}) | values})})),
        ("POST", "/api/styles", shaped({"name": values, "project_ids": st.lists(st.just(pid) | values, max_size=3)
                                        | values, "dry_run": st.just(True) | values})),
        ("IMPORT", "/api/styles/import", style_file),
        ("IMPORT", f"/api/projects/{pid}/import", values | shaped({"format": st.just("autohaptics.timeline"),
                                                                   "version": values, "n_ticks": values,
                                                                   "vibration": values})),
    ]


@pytest.fixture(scope="module")
def client(tmp_path_factory):
    root = tmp_path_factory.mktemp("server-fuzz")
    with LocalClient(create_app(Settings(data_dir=root / "data", frontend_dir=None)),
                     raise_server_exceptions=False) as c:
        c.root = root
        yield c


@pytest.fixture(scope="module")
def pid(client) -> str:
    scene = Scene(duration_s=2.0, background=(Segment(0.0, 2.0, (40, 160, 60)),),
                  audio=(Tone(0.2, 1.5, 80.0, level_dbfs=-12.0),), name="fuzz")
    film = write_scene(Path(client.root) / "film.mp4", scene, width=48, height=28, fps=5, quality="low",
                       sample_rate=24000)
    r = client.post("/api/projects", files={"file": ("film.mp4", film.read_bytes(), "video/mp4")},
                    data={"mode": "audio"})
    assert r.status_code == 201, r.text
    deadline = time.monotonic() + 120
    while client.get(f"/api/jobs/{r.json()['job']['id']}").json()["status"] not in TERMINAL:
        assert time.monotonic() < deadline
        time.sleep(0.2)
    return r.json()["id"]


def send(client, method: str, path: str, body) -> object:
    text = json.dumps(body)  # Python writes NaN / Infinity, as a careless client would
    if method == "IMPORT":
        return client.post(path, files={"file": ("fuzz.json", text.encode(), "application/json")})
    return client.request(method, path, content=text.encode(), headers={"content-type": "application/json"})


@settings(max_examples=EXAMPLES, deadline=None, derandomize=True, database=None,
          suppress_health_check=list(HealthCheck))
@given(data=st.data())
def test_no_json_body_gets_a_500(client, pid, data):
    method, path, body = data.draw(st.sampled_from(routes(pid)).flatmap(
        lambda r: st.tuples(st.just(r[0]), st.just(r[1]), r[2])), label="request")
    r = send(client, method, path, body)
    SENT.append(r.status_code)
    assert r.status_code < 500, (method, path, r.status_code, r.text[:300])
    if r.status_code >= 400:
        detail = r.json()["detail"]
        assert isinstance(detail, str) and detail and "\n" not in detail, detail
        assert str(client.root) not in detail, detail


def test_the_fuzz_sent_at_least_2000_requests():
    assert len(SENT) >= 2000, len(SENT)
    assert max(SENT) < 500
