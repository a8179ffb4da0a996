"""A derive's kept results handed from a job's worker to the server (:mod:`autohaptics.pipeline.handoff`):
the server's derives from the feature cache as loaded from the job's file then compute neither the
fan track nor the intensity decision inputs, and give the timeline a derive in a fresh process
gives, bit for bit (the "fresh process" is the derive module's tables emptied and the cache
loaded again). A layer that does not hold the kept picture arrays hands over no picture entry.
"""

from __future__ import annotations

import importlib
import pickle

import numpy as np
import pytest

from autohaptics import pipeline
from autohaptics import testing as synth
from autohaptics.params import params_from_doc
from autohaptics.pipeline import handoff
from autohaptics.timeline.npz import load_npz, save_npz

BASE = params_from_doc({})[0]
LOWER = params_from_doc({"thresholds": dict.fromkeys(("sharpness", "booming", "low_energy", "loudness"), 0.2)})[0]
derive_mod = importlib.import_module("autohaptics.pipeline.derive")  # the package's derive is the function


@pytest.fixture(scope="module")
def cache(tmp_path_factory):
    """(the feature cache as the worker holds it, its file, the worker's layer as written)."""
    folder = tmp_path_factory.mktemp("handoff")
    film = synth.write_scene(folder / "film.mp4", synth.left_boom_right_hum_scene(), width=64, height=36, fps=5)
    analysis = pipeline.analyse(film, BASE)
    analysis.save(folder / "analysis.npz")
    return analysis, folder


def fresh_tables(monkeypatch) -> None:
    monkeypatch.setattr(derive_mod, "_PICTURE", {})
    monkeypatch.setattr(derive_mod, "_CURVES", {})


def counted(monkeypatch) -> list[str]:
    calls: list[str] = []
    fans, inputs = derive_mod.fan_track, derive_mod.inten.decision_inputs
    monkeypatch.setattr(derive_mod, "fan_track", lambda *a, **k: calls.append("fan_track") or fans(*a, **k))
    monkeypatch.setattr(derive_mod.inten, "decision_inputs",
                        lambda *a, **k: calls.append("decision_inputs") or inputs(*a, **k))
    return calls


def assert_same(a, b) -> None:
    for track in ("vibration", "temperature_c", "fans"):
        x, y = getattr(a, track), getattr(b, track)
        assert x.dtype == y.dtype and np.array_equal(x, y), track
    assert list(a.features) == list(b.features)
    for name in a.features:
        assert a.features[name].dtype == b.features[name].dtype, name
        assert np.array_equal(a.features[name], b.features[name]), name
    assert {k: v for k, v in a.stats.items() if k != "derive"} == {k: v for k, v in b.stats.items() if k != "derive"}
    assert a.generator == b.generator


def worker_side(cache, monkeypatch, *, touch_fans: bool = False) -> dict:
    """A job's worker: derive from the cache in memory, write the layer, say what was kept (pickled
    as the process pool sends it)."""
    analysis, folder = cache
    fresh_tables(monkeypatch)
    layer = pipeline.derive(analysis, BASE)
    if touch_fans:  # what a style reshaping the fans does to the layer
        layer.fans = layer.fans.copy()
        layer.fans[len(layer.fans) // 2, 0, 0] = 0.5 if layer.fans[len(layer.fans) // 2, 0, 0] != 0.5 else 0.25
    save_npz(layer, folder / "generated.npz")
    return pickle.loads(pickle.dumps(handoff.kept_of(analysis, layer)))


def test_a_derive_from_a_handed_cache_computes_nothing_and_gives_the_same_timeline(cache, monkeypatch):
    kept = worker_side(cache, monkeypatch)
    assert len(kept["inputs"]) == 1 and len(kept["picture"]) == 1
    folder = cache[1]
    fresh_tables(monkeypatch)  # the server's process
    loaded = pipeline.Analysis.load(folder / "analysis.npz")
    assert handoff.seed(loaded, kept, load_npz(folder / "generated.npz"))
    calls = counted(monkeypatch)
    got = [pipeline.derive(loaded, p) for p in (BASE, LOWER)]
    assert calls == []  # neither the fan track nor the decision inputs computed again
    for params, tl in zip((BASE, LOWER), got):
        fresh_tables(monkeypatch)
        assert_same(tl, pipeline.derive(pipeline.Analysis.load(folder / "analysis.npz"), params))
    assert calls.count("fan_track") == 2


def test_a_layer_without_the_kept_picture_arrays_hands_over_no_picture(cache, monkeypatch):
    kept = worker_side(cache, monkeypatch, touch_fans=True)
    assert len(kept["inputs"]) == 1 and kept["picture"] == []
    folder = cache[1]
    fresh_tables(monkeypatch)
    loaded = pipeline.Analysis.load(folder / "analysis.npz")
    assert not handoff.seed(loaded, kept, load_npz(folder / "generated.npz"))
    calls = counted(monkeypatch)
    got = pipeline.derive(loaded, BASE)
    assert calls == ["fan_track"]  # the picture computed again, the decision inputs handed over
    fresh_tables(monkeypatch)
    assert_same(got, pipeline.derive(pipeline.Analysis.load(folder / "analysis.npz"), BASE))
