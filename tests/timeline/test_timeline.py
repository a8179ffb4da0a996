import json

import numpy as np
import pytest

from autohaptics.errors import ParameterError
from autohaptics.timeline import Timeline


def _random_timeline(n=37, seed=0):
    rng = np.random.default_rng(seed)
    tl = Timeline.empty(n, source={"name": "x.mp4", "duration_s": n * 0.1}, generator={"mode": "audio"})
    tl.vibration[:] = rng.random((n, 9)) * (rng.random((n, 1)) > 0.5)
    tl.temperature_c[:] = 30 + 25 * rng.random(n)
    tl.fans[n // 3:n // 3 + 1, 2:4, 10:] = rng.random((1, 2, 7))
    tl.features["loudness"] = rng.random(n)
    tl.features["loudness_sone"] = 40 * rng.random(n)
    tl.stats = {"audio": {"seconds": 0.5}}
    tl.extra["edits"] = [{"op": "set", "track": "vibration", "t0": 0, "t1": 3, "value": 0.5}]
    return tl.validate()


def test_save_load_round_trip(tmp_path):
    tl = _random_timeline()
    path = tl.save(tmp_path / "t.json")
    back = Timeline.load(path)
    assert back.n_ticks == tl.n_ticks
    np.testing.assert_allclose(back.vibration, tl.vibration, atol=5e-5)
    np.testing.assert_allclose(back.temperature_c, tl.temperature_c, atol=5e-5)
    np.testing.assert_allclose(back.fans, tl.fans, atol=5e-5)
    np.testing.assert_allclose(back.features["loudness_sone"], tl.features["loudness_sone"], atol=5e-5)
    assert back.extra["edits"] == tl.extra["edits"]
    assert back.stats == tl.stats


def test_file_follows_the_documented_schema(tmp_path):
    tl = _random_timeline(n=5)
    doc = json.loads(tl.to_json())
    assert doc["format"] == "autohaptics.timeline" and doc["version"] == 1
    assert doc["tick_s"] == 0.1 and doc["n_ticks"] == 5
    assert [a["id"] for a in doc["layout"]["actuators"]] == [f"A{i}" for i in range(1, 10)]
    assert doc["layout"]["fans"] == {"rows": 9, "cols": 17}
    assert np.asarray(doc["tracks"]["vibration"]).shape == (5, 9)
    assert np.asarray(doc["tracks"]["temperature_c"]).shape == (5,)
    assert np.asarray(doc["tracks"]["fans"]).shape == (5, 9, 17)
    assert doc["generator"]["name"] == "autohaptics"


def test_empty_timeline_is_valid_and_neutral():
    tl = Timeline.empty(3)
    assert tl.vibration.shape == (3, 9) and not tl.vibration.any()
    assert np.all(tl.temperature_c == 33.0)
    assert tl.fans.shape == (3, 9, 17)
    tl.validate()


@pytest.mark.parametrize("mutate, message", [
    (lambda t: setattr(t, "vibration", np.zeros((4, 9))), "vibration"),
    (lambda t: setattr(t, "vibration", np.zeros((5, 8))), "(5, 8)"),
    (lambda t: t.vibration.__setitem__((2, 3), np.nan), "non-finite"),
    (lambda t: t.vibration.__setitem__((2, 3), 1.5), "outside"),
    (lambda t: t.fans.__setitem__((0, 0, 0), -0.2), "fans"),
    (lambda t: t.temperature_c.__setitem__(1, 80.0), "temperature_c"),
    (lambda t: t.features.__setitem__("loudness", np.full(5, 2.0)), "features.loudness"),
    (lambda t: t.features.__setitem__("motion", np.zeros(6)), "features.motion"),
])
def test_validation_names_the_track(mutate, message):
    tl = Timeline.empty(5)
    mutate(tl)
    with pytest.raises(ParameterError, match=message.replace("(", r"\(").replace(")", r"\)")):
        tl.validate()


def test_load_rejects_foreign_and_broken_files(tmp_path):
    p = tmp_path / "a.json"
    p.write_text("{not json")
    with pytest.raises(ParameterError, match="not a timeline JSON"):
        Timeline.load(p)
    p.write_text(json.dumps({"format": "other"}))
    with pytest.raises(ParameterError, match="format"):
        Timeline.load(p)
    with pytest.raises(ParameterError, match="no such file"):
        Timeline.load(tmp_path / "missing.json")
    doc = json.loads(Timeline.empty(2).to_json())
    del doc["tracks"]["fans"]
    p.write_text(json.dumps(doc))
    with pytest.raises(ParameterError, match="fans"):
        Timeline.load(p)


def test_temperature_range_follows_generator_params():
    tl = Timeline.empty(2, generator={"params": {"temp_low": 20.0, "temp_high": 40.0}})
    tl.temperature_c[:] = 45.0
    with pytest.raises(ParameterError, match=r"\[20, 40\]"):
        tl.validate()


def test_save_is_atomic_and_leaves_no_partial_file(tmp_path):
    tl = Timeline.empty(3)
    tl.vibration[0, 0] = np.inf
    with pytest.raises(ParameterError):
        tl.save(tmp_path / "x.json")
    assert list(tmp_path.iterdir()) == []
