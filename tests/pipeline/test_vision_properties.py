"""Properties of the vision stages that must hold for every input (hypothesis).

- any frame (black, white, pure red/green/blue, noise, a gradient, one pixel wide or tall) gives
  finite outputs inside their ranges at every stage, with numpy's division and invalid-value
  warnings turned into errors (no division by zero anywhere);
- a brighter red is never colder (plain and neutral-aware); flat frames have no saliency and no flow;
  the slew limit chunked equals whole;
- the per-tick functions have no hidden state: prefixing a sequence with k copies of its first
  tick shifts every per-tick output by k.
"""

from __future__ import annotations

import cv2
import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from hypothesis.extra import numpy as hnp

from autohaptics import airflow, fusion
from autohaptics.airflow import cuts
from autohaptics.fusion import saliency
from autohaptics import temperature as thermal
from autohaptics.layout import ACTUATOR_IDS, N_ACTUATORS
from onnx_models import map_model
from test_vision_contract import STAGES, Inputs, check

SETTINGS = settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.too_slow])
RAISE = dict(divide="raise", invalid="raise", over="raise")
A5 = np.eye(N_ACTUATORS)[ACTUATOR_IDS.index("A5")]

KINDS = ("black", "white", "red", "green", "blue", "noise", "gradient", "colour", "disc")
sizes = st.tuples(st.integers(1, 40), st.integers(1, 48)) | st.sampled_from([(1, 1), (1, 40), (40, 1), (16, 16)])


def make_frame(kind: str, h: int, w: int, seed: int) -> np.ndarray:
    rng = np.random.default_rng(seed)
    solid = {"black": (0, 0, 0), "white": (255, 255, 255), "red": (255, 0, 0), "green": (0, 255, 0),
             "blue": (0, 0, 255), "colour": tuple(int(v) for v in rng.integers(0, 256, 3))}
    if kind in solid:
        return np.broadcast_to(np.asarray(solid[kind], np.uint8), (h, w, 3)).copy()
    if kind == "noise":
        return rng.integers(0, 256, (h, w, 3), dtype=np.uint8)
    if kind == "gradient":
        ramp = np.linspace(0, 255, w, dtype=np.float64)[None, :, None]
        return np.broadcast_to(ramp * rng.uniform(0, 1, 3), (h, w, 3)).astype(np.uint8)
    frame = np.full((h, w, 3), 20, np.uint8)  # a bright disc somewhere
    ys, xs = np.mgrid[0:h, 0:w]
    cy, cx, r = rng.uniform(0, h), rng.uniform(0, w), rng.uniform(0.5, max(1.0, min(h, w) / 3))
    frame[(ys - cy) ** 2 + (xs - cx) ** 2 <= r * r] = (250, 240, 200)
    return frame


@st.composite
def frame_pairs(draw):
    h, w = draw(sizes)
    kind, prev_kind = draw(st.sampled_from(KINDS)), draw(st.sampled_from(KINDS))
    seed = draw(st.integers(0, 2**16))
    return make_frame(kind, h, w, seed), make_frame(prev_kind, h, w, seed + 1)


@pytest.fixture(scope="module")
def models(tmp_path_factory) -> dict:
    d = tmp_path_factory.mktemp("onnx")
    return {"nchw": str(map_model(d / "nchw.onnx", layout="nchw")), "nhwc": str(map_model(d / "nhwc.onnx", layout="nhwc"))}


@SETTINGS
@given(pair=frame_pairs())
def test_every_stage_is_finite_and_in_range_for_any_frame(pair, models):
    rgb, prev = pair
    x = Inputs(rgb, prev, models)
    with np.errstate(**RAISE):
        for stage in STAGES:
            check(stage, stage.run(x), rgb.shape[:2])


# ---------------------------------------------------------------- no division by zero
@pytest.mark.parametrize("shape", [(1, 1), (1, 30), (30, 1), (72, 128)])
def test_pure_green_frame(shape):
    green = np.broadcast_to(np.array([0, 255, 0], np.uint8), shape + (3,)).copy()
    with np.errstate(**RAISE):
        assert float(thermal.temperature_target(thermal.mean_colour(green))) == 30.0
        aware = thermal.temperature_target(thermal.mean_colour(green), params=thermal.ThermalParams(neutral_aware=True))
        assert float(aware) == 30.0
        smap = saliency.saliency_map(green)
        np.testing.assert_array_equal(fusion.actuator_weights(smap), A5)


@SETTINGS
@given(shape=sizes, fill=st.sampled_from([0.0, np.nan, -1.0]))
def test_empty_saliency_map_puts_everything_on_a5(shape, fill):
    with np.errstate(**RAISE):
        np.testing.assert_array_equal(fusion.actuator_weights(np.full(shape, fill, np.float32)), A5)
        np.testing.assert_array_equal(fusion.actuator_weights(shape=np.zeros(shape, bool)), A5)


@SETTINGS
@given(tri=st.integers(0, 13), vertex=st.integers(0, 2), nudge=st.sampled_from([0.0, 1e-15, 1e-9, 1e-6]))
def test_centroid_on_or_next_to_a_vertex(tri, vertex, nudge):
    xy = fusion.TRIANGLE_XY[tri][vertex] + nudge
    with np.errstate(**RAISE):
        w = fusion.triangle_weights(tuple(xy), tri)
    assert np.isfinite(w).all() and w.min() >= 0 and w.sum() == pytest.approx(1.0, abs=1e-12)
    act = fusion.TRIANGLE_ACTUATORS[tri][vertex]
    if act >= 0 and nudge == 0.0:
        np.testing.assert_array_equal(w, np.eye(N_ACTUATORS)[act])


@SETTINGS
@given(tri=st.integers(0, 13), xy=st.tuples(st.floats(0, 1), st.floats(0, 1)))
def test_triangle_weights_anywhere(tri, xy):
    with np.errstate(**RAISE):
        w = fusion.triangle_weights(xy, tri)
    assert np.isfinite(w).all() and w.min() >= 0 and w.sum() == pytest.approx(1.0, abs=1e-12)
    assert set(np.flatnonzero(w)) <= {a for a in fusion.TRIANGLE_ACTUATORS[tri] if a >= 0}


@SETTINGS
@given(shape=hnp.arrays(bool, st.tuples(st.integers(1, 30), st.integers(1, 30))), variant=st.sampled_from(["paper", "mass"]))
def test_any_salient_shape_gives_weights_in_range(shape, variant):
    with np.errstate(**RAISE):
        beta = fusion.actuator_weights(shape=shape, params=fusion.FusionParams(variant=variant))
    assert beta.shape == (N_ACTUATORS,) and np.isfinite(beta).all()
    assert beta.min() >= 0 and beta.max() == 1.0


# ---------------------------------------------------------------- colour order
channel = st.integers(0, 255)


@SETTINGS
@given(r=channel, g=channel, b=channel, more=st.integers(1, 255), aware=st.booleans())
def test_a_brighter_red_frame_is_never_colder(r, g, b, more, aware):
    params = thermal.ThermalParams(neutral_aware=aware)
    redder = min(255, r + more)
    frames = [np.broadcast_to(np.array(c, np.uint8), (9, 16, 3)) for c in ((r, g, b), (redder, g, b))]
    with np.errstate(**RAISE):
        t0, t1 = (float(thermal.temperature_target(thermal.mean_colour(f), params=params)) for f in frames)
    assert t1 >= t0 - 1e-9


@SETTINGS
@given(c=st.tuples(channel, channel, channel), aware=st.booleans())
def test_temperature_stays_in_range(c, aware):
    t = float(thermal.temperature_target(np.array(c, float), params=thermal.ThermalParams(neutral_aware=aware)))
    assert 30.0 <= t <= 55.0


# ---------------------------------------------------------------- shift by k ticks
def per_tick(frames: list[np.ndarray]) -> dict[str, np.ndarray]:
    """Per-tick outputs of the pure stage functions over a frame sequence (tick t uses frames t-1, t)."""
    temps, betas, cut, motion, fans = [], [], [], [], []
    for t, f in enumerate(frames):
        prev = frames[t - 1] if t else f
        temps.append(thermal.temperature_target(thermal.mean_colour(f)))
        betas.append(fusion.actuator_weights(saliency.saliency_map(f)))
        cut.append(t > 0 and cuts.is_cut(cuts.frame_signature(prev), cuts.frame_signature(f)))
        g0, g1 = cv2.cvtColor(prev, cv2.COLOR_RGB2GRAY), cv2.cvtColor(f, cv2.COLOR_RGB2GRAY)
        mag = airflow.motion_magnitude(airflow.optical_flow(g0, g1), dt_s=0.04, width_px=g0.shape[1])
        cells = airflow.cell_motion(mag)
        motion.append(airflow.motion_score(mag))
        fans.append(airflow.fan_levels(cells, np.ones_like(cells)))
    return {"temperature": np.array(temps), "beta": np.array(betas), "cut": np.array(cut), "motion": np.array(motion),
            "fans": np.array(fans)}


@settings(max_examples=15, deadline=None)
@given(kinds=st.lists(st.sampled_from(KINDS), min_size=2, max_size=5), k=st.integers(1, 3), seed=st.integers(0, 999),
       size=st.sampled_from([(18, 32), (36, 64)]))
def test_a_sequence_shifted_by_k_ticks_shifts_the_outputs_by_k(kinds, k, seed, size):
    frames = [make_frame(kind, *size, seed + i) for i, kind in enumerate(kinds)]
    base = per_tick(frames)
    shifted = per_tick([frames[0]] * k + frames)
    for name, values in base.items():
        np.testing.assert_array_equal(shifted[name][k:], values, err_msg=name)
    assert not shifted["cut"][:k + 1].any()  # repeating the first frame never makes a cut


@SETTINGS
@given(colours=hnp.arrays(np.float64, st.tuples(st.integers(1, 30), st.just(3)), elements=st.floats(0, 255)),
       k=st.integers(1, 10), aware=st.booleans())
def test_temperature_of_a_shifted_sequence(colours, k, aware):
    params = thermal.ThermalParams(neutral_aware=aware)
    base = thermal.temperature_target(colours, params=params)
    shifted = thermal.temperature_target(np.concatenate([np.repeat(colours[:1], k, axis=0), colours]), params=params)
    np.testing.assert_array_equal(shifted[k:], base)


@SETTINGS
@given(temps=hnp.arrays(np.float64, st.integers(1, 40), elements=st.floats(20, 60)), k=st.integers(1, 10),
       rate=st.floats(0.5, 50))
def test_slew_limit_of_a_shifted_sequence(temps, k, rate):
    """The element starts at the first target: k more ticks of that target change nothing after them."""
    base = thermal.slew_limit(temps, max_rate_c_per_s=rate)
    shifted = thermal.slew_limit(np.concatenate([np.full(k, temps[0]), temps]), max_rate_c_per_s=rate)
    np.testing.assert_allclose(shifted[k:], base, rtol=0, atol=1e-12)
    assert np.abs(np.diff(base)).max(initial=0) <= rate * 0.1 + 1e-9


@settings(max_examples=40, deadline=None)
@given(kind=st.sampled_from(["black", "white", "red", "green", "blue", "colour"]), h=st.integers(1, 40),
       w=st.integers(1, 40), seed=st.integers(0, 999))
def test_flat_frames_have_no_salient_region_and_no_motion(kind, h, w, seed):
    f = make_frame(kind, h, w, seed)
    smap = saliency.saliency_map(f)
    assert not smap.any()
    np.testing.assert_array_equal(fusion.actuator_weights(smap), A5)
    g = cv2.cvtColor(f, cv2.COLOR_RGB2GRAY)
    assert not airflow.optical_flow(g, g).any()


@pytest.mark.parametrize("xy", [(1 / 3, 0.0), (2 / 3, 0.0), (0.0, 0.5), (0.25, 0.5), (0.5, 0.5), (0.75, 0.5),
                                (1.0, 0.5), (1 / 3, 1.0), (2 / 3, 1.0), (0.0, 0.0), (1.0, 1.0)])
def test_a_vertex_as_the_centroid_of_any_triangle_is_safe(xy):
    """Every actuator and corner position, taken as the centroid of each of the 14 triangles."""
    for tri in range(14):
        with np.errstate(**RAISE):
            w = fusion.triangle_weights(xy, tri)
        assert np.isfinite(w).all() and w.sum() == pytest.approx(1.0)


@SETTINGS
@given(temps=st.lists(st.floats(20.0, 60.0), min_size=1, max_size=80), rate=st.floats(0.05, 20.0),
       split=st.integers(0, 80))
def test_slew_limit_chunked_equals_whole(temps, rate, split):
    x = np.asarray(temps)
    whole = thermal.slew_limit(x, max_rate_c_per_s=rate, tick_s=0.1)
    k = min(split, x.size)
    first = thermal.slew_limit(x[:k], max_rate_c_per_s=rate, tick_s=0.1)
    rest = thermal.slew_limit(x[k:], max_rate_c_per_s=rate, tick_s=0.1, start_c=float(first[-1]) if k else None)
    np.testing.assert_allclose(np.concatenate([first, rest]), whole, rtol=0, atol=1e-9)
