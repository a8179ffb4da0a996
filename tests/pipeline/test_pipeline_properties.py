"""Properties of the pipeline's pure functions for every input (hypothesis).

- finite and in range: thermal, fusion, airflow, derive (every mode), timeline round trip;
- monotone where physics says so: louder / lower thresholds never vibrate less, a greener colour is
  never warmer, a higher fan bar never turns a fan on;
- invariances: gain cancels in normalisation and in the fan levels, a mirrored picture mirrors
  the actuator weights, gain scales the low-frequency energy by its square;
- streaming: the explicit state API (init_state / process_chunk / finish) with any chunking,
  empty chunks included, equals the whole-signal call, and never mutates its state;
- time shift: input shifted by k ticks gives the output shifted by k ticks (timebase, intensity,
  derive on a shifted Analysis).

Not repeated here: tests/intensity/test_audio_properties.py (features finite, silence, non-finite input,
loudness vs gain, chunk lists), tests/intensity/test_intensity.py (normalise range, max rule) and
tests/pipeline/test_vision_properties.py (per-stage ranges for any frame, redder never colder, slew limit,
per-stage shifts).
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from hypothesis import HealthCheck, assume, given, settings
from hypothesis import strategies as st
from hypothesis.extra import numpy as hnp

from autohaptics import airflow as A
from autohaptics.intensity import features as af
from autohaptics import fusion as F
from autohaptics import intensity as I
from autohaptics import temperature as T
from autohaptics import timebase as tb
from autohaptics.layout import ACTUATOR_IDS, FAN_COLS, FAN_ROWS, N_ACTUATORS
from autohaptics.params import THESIS_RULES, GenerateParams, resolve_params
from autohaptics.pipeline import Analysis, derive
from autohaptics.timeline import NORMALISED_FEATURES, Timeline
from autohaptics.pipeline.ticks import VideoAnalysis

SETTINGS = settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.too_slow])
FEW = settings(max_examples=15, deadline=None, suppress_health_check=[HealthCheck.too_slow])

unit = st.floats(0.0, 1.0)
any_float = st.floats(allow_nan=True, allow_infinity=True, width=64)
thresholds = st.fixed_dictionaries({f: st.floats(0.0, 1.2) for f in I.FEATURES})


def _norm_stack(n_frames: int):
    return hnp.arrays(np.float64, (4, n_frames), elements=unit)


# ------------------------------------------------------------------ intensity
@SETTINGS
@given(stack=_norm_stack(20), bump=hnp.arrays(np.float64, (4, 20), elements=unit), th=thresholds,
       gate=st.floats(0.0, 1.0))
def test_more_of_any_feature_never_gives_less_intensity(stack, bump, th, gate):
    params = I.IntensityParams(thresholds=th, loudness_gate=gate)
    lo = I.frame_intensity(dict(zip(I.FEATURES, stack)), params=params)
    hi = I.frame_intensity(dict(zip(I.FEATURES, np.minimum(stack + bump, 1.0))), params=params)
    assert (hi >= lo).all()


@SETTINGS
@given(stack=_norm_stack(25), th=thresholds, drop=st.fixed_dictionaries({f: st.floats(0.0, 1.2) for f in I.FEATURES}))
def test_lower_thresholds_never_give_less_intensity(stack, th, drop):
    norm = dict(zip(I.FEATURES, stack))
    high = I.IntensityParams(thresholds=th)
    low = I.IntensityParams(thresholds={f: max(0.0, th[f] - drop[f]) for f in I.FEATURES})
    assert (I.tick_intensity(norm, 5, params=low) >= I.tick_intensity(norm, 5, params=high)).all()


@SETTINGS
@given(raw=hnp.arrays(np.float64, st.integers(1, 60), elements=st.one_of(st.just(0.0), st.floats(1e-100, 1e6))),
       gain_exp=st.integers(-20, 20), method=st.sampled_from(I.NORMALISERS))
def test_gain_cancels_in_normalisation(raw, gain_exp, method):
    # a power-of-two gain is exact in binary floating point: the normalised curve must not move at all
    np.testing.assert_array_equal(I.normalise(raw * 2.0 ** gain_exp, method=method), I.normalise(raw, method=method))


@SETTINGS
@given(stack=_norm_stack(30), k=st.integers(0, 12), th=thresholds)
def test_intensity_shifts_with_whole_ticks(stack, k, th):
    params = I.IntensityParams(thresholds=th)
    n = stack.shape[1] // tb.FRAMES_PER_TICK
    base = I.tick_intensity(dict(zip(I.FEATURES, stack)), n, params=params)
    shifted = np.concatenate([np.zeros((4, k * tb.FRAMES_PER_TICK)), stack], axis=1)
    out = I.tick_intensity(dict(zip(I.FEATURES, shifted)), n + k, params=params)
    np.testing.assert_array_equal(out, np.r_[np.zeros(k), base])


# ------------------------------------------------------------------- timebase
@SETTINGS
@given(x=hnp.arrays(np.float64, st.tuples(st.integers(0, 40), st.integers(1, 3)), elements=st.floats(-1e9, 1e9)),
       n=st.integers(1, 10), k=st.integers(0, 10))
def test_frames_to_ticks_shifts_with_whole_ticks(x, n, k):
    base = tb.frames_to_ticks(x, n)
    shifted = np.concatenate([np.full((k * tb.FRAMES_PER_TICK, x.shape[1]), -2e9), x])
    np.testing.assert_array_equal(tb.frames_to_ticks(shifted, n + k)[k:], base)
    # missing trailing frames count as 0, frames past the last tick are dropped
    whole = np.concatenate([x, np.zeros((max(0, n * tb.FRAMES_PER_TICK - x.shape[0]), x.shape[1]))])
    np.testing.assert_array_equal(tb.frames_to_ticks(whole, n), base)
    extra = np.concatenate([whole[: n * tb.FRAMES_PER_TICK], np.full((7, x.shape[1]), 5e9)])
    np.testing.assert_array_equal(tb.frames_to_ticks(extra, n), base)


@SETTINGS
@given(ms=st.integers(1, 10_000_000), k=st.integers(0, 100_000))
def test_tick_count_and_tick_index_shift_with_whole_ticks(ms, k):
    d = ms / 1000.0
    assert tb.n_ticks(d + k * tb.TICK_S) == tb.n_ticks(d) + k
    assert tb.tick_of_time(d + k * tb.TICK_S) == tb.tick_of_time(d) + k
    assert tb.tick_of_time(d - 0.0005) == tb.n_ticks(d) - 1  # the clip's last instant is in its last tick


# ------------------------------------------------- audio features (streaming API)
@st.composite
def audio(draw, max_len: int = 6000) -> np.ndarray:
    n = draw(st.integers(1, max_len))
    rng = np.random.default_rng(draw(st.integers(0, 2 ** 32 - 1)))
    level = 10 ** (draw(st.floats(-90.0, 0.0)) / 20)
    kind = draw(st.sampled_from(["noise", "tone", "bursts", "square"]))
    t = np.arange(n) / 48_000
    if kind == "noise":
        x = rng.standard_normal(n)
    elif kind == "tone":
        x = np.sin(2 * np.pi * draw(st.floats(30.0, 15_000.0)) * t)
    elif kind == "bursts":
        x = rng.standard_normal(n) * (rng.random(n // 300 + 1) > 0.6).repeat(300)[:n]
    else:
        x = np.sign(np.sin(2 * np.pi * 60.0 * t) + 1e-9)
    return np.clip(level * x, -1.0, 1.0).astype(np.float32)


@FEW
@given(x=audio(), cuts=st.lists(st.integers(0, 6000), max_size=6), empties=st.integers(0, 3),
       method=st.sampled_from(["fast", "iso"]), frame_loudness=st.sampled_from(af.FRAME_LOUDNESS))
def test_state_api_with_any_chunking_equals_the_whole_signal(x, cuts, empties, method, frame_loudness):
    params = af.AudioFeatureParams(loudness_method=method, frame_loudness=frame_loudness)
    bounds = sorted({0, x.size, *[c for c in cuts if c <= x.size]})
    chunks = [x[a:b] for a, b in zip(bounds[:-1], bounds[1:])]
    for i in range(empties):  # empty chunks anywhere change nothing
        chunks.insert((i * 7) % (len(chunks) + 1), x[:0])
    state = af.init_state(params)
    parts, frames = [], 0
    for c in chunks:
        part, state = af.process_chunk(c, state, params=params)
        frames += part.n_frames
        assert frames == state.frames_out and state.n_samples == sum(p.size for p in chunks[: len(parts) + 1])
        parts.append(part)
    parts.append(af.finish(state, params=params))
    got = af.concatenate(parts)
    whole = af.compute_audio_features([x], params=params)
    assert got.n_frames == whole.n_frames == -(-x.size // tb.SAMPLES_PER_FRAME)
    for name in af.FEATURE_NAMES + ("t_s",):
        np.testing.assert_array_equal(getattr(got, name), getattr(whole, name), err_msg=name)


@FEW
@given(x=audio(max_len=4000), y=audio(max_len=4000))
def test_process_chunk_never_mutates_its_state(x, y):
    params = af.AudioFeatureParams()
    _, state = af.process_chunk(x, af.init_state(params), params=params)
    snapshot = {f.name: np.copy(getattr(state, f.name)) if isinstance(getattr(state, f.name), np.ndarray)
                else getattr(state, f.name) for f in dataclasses.fields(state)}
    first, s1 = af.process_chunk(y, state, params=params)
    again, s2 = af.process_chunk(y, state, params=params)  # the same state twice: the same answer
    for name in af.FEATURE_NAMES:
        np.testing.assert_array_equal(getattr(first, name), getattr(again, name))
    np.testing.assert_array_equal(af.finish(s1, params=params).loudness, af.finish(s2, params=params).loudness)
    for name, before in snapshot.items():
        now = getattr(state, name)
        if isinstance(before, np.ndarray):
            np.testing.assert_array_equal(now, before, err_msg=name)
        else:
            assert now is before or now == before, name


@FEW
@given(x=audio(max_len=8000), gain_db=st.floats(-40.0, 20.0))
def test_low_frequency_energy_scales_with_the_square_of_the_gain(x, gain_db):
    g = 10 ** (gain_db / 20)
    base = af.compute_audio_features([x.astype(np.float64)]).low_energy
    scaled = af.compute_audio_features([x.astype(np.float64) * g]).low_energy
    np.testing.assert_allclose(scaled, base * g * g, rtol=1e-6, atol=1e-30)


@FEW
@given(x=audio(max_len=8000), gain_db=st.floats(0.0, 30.0))
def test_calibration_is_a_gain(x, gain_db):
    # pa_per_unit * g on x equals pa_per_unit on x * g: the calibration is nothing but a gain
    g = 10 ** (gain_db / 20)
    a = af.compute_audio_features([x.astype(np.float64) * g])
    b = af.compute_audio_features([x.astype(np.float64)], params=af.AudioFeatureParams(pa_per_unit=3.5566 * g))
    for name in af.FEATURE_NAMES:
        np.testing.assert_allclose(getattr(a, name), getattr(b, name), rtol=1e-6, atol=1e-9, err_msg=name)


# --------------------------------------------------------------------- thermal
colour = hnp.arrays(np.float64, 3, elements=st.floats(0.0, 255.0))
thermal_params = st.builds(
    lambda lo, span, neutral_at, aware: T.ThermalParams(
        mapping="thesis", temp_low=lo, temp_high=lo + span, neutral_c=lo + neutral_at * span, neutral_aware=aware),
    st.floats(-20.0, 40.0), st.floats(1.0, 40.0), unit, st.booleans())


@SETTINGS
@given(rgb=hnp.arrays(np.float64, st.tuples(st.integers(1, 20), st.just(3)), elements=any_float),
       params=thermal_params)
def test_temperature_is_finite_and_in_range_for_any_colour(rgb, params):
    t = T.temperature_target(rgb, params=params)
    assert t.shape == (rgb.shape[0],) and np.isfinite(t).all()
    assert (t >= params.temp_low).all() and (t <= params.temp_high).all()
    assert np.isfinite(T.clamp_to_device(rgb[:, 0])).all()


@SETTINGS
@given(c=colour, more=st.floats(0.0, 255.0), aware=st.booleans())
def test_a_greener_colour_is_never_warmer(c, more, aware):
    # (a redder one never colder: tests/pipeline/test_vision_properties.py)
    params = T.ThermalParams(neutral_aware=aware)
    greener = c.copy()
    greener[1] = min(255.0, c[1] + more)
    assert T.temperature_target(greener, params=params) <= T.temperature_target(c, params=params) + 1e-9


# ---------------------------------------------------------------------- fusion
_MIRROR_X = [ACTUATOR_IDS.index(a) for a in ("A2", "A1", "A7", "A6", "A5", "A4", "A3", "A9", "A8")]
_MIRROR_Y = [ACTUATOR_IDS.index(a) for a in ("A8", "A9", "A3", "A4", "A5", "A6", "A7", "A1", "A2")]


@st.composite
def saliency_maps(draw, even: bool = False):
    """Smooth maps (a few Gaussian blobs) or raw noise, NaN/inf sprinkled in unless ``even``."""
    h = draw(st.integers(1, 24)) * (2 if even else 1)
    w = draw(st.integers(1, 40)) * (2 if even else 1)
    rng = np.random.default_rng(draw(st.integers(0, 2 ** 32 - 1)))
    ys, xs = np.mgrid[0:h, 0:w]
    if draw(st.booleans()):
        m = rng.random((h, w))
    else:
        m = np.zeros((h, w))
        for _ in range(draw(st.integers(1, 3))):
            cx, cy, s = rng.uniform(0, w), rng.uniform(0, h), rng.uniform(0.8, max(1.0, w / 3))
            m += rng.uniform(0.2, 1.0) * np.exp(-((xs - cx) ** 2 + (ys - cy) ** 2) / (2 * s * s))
        m /= max(m.max(), 1e-12)
    if not even and draw(st.booleans()):
        m.flat[rng.integers(0, m.size, size=max(1, m.size // 50))] = rng.choice([np.nan, np.inf, -np.inf])
    return m


@SETTINGS
@given(m=saliency_maps(), variant=st.sampled_from(F.VARIANTS), level=unit, k_std=st.floats(0.0, 4.0))
def test_actuator_weights_of_maps_with_non_finite_values_and_any_binarisation(m, variant, level, k_std):
    beta = F.actuator_weights(m, params=F.FusionParams(variant=variant, min_level=level, k_std=k_std))
    assert beta.shape == (N_ACTUATORS,) and np.isfinite(beta).all()
    assert beta.min() >= 0.0 and beta.max() == pytest.approx(1.0)


def _pixel_centre_on_an_edge(h: int, w: int) -> bool:
    """Exactly (rational arithmetic): does any pixel centre ((i + 1/2) / w, (j + 1/2) / h) lie on an
    edge of the 14 triangles? Such a pixel goes to the lower-numbered triangle, a tie-break that is
    not mirror symmetric, so the mirror property is checked on sizes without one."""
    from fractions import Fraction

    from autohaptics.layout import TRIANGLES, vertex_xy

    edges = set()
    for tri in TRIANGLES:
        pts = [tuple(Fraction(v).limit_denominator(12) for v in vertex_xy(name)) for name in tri]
        edges |= {tuple(sorted((pts[a], pts[b]))) for a, b in ((0, 1), (1, 2), (0, 2))}
    for (x0, y0), (x1, y1) in edges:
        for j in range(h):
            y = Fraction(2 * j + 1, 2 * h)
            if y0 == y1:
                if y == y0 and any(min(x0, x1) <= Fraction(2 * i + 1, 2 * w) <= max(x0, x1) for i in range(w)):
                    return True
                continue
            if not min(y0, y1) <= y <= max(y0, y1):
                continue
            x = x0 + (y - y0) * (x1 - x0) / (y1 - y0)
            i2 = x * 2 * w - 1  # x = (2 i + 1) / (2 w)
            if i2.denominator == 1 and i2.numerator % 2 == 0 and 0 <= i2.numerator // 2 < w:
                return True
    return False


@SETTINGS
@given(m=saliency_maps(even=True), variant=st.sampled_from(F.VARIANTS))
def test_a_mirrored_picture_mirrors_the_actuator_weights(m, variant):
    assume(not _pixel_centre_on_an_edge(*m.shape))
    params = F.FusionParams(variant=variant)
    beta = F.actuator_weights(m, params=params)
    np.testing.assert_allclose(F.actuator_weights(m[:, ::-1], params=params), beta[_MIRROR_X], atol=1e-9)
    np.testing.assert_allclose(F.actuator_weights(m[::-1], params=params), beta[_MIRROR_Y], atol=1e-9)


# --------------------------------------------------------------------- airflow
grid = hnp.arrays(np.float64, (FAN_ROWS, FAN_COLS), elements=any_float)
# no subnormals: scaling by a power of two stays exact
clean_grid = hnp.arrays(np.float64, (FAN_ROWS, FAN_COLS), elements=st.one_of(st.just(0.0), st.floats(1e-100, 1e3)))


@SETTINGS
@given(m=grid, near=grid, rel=unit, near_min=unit, share=unit)
def test_fan_levels_are_finite_and_in_range_for_any_grid(m, near, rel, near_min, share):
    levels = A.fan_levels(m, near, params=A.AirflowParams(cell_rel=rel, near_min=near_min, near_share=share))
    assert levels.shape == (FAN_ROWS, FAN_COLS) and np.isfinite(levels).all()
    assert levels.min() >= 0.0 and levels.max() <= 1.0


@SETTINGS
@given(m=clean_grid, near=hnp.arrays(np.float64, (FAN_ROWS, FAN_COLS), elements=unit), exp=st.integers(-30, 30))
def test_fan_levels_do_not_depend_on_the_motion_units(m, near, exp):
    np.testing.assert_array_equal(A.fan_levels(m * 2.0 ** exp, near), A.fan_levels(m, near))


@SETTINGS
@given(m=clean_grid, near=hnp.arrays(np.float64, (FAN_ROWS, FAN_COLS), elements=unit), rel=unit, near_min=unit,
       share=unit, more=unit)
def test_a_higher_bar_never_turns_a_fan_on(m, near, rel, near_min, share, more):
    def on(**kw):
        args = dict(cell_rel=rel, near_min=near_min, near_share=share) | kw
        return A.fan_levels(m, near, params=A.AirflowParams(**args)) > 0

    base = on()
    for stricter in (on(cell_rel=min(1.0, rel + more)), on(near_min=min(1.0, near_min + more)),
                     on(near_share=max(0.0, share - more))):
        assert not (stricter & ~base).any()


@SETTINGS
@given(cm=hnp.arrays(np.float64, st.tuples(st.integers(1, 30), st.just(FAN_ROWS), st.just(FAN_COLS)),
                     elements=st.one_of(st.just(0.0), st.floats(0.0, 1e6))),
       cuts=st.lists(st.booleans(), min_size=30, max_size=30),
       sigma_t=st.floats(0.0, 5.0), sigma_x=st.floats(0.0, 3.0), exp=st.integers(-20, 20))
def test_smoothed_cell_motion_is_a_weighted_mean(cm, cuts, sigma_t, sigma_x, exp):
    """Finite, >= 0, never above the largest input, and it scales with the motion's units."""
    n = cm.shape[0]
    cut = np.array(cuts[:n])
    shot = np.where(cut, -1, np.cumsum(cut))
    params = A.AirflowParams(cell_sigma_ticks=sigma_t, cell_sigma_cells=sigma_x)
    out = A.smoothed_cell_motion(cm, shot, np.arange(n), params=params)
    assert out.shape == cm.shape and np.isfinite(out).all() and out.min() >= 0.0
    assert out.max() <= np.float32(cm.max()) * (1 + 1e-6)
    scaled = A.smoothed_cell_motion(cm * 2.0 ** exp, shot, np.arange(n), params=params)
    np.testing.assert_allclose(scaled, out * 2.0 ** exp, rtol=1e-5, atol=1e-30)


@SETTINGS
@given(motion=hnp.arrays(np.float64, st.integers(0, 80), elements=st.one_of(st.just(0.0), st.floats(1e-100, 50.0))),
       floor=st.floats(0.0, 1.0), exp=st.integers(-10, 10))
def test_adaptive_threshold_respects_the_floor_and_follows_the_units(motion, floor, exp):
    thr = A.motion_threshold(motion, params=A.AirflowParams(floor=floor))
    assert np.isfinite(thr) and thr >= floor
    # with no floor the adaptive threshold is in the motion's own units
    free = A.AirflowParams(floor=0.0)
    assert A.motion_threshold(motion * 2.0 ** exp, params=free) == pytest.approx(
        A.motion_threshold(motion, params=free) * 2.0 ** exp, rel=1e-12, abs=1e-300)
    assert A.motion_threshold(motion, params=A.AirflowParams(threshold=0.25)) == 0.25


@SETTINGS
@given(flow=hnp.arrays(np.float32, st.tuples(st.integers(1, 20), st.integers(1, 20), st.just(2)),
                       elements=st.one_of(st.just(0.0), st.floats(2.0 ** -20, 1e3, width=32),
                                          st.floats(-1e3, -(2.0 ** -20), width=32))),
       dt=st.floats(1e-3, 1.0), width=st.integers(1, 4000))
def test_motion_magnitude_is_finite_non_negative_and_linear_in_the_flow(flow, dt, width):
    mag = A.motion_magnitude(flow, dt_s=dt, width_px=width)
    assert np.isfinite(mag).all() and (mag >= 0).all()
    np.testing.assert_allclose(A.motion_magnitude(flow * 2, dt_s=dt, width_px=width), 2 * mag, rtol=1e-6)
    np.testing.assert_allclose(A.motion_magnitude(flow, dt_s=2 * dt, width_px=width), mag / 2, rtol=1e-6)
    cells = A.cell_motion(mag)
    assert cells.shape == (FAN_ROWS, FAN_COLS)
    assert cells.min() >= mag.min() - 1e-4 * (1 + mag.max()) and cells.max() <= mag.max() * (1 + 1e-5) + 1e-6


# ---------------------------------------------------------------- timeline
@st.composite
def timelines(draw):
    n = draw(st.integers(1, 30))
    rng = np.random.default_rng(draw(st.integers(0, 2 ** 32 - 1)))
    tl = Timeline.empty(n, source={"name": "x.mp4", "duration_s": n / 10})
    tl.vibration[:] = rng.random((n, N_ACTUATORS)) * (rng.random((n, N_ACTUATORS)) > 0.5)
    tl.temperature_c[:] = rng.uniform(30.0, 55.0, n)
    tl.fans[:] = rng.random((n, FAN_ROWS, FAN_COLS)) * (rng.random((n, FAN_ROWS, FAN_COLS)) > 0.8)
    tl.features["loudness"] = rng.random(n)
    tl.features["motion_fw_per_s"] = rng.uniform(-1e6, 1e6, n) * 10.0 ** rng.integers(-8, 3)
    return tl.validate()


@SETTINGS
@given(tl=timelines())
def test_timeline_round_trip_is_within_the_rounding_and_idempotent(tl):
    once = Timeline.from_json(tl.to_json())
    assert once.n_ticks == tl.n_ticks
    for name in ("vibration", "temperature_c", "fans"):
        np.testing.assert_allclose(getattr(once, name), getattr(tl, name), atol=5e-5 + 1e-6, err_msg=name)
    np.testing.assert_allclose(once.features["loudness"], tl.features["loudness"], atol=5e-5 + 1e-6)
    twice_text = Timeline.from_json(once.to_json()).to_json()
    assert twice_text == once.to_json()  # a written timeline reads back to the same document


# ---------------------------------------------------------------------- derive
def _info(n: int, video: bool, audio: bool) -> dict:
    return {"path": "synthetic.mp4", "duration_s": n / 10, "size_bytes": 0, "container": "mp4",
            "video": {"width": 64, "height": 36, "fps": 24.0, "codec": "h264", "rotation": 0} if video else None,
            "audio": {"sample_rate": 48000, "channels": 2, "layout": "stereo", "codec": "aac"} if audio else None}


@st.composite
def analyses(draw, max_ticks: int = 25):
    """A random but consistent feature cache: audio features on the 20 ms grid, a video analysis per tick."""
    n = draw(st.integers(1, max_ticks))
    rng = np.random.default_rng(draw(st.integers(0, 2 ** 32 - 1)))
    has_audio, has_video = draw(st.booleans()), draw(st.booleans())
    audio = None
    if has_audio:
        audio = {f: rng.random(n * 5) ** 3 * draw(st.sampled_from([0.0, 1e-9, 1.0, 40.0])) for f in I.FEATURES}
    video = None
    if has_video:
        v = VideoAnalysis.empty(n)
        v.frame_mask[:] = True
        v.mean_rgb[:] = rng.uniform(0, 255, (n, 3))
        v.cut[:] = rng.random(n) < 0.1
        v.static[:] = rng.random(n) < 0.2
        v.flow_mask[:] = ~v.cut & ~v.static
        v.motion[:] = np.where(v.flow_mask, rng.random(n) ** 2 * 0.5, 0.0)
        v.cell_motion[:] = rng.random((n, FAN_ROWS, FAN_COLS)) * v.motion[:, None, None] * 2
        v.depth_mask[:] = v.flow_mask & (v.motion > 0.005)
        v.nearness[:] = np.where(v.depth_mask[:, None, None], rng.random((n, FAN_ROWS, FAN_COLS)), 0.0)
        v.saliency_mask[:] = rng.random(n) < 0.8
        beta = rng.random((n, N_ACTUATORS))
        v.beta[:] = np.where(v.saliency_mask[:, None], beta / beta.max(axis=1, keepdims=True), 0.0)
        video = v
    if audio is None and video is None:
        audio = {f: rng.random(n * 5) for f in I.FEATURES}
    return Analysis(info=_info(n, video is not None, audio is not None), sha256="0" * 64, n_ticks=n, params={},
                    audio=audio, video=video)


def _shifted(a: Analysis, k: int) -> Analysis:
    """The same cache with k silent, black, motionless ticks in front."""
    audio = None if a.audio is None else {f: np.r_[np.zeros(5 * k), x] for f, x in a.audio.items()}
    video = None
    if a.video is not None:
        pad = VideoAnalysis.empty(k)
        pad.frame_mask[:] = True
        video = VideoAnalysis.from_arrays({name: np.concatenate([getattr(pad, name), arr])
                                           for name, arr in a.video.arrays().items()})
    n = a.n_ticks + k
    return Analysis(info=_info(n, video is not None, audio is not None), sha256=a.sha256, n_ticks=n,
                    params={}, audio=audio, video=video)


def _params(mode: str, th: dict | None = None, manual_threshold: bool = False, thesis: bool = False) -> GenerateParams:
    overrides = {"mode": mode, **(THESIS_RULES if thesis else {})}
    if manual_threshold:
        overrides["airflow.threshold"] = 0.05
    return resolve_params("balanced", overrides, th)[0]


@SETTINGS
@given(a=analyses(), mode=st.sampled_from(["multimodal", "audio", "visual", "random"]), th=thresholds,
       normaliser=st.sampled_from(I.NORMALISERS))
def test_derive_output_is_finite_and_in_range_in_every_mode(a, mode, th, normaliser):
    params = dataclasses.replace(_params(mode, th),
                                 intensity=dataclasses.replace(I.IntensityParams(thresholds=th), normaliser=normaliser))
    tl = derive(a, params)
    n = a.n_ticks
    assert tl.n_ticks == n and tl.vibration.shape == (n, N_ACTUATORS) and tl.fans.shape == (n, FAN_ROWS, FAN_COLS)
    lo, hi = tl.temp_range
    for arr, a_, b_ in ((tl.vibration, 0, 1), (tl.fans, 0, 1), (tl.temperature_c, lo, hi)):
        assert np.isfinite(arr).all() and arr.min() >= a_ and arr.max() <= b_
    for name, values in tl.features.items():
        assert np.isfinite(values).all(), name
        if name in NORMALISED_FEATURES:
            assert values.min() >= 0 and values.max() <= 1, name
    np.testing.assert_array_equal(derive(a, params).vibration, tl.vibration)  # pure: same input, same output


@SETTINGS
@given(a=analyses(), k=st.integers(1, 15), mode=st.sampled_from(["multimodal", "audio", "visual"]))
def test_derive_on_a_shifted_analysis_shifts_the_timeline(a, k, mode):
    # max normaliser and a manual airflow threshold: both ignore k silent, motionless ticks in front
    # (the percentile normaliser and the adaptive threshold look at the whole clip's distribution);
    # the thesis's vibration rule, since the default judges each tick against the seconds before it
    params = _params(mode, manual_threshold=True, thesis=True)
    base, shifted = derive(a, params), derive(_shifted(a, k), params)
    assert shifted.n_ticks == base.n_ticks + k
    np.testing.assert_array_equal(shifted.vibration[k:], base.vibration)
    assert not shifted.vibration[:k].any() and not shifted.fans[:k].any()
    np.testing.assert_array_equal(shifted.fans[k:], base.fans)
    np.testing.assert_array_equal(shifted.temperature_c[k:], base.temperature_c)
    for name, values in base.features.items():
        np.testing.assert_array_equal(shifted.features[name][k:], values, err_msg=name)


@SETTINGS
@given(a=analyses(), th=thresholds, drop=unit, mode=st.sampled_from(["multimodal", "audio"]))
def test_lower_thresholds_never_give_less_vibration(a, th, drop, mode):
    assume(a.audio is not None)
    high = derive(a, _params(mode, th)).vibration
    low = derive(a, _params(mode, {f: max(0.0, v - drop) for f, v in th.items()})).vibration
    assert (low >= high).all()


@FEW
@given(a=analyses())
def test_derive_does_not_touch_its_analysis(a):
    before = {f: x.copy() for f, x in (a.audio or {}).items()}
    vbefore = {k: v.copy() for k, v in a.video.arrays().items()} if a.video is not None else {}
    derive(a, _params("multimodal"))
    for f, x in before.items():
        np.testing.assert_array_equal(a.audio[f], x)
    for k, v in vbefore.items():
        np.testing.assert_array_equal(getattr(a.video, k), v)
