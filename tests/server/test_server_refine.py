"""Threshold commits through the API on a generated film with known answers: raising or lowering a
threshold starts no work (the analysis has the saliency of every tick the sliders could wake);
lowering the loudness gate below the analysed one starts a refinement (saliency of the newly
vibrating ticks only) whose timeline equals a fresh generate, and a restart in the middle of one
leaves the project usable with its parameters.

The film (64 x 36, 5 fps, 14 s): a loud boom at 3-4 s with a bright disc on the LEFT, a quiet hum
at 9-11 s with a bright square on the RIGHT.
"""

from __future__ import annotations

import time

import numpy as np
import pytest

from autohaptics import pipeline
from autohaptics import testing as synth
from autohaptics.params import params_from_doc, resolve_doc
from autohaptics.server.app import create_app
from autohaptics.server.settings import Settings

from service_client import LocalClient

HIGH = {"sharpness": 0.95, "booming": 0.95, "low_energy": 0.95, "loudness": 0.95}
LOW = {"sharpness": 0.3, "booming": 0.3, "low_energy": 0.3, "loudness": 0.3}
SCENE = synth.left_boom_right_hum_scene()
THESIS = {"intensity.rule": "thesis"}
GATED = THESIS | {"intensity.loudness_gate": 0.6}  # the boom passes it, the hum does not


@pytest.fixture(scope="module")
def film(tmp_path_factory):
    return synth.write_scene(tmp_path_factory.mktemp("refine") / "film.mp4", SCENE, width=64, height=36, fps=5)


def wait_done(client: LocalClient, job_id: str) -> dict:
    with client.stream("GET", f"/api/jobs/{job_id}/events") as resp:
        stages = [line for line in resp.iter_lines() if line.startswith("data: ")]
    job = client.get(f"/api/jobs/{job_id}").json()
    assert job["status"] == "done", (job, stages[-3:])
    return job


def thesis_project(client: LocalClient, film) -> tuple[str, str]:
    """Upload ``film`` and generate it with the thesis's intensity rule, which the scene's known
    answer is defined by (under the "events" rule both of its sounds are events at any threshold).
    Returns (project id, job id)."""
    r = client.post("/api/projects", files={"file": ("film.mp4", film.read_bytes(), "video/mp4")},
                    data={"mode": "multimodal", "generate": "false"})
    assert r.status_code == 201, r.text
    pid = r.json()["id"]
    r = client.post(f"/api/projects/{pid}/generate", json={"overrides": GATED})
    assert r.status_code == 202, r.text
    return pid, r.json()["job"]["id"]


def vibration(client: LocalClient, pid: str) -> np.ndarray:
    return np.asarray(client.get(f"/api/projects/{pid}/timeline").json()["tracks"]["vibration"], dtype=float)


def test_threshold_commits_refine_only_what_they_wake(tmp_path, film):
    settings = Settings(data_dir=tmp_path / "data", frontend_dir=None)
    with LocalClient(create_app(settings)) as client:
        pid, job_id = thesis_project(client, film)
        wait_done(client, job_id)
        # Raising wakes no tick: derived at once, no job.
        r = client.put(f"/api/projects/{pid}/params", json={"thresholds": HIGH})
        assert r.status_code == 200 and r.json()["derived"] and r.json()["job"] is None
        # Lowering them: the weights were computed up front, derived at once, no job.
        r = client.put(f"/api/projects/{pid}/params", json={"thresholds": LOW})
        assert r.status_code == 200 and r.json()["derived"] and r.json()["job"] is None
        # Lowering the gate wakes the hum: derived at once with estimated weights, and a refinement starts.
        r = client.put(f"/api/projects/{pid}/params", json={"thresholds": LOW, "overrides": THESIS})
        assert r.status_code == 200 and r.json()["derived"] and r.json()["job"] is not None
        job = wait_done(client, r.json()["job"]["id"])
        assert job["params"]["thresholds"] == LOW and job["stage"] in ("saliency", "done")
        refined = vibration(client, pid)
        stored = client.get(f"/api/projects/{pid}").json()
        assert stored["status"] == "ready" and stored["params"]["thresholds"] == LOW
        # The same timeline as a fresh generate at the lowered thresholds.
        params, _ = params_from_doc(resolve_doc(stored["params"])[0])
        fresh = pipeline.generate(film, params)
        np.testing.assert_allclose(refined, fresh.vibration, rtol=0, atol=5.1e-5)  # the document has 4 decimals
        assert refined[91:109].max() > 0  # the hum vibrates
        # Committing the same thresholds again wakes nothing new: no job.
        r = client.put(f"/api/projects/{pid}/params", json={"thresholds": dict(LOW, loudness=0.31)})
        assert r.status_code == 200 and r.json()["job"] is None


def test_a_restart_during_a_refinement_keeps_the_project_usable(tmp_path, film):
    settings = Settings(data_dir=tmp_path / "data", frontend_dir=None)
    with LocalClient(create_app(settings)) as client:
        pid, job_id = thesis_project(client, film)
        wait_done(client, job_id)
        assert client.put(f"/api/projects/{pid}/params", json={"thresholds": HIGH}).json()["job"] is None
        r = client.put(f"/api/projects/{pid}/params", json={"thresholds": LOW, "overrides": THESIS})
        job_id = r.json()["job"]["id"]
    # Stopped whatever the job had done: the next start runs it again and nothing shows as failed.
    with LocalClient(create_app(settings)) as client:
        p = client.get(f"/api/projects/{pid}").json()
        assert p["status"] != "failed" and p["has_timeline"] and p["params"]["thresholds"] == LOW
        job = client.get(f"/api/jobs/{job_id}").json()
        if job["status"] != "done":  # it had not finished before the stop: resumed
            wait_done(client, job_id)
        assert client.get(f"/api/projects/{pid}").json()["status"] == "ready"
        doc = client.get(f"/api/projects/{pid}/timeline").json()
        assert doc["generator"]["params"]["thresholds"] == LOW
        assert client.put(f"/api/projects/{pid}/params", json={"thresholds": LOW, "overrides": THESIS}).json()["job"] is None


def test_a_finished_job_leaves_the_project_warm(tmp_path, film, monkeypatch):
    """After a generate and after a regeneration the server loads the project's feature cache (and
    derives from it) in the background, once each, so the first threshold commit loads nothing."""
    loads = []
    real = pipeline.Analysis.load.__func__

    def counted(cls, path):
        loads.append(str(path))
        return real(cls, path)

    monkeypatch.setattr(pipeline.Analysis, "load", classmethod(counted))
    settings = Settings(data_dir=tmp_path / "data", frontend_dir=None)
    with LocalClient(create_app(settings)) as client:
        composer = client.app.state.composer
        pid, job_id = thesis_project(client, film)
        for round_ in range(2):
            wait_done(client, job_id)
            deadline = time.monotonic() + 60
            while not composer.held(pid):
                assert time.monotonic() < deadline, "the project was not loaded after its job"
                time.sleep(0.05)
            assert len(loads) == round_ + 1, loads  # loaded once, by the job's end
            r = client.put(f"/api/projects/{pid}/params", json={"thresholds": HIGH if round_ else LOW})
            assert r.status_code == 200 and r.json()["derived"] and r.json()["job"] is None
            assert client.get(f"/api/projects/{pid}/timeline.bin").status_code == 200
            assert len(loads) == round_ + 1, loads  # the commit did not load the analysis again
            r = client.post(f"/api/projects/{pid}/generate", json={"overrides": THESIS})
            assert r.status_code == 202, r.text
            job_id = r.json()["job"]["id"]
        wait_done(client, job_id)


def test_the_first_commit_after_a_job_derives_from_what_the_job_kept(tmp_path, film, monkeypatch):
    """The job's worker hands over what its derive kept (:mod:`autohaptics.pipeline.handoff`): after
    the job the server computes neither the fan track nor the intensity decision inputs, in the
    warm-up or in the first commit, and the committed timeline, generated and composed, equals a
    derive from the project's feature cache with the derive's tables emptied, bit for bit."""
    import importlib

    from autohaptics.server.composer import derive_timeline

    derive_mod = importlib.import_module("autohaptics.pipeline.derive")  # the package's derive is the function
    calls: list[str] = []
    fans, inputs = derive_mod.fan_track, derive_mod.inten.decision_inputs
    monkeypatch.setattr(derive_mod, "fan_track", lambda *a, **k: calls.append("fan_track") or fans(*a, **k))
    monkeypatch.setattr(derive_mod.inten, "decision_inputs",
                        lambda *a, **k: calls.append("decision_inputs") or inputs(*a, **k))
    settings = Settings(data_dir=tmp_path / "data", frontend_dir=None)
    with LocalClient(create_app(settings)) as client:
        composer = client.app.state.composer
        pid, job_id = thesis_project(client, film)
        wait_done(client, job_id)
        deadline = time.monotonic() + 60
        while not composer.held(pid):
            assert time.monotonic() < deadline, "the project was not loaded after its job"
            time.sleep(0.05)
        r = client.put(f"/api/projects/{pid}/params", json={"thresholds": LOW})
        assert r.status_code == 200 and r.json()["derived"] and r.json()["job"] is None
        assert calls == []
        got, composed = composer.generated(pid), composer.compose(pid).timeline
        project = composer.store.get_project(pid)
        monkeypatch.setattr(derive_mod, "_PICTURE", {})
        monkeypatch.setattr(derive_mod, "_CURVES", {})
        fresh = derive_timeline(pipeline.Analysis.load(composer.store.analysis_path(pid)), project["params"],
                                name=project["name"])
    assert calls == ["decision_inputs", "fan_track"]  # the fresh derive's own
    for tl in (got, composed):
        for track in ("vibration", "temperature_c", "fans"):
            assert np.array_equal(getattr(tl, track), getattr(fresh, track)), track
    assert got.features.keys() == fresh.features.keys()
    for name, values in got.features.items():
        assert values.dtype == fresh.features[name].dtype and np.array_equal(values, fresh.features[name]), name
    assert got.stats["vibration"] == fresh.stats["vibration"] and got.stats.get("airflow") == fresh.stats.get("airflow")


def test_a_commit_during_the_warm_up_shares_its_fan_track(film, monkeypatch):
    """A threshold commit's derive that starts while the warm-up after a job is computing the
    picture's tracks (the fans most of all) waits for them instead of computing them again: two
    derives from one feature cache, the second started while the first is inside the fan track,
    compute it once and give the same timeline."""
    import importlib
    import threading

    from autohaptics.server.composer import derive_timeline

    derive_mod = importlib.import_module("autohaptics.pipeline.derive")  # the package's derive is the function

    analysis = pipeline.analyse(film, params_from_doc(resolve_doc({"preset": "balanced"})[0])[0])
    doc = {"preset": "balanced", "thresholds": HIGH, "overrides": THESIS}
    inside, release, waiting = threading.Event(), threading.Event(), threading.Event()
    calls = []
    real_fans = derive_mod.fan_track

    def fans(*args, **kwargs):
        calls.append(threading.current_thread().name)
        inside.set()
        assert release.wait(60), "the second derive never came to wait"
        return real_fans(*args, **kwargs)

    class Making(dict):
        def get(self, key, default=None):  # a derive that finds the entry being made is about to wait
            found = super().get(key, default)
            if found is not None:
                waiting.set()
            return found

    monkeypatch.setattr(derive_mod, "fan_track", fans)
    monkeypatch.setattr(derive_mod, "_MAKING", Making())
    out = {}

    def run(name: str) -> None:
        out[name] = derive_timeline(analysis, doc, name="film")

    warm = threading.Thread(target=run, args=("warm",), name="warm")
    warm.start()
    assert inside.wait(60)
    commit = threading.Thread(target=run, args=("commit",), name="commit")
    commit.start()
    assert waiting.wait(60), "the commit's derive did not wait for the fan track being made"
    release.set()
    warm.join(60), commit.join(60)
    assert calls == ["warm"]
    np.testing.assert_array_equal(out["warm"].fans, out["commit"].fans)
    np.testing.assert_array_equal(out["warm"].vibration, out["commit"].vibration)
    np.testing.assert_array_equal(out["warm"].temperature_c, out["commit"].temperature_c)
