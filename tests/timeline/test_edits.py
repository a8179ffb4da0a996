"""Edit operations (autohaptics.timeline.edits): every op with known answers, validation, properties."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from autohaptics.errors import ParameterError
from autohaptics.layout import FAN_COLS, FAN_ROWS, TEMP_NEUTRAL_C
from autohaptics.timeline.edit_ops import OPS
from autohaptics.timeline.op_fields import LANES
from autohaptics.timeline.edits import apply_ops, validate_op
from autohaptics.timeline import Timeline

N = 10


def base(n: int = N) -> Timeline:
    """Vibration 0.5 everywhere, temperature 40 C, every fan at 0.5, loudness ramp."""
    tl = Timeline.empty(n, generator={"params": {"temp_low": 30.0, "temp_high": 55.0}})
    tl.vibration[:] = 0.5
    tl.temperature_c[:] = 40.0
    tl.fans[:] = 0.5
    tl.features["loudness"] = np.linspace(0, 1, n)
    return tl.validate()


def vib(tl: Timeline, lane: str) -> np.ndarray:
    return tl.vibration[:, int(lane[1:]) - 1]


def test_set_writes_value_in_range_only_on_named_lanes():
    gen = base()
    tl, markers = apply_ops(gen, [{"op": "set", "lanes": ["A1", "fans"], "t0": 2, "t1": 5, "value": 0.8}])
    np.testing.assert_allclose(vib(tl, "A1"), [0.5, 0.5, 0.8, 0.8, 0.8, 0.5, 0.5, 0.5, 0.5, 0.5])
    np.testing.assert_allclose(vib(tl, "A2"), 0.5)
    np.testing.assert_allclose(tl.fans[2:5], 0.8)
    np.testing.assert_allclose(tl.fans[5:], 0.5)
    np.testing.assert_allclose(tl.temperature_c, 40.0)
    assert markers == []


def test_set_clamps_to_track_ranges():
    tl, _ = apply_ops(base(), [
        {"op": "set", "lanes": ["A1"], "t0": 0, "t1": 2, "value": 7.0},
        {"op": "set", "lanes": ["A2"], "t0": 0, "t1": 2, "value": -1.0},
        {"op": "set", "lanes": ["temperature"], "t0": 0, "t1": 1, "value": 99.0},
        {"op": "set", "lanes": ["temperature"], "t0": 1, "t1": 2, "value": 10.0},
        {"op": "set", "lanes": ["temperature"], "t0": 2, "t1": 3, "value": 45.5},
    ])
    np.testing.assert_allclose(vib(tl, "A1")[:2], 1.0)
    np.testing.assert_allclose(vib(tl, "A2")[:2], 0.0)
    np.testing.assert_allclose(tl.temperature_c[:3], [55.0, 30.0, 45.5])


def test_scale_multiplies_and_scales_temperature_around_neutral():
    tl, _ = apply_ops(base(), [
        {"op": "scale", "lanes": ["A1"], "t0": 0, "t1": 3, "factor": 0.5},
        {"op": "scale", "lanes": ["A2"], "t0": 0, "t1": 3, "factor": 3.0},
        {"op": "scale", "lanes": ["temperature"], "t0": 0, "t1": 1, "factor": 2.0},
        {"op": "scale", "lanes": ["temperature"], "t0": 1, "t1": 2, "factor": 0.0},
        {"op": "scale", "lanes": ["fans"], "t0": 0, "t1": 1, "factor": 0.2},
    ])
    np.testing.assert_allclose(vib(tl, "A1")[:4], [0.25, 0.25, 0.25, 0.5])
    np.testing.assert_allclose(vib(tl, "A2")[:3], 1.0)  # clipped
    np.testing.assert_allclose(tl.temperature_c[:3], [33 + 2 * 7, 33.0, 40.0])
    np.testing.assert_allclose(tl.fans[0], 0.1, rtol=1e-6)


def test_clear_sets_off_and_neutral():
    tl, _ = apply_ops(base(), [{"op": "clear", "lanes": ["A9", "temperature", "fans"], "t0": 4, "t1": 6}])
    np.testing.assert_allclose(vib(tl, "A9")[4:6], 0.0)
    np.testing.assert_allclose(vib(tl, "A9")[6:], 0.5)
    np.testing.assert_allclose(tl.temperature_c[4:6], TEMP_NEUTRAL_C)
    np.testing.assert_allclose(tl.fans[4:6], 0.0)


def test_fade_in_and_out_ramps():
    tl, _ = apply_ops(base(), [
        {"op": "fade_in", "lanes": ["A1", "temperature"], "t0": 0, "t1": 5},
        {"op": "fade_out", "lanes": ["A2", "fans"], "t0": 5, "t1": 10},
    ])
    np.testing.assert_allclose(vib(tl, "A1")[:5], 0.5 * np.array([0, 0.25, 0.5, 0.75, 1.0]))
    np.testing.assert_allclose(tl.temperature_c[:5], 33 + 7 * np.array([0, 0.25, 0.5, 0.75, 1.0]), rtol=1e-6)
    np.testing.assert_allclose(vib(tl, "A2")[5:], 0.5 * np.array([1.0, 0.75, 0.5, 0.25, 0]))
    np.testing.assert_allclose(tl.fans[5:, 3, 7], 0.5 * np.array([1.0, 0.75, 0.5, 0.25, 0]))
    np.testing.assert_allclose(vib(tl, "A2")[:5], 0.5)


def test_one_tick_fade_gives_zero_and_fade_past_end_keeps_its_slope():
    tl, _ = apply_ops(base(), [{"op": "fade_in", "lanes": ["A1"], "t0": 3, "t1": 4},
                               {"op": "fade_in", "lanes": ["A2"], "t0": 8, "t1": 13}])
    assert vib(tl, "A1")[3] == 0.0
    np.testing.assert_allclose(vib(tl, "A2")[8:], 0.5 * np.array([0, 0.25]))


def test_paste_writes_per_lane_values_and_cuts_at_the_end():
    fans = np.full((2, FAN_ROWS, FAN_COLS), 0.25)
    fans[1, 0, 0] = 1.0
    tl, _ = apply_ops(base(), [{"op": "paste", "t0": 8, "values": {
        "A3": [0.1, 0.2, 0.3], "temperature": [31.0, 70.0], "fans": fans.tolist()}}])
    np.testing.assert_allclose(vib(tl, "A3")[7:], [0.5, 0.1, 0.2], rtol=1e-6)
    np.testing.assert_allclose(tl.temperature_c[8:], [31.0, 55.0])
    np.testing.assert_allclose(tl.fans[8:], fans)


def test_pencil_writes_one_lane_and_fans_get_one_level_each_tick():
    tl, _ = apply_ops(base(), [{"op": "pencil", "lane": "A4", "t0": 1, "values": [0.0, 0.9, 1.5]},
                               {"op": "pencil", "lane": "fans", "t0": 0, "values": [0.3]}])
    np.testing.assert_allclose(vib(tl, "A4")[:5], [0.5, 0.0, 0.9, 1.0, 0.5], rtol=1e-6)
    np.testing.assert_allclose(tl.fans[0], 0.3, rtol=1e-6)
    np.testing.assert_allclose(tl.fans[1], 0.5)


def test_temp_points_is_piecewise_linear_and_constant_outside_the_points():
    tl, _ = apply_ops(base(), [{"op": "temp_points", "t0": 0, "t1": 10, "points": [[6, 42.0], [2, 34.0]]}])
    np.testing.assert_allclose(tl.temperature_c, [34, 34, 34, 36, 38, 40, 42, 42, 42, 42])


def test_markers_add_update_delete_sorted_by_time():
    ops = [{"op": "marker_add", "marker": {"id": "b", "t_s": 0.5, "label": "boom"}},
           {"op": "marker_add", "marker": {"id": "a", "t_s": 0.2, "label": "start"}},
           {"op": "marker_add", "marker": {"id": "c", "t_s": 99.0, "label": "late"}},
           {"op": "marker_update", "marker": {"id": "b", "label": "big boom"}},
           {"op": "marker_update", "marker": {"id": "a", "t_s": 0.7}},
           {"op": "marker_delete", "id": "c"}]
    tl, markers = apply_ops(base(), ops, strict=True)
    assert markers == [{"id": "b", "t_s": 0.5, "label": "big boom"}, {"id": "a", "t_s": 0.7, "label": "start"}]
    _, markers = apply_ops(base(), ops[:3])
    assert markers[-1] == {"id": "c", "t_s": 1.0, "label": "late"}  # clamped to the duration


def test_marker_references_are_checked_only_when_strict():
    dangling = [{"op": "marker_update", "marker": {"id": "x", "label": "?"}}, {"op": "marker_delete", "id": "y"}]
    assert apply_ops(base(), dangling)[1] == []
    with pytest.raises(ParameterError, match="no marker with id 'x'"):
        apply_ops(base(), dangling[:1], strict=True)
    dup = [{"op": "marker_add", "marker": {"id": "m", "t_s": 0.1}}] * 2
    with pytest.raises(ParameterError, match="already exists"):
        apply_ops(base(), dup, strict=True)
    assert apply_ops(base(), dup)[1] == [{"id": "m", "t_s": 0.1, "label": ""}]


def test_import_replaces_tracks_with_lengths_fitted():
    other = Timeline.empty(4)
    other.vibration[:] = 0.9
    other.temperature_c[:] = 50.0
    other.fans[:, 0, 0] = 1.0
    tl, _ = apply_ops(base(), [{"op": "import", "timeline": other.to_dict()}])
    np.testing.assert_allclose(tl.vibration[:4], 0.9, rtol=1e-6)
    np.testing.assert_allclose(tl.vibration[4:], 0.0)
    np.testing.assert_allclose(tl.temperature_c, [50] * 4 + [TEMP_NEUTRAL_C] * 6)
    assert tl.fans[:4, 0, 0].tolist() == [1.0] * 4 and tl.fans[4:].max() == 0.0
    np.testing.assert_allclose(tl.features["loudness"], np.linspace(0, 1, N), rtol=1e-6)  # features stay
    longer = Timeline.empty(15)
    longer.vibration[:] = 0.2
    tl, _ = apply_ops(base(), [{"op": "import", "timeline": longer.to_dict()}])
    assert tl.n_ticks == N and tl.vibration.shape == (N, 9)


def test_ops_compose_in_order_and_input_is_untouched():
    gen = base()
    before = (gen.vibration.copy(), gen.temperature_c.copy(), gen.fans.copy())
    tl, _ = apply_ops(gen, [{"op": "set", "lanes": ["A1"], "t0": 0, "t1": 10, "value": 0.2},
                            {"op": "scale", "lanes": ["A1"], "t0": 0, "t1": 5, "factor": 2}])
    np.testing.assert_allclose(vib(tl, "A1"), [0.4] * 5 + [0.2] * 5, rtol=1e-6)
    for a, b in zip(before, (gen.vibration, gen.temperature_c, gen.fans)):
        np.testing.assert_array_equal(a, b)


def test_range_past_the_end_is_cut_but_refused_when_strict():
    tl, _ = apply_ops(base(), [{"op": "set", "lanes": ["A1"], "t0": 20, "t1": 30, "value": 1.0}])
    np.testing.assert_allclose(vib(tl, "A1"), 0.5)
    with pytest.raises(ParameterError, match="'t0' \\(20\\) lies past the end"):
        apply_ops(base(), [{"op": "set", "lanes": ["A1"], "t0": 20, "t1": 30, "value": 1.0}], strict=True)


@pytest.mark.parametrize("op, message", [
    ({"op": "explode"}, "field 'op' must be one of"),
    ("set", "must be a JSON object"),
    ({"op": "set", "lanes": ["A1"], "t0": 0, "t1": 2}, "field 'value' is required"),
    ({"op": "set", "lanes": ["A1"], "t0": 0, "t1": 2, "value": 1, "colour": 3}, "unknown field 'colour'"),
    ({"op": "set", "lanes": ["A10"], "t0": 0, "t1": 2, "value": 1}, "field 'lanes' has unknown lane 'A10'"),
    ({"op": "set", "lanes": [], "t0": 0, "t1": 2, "value": 1}, "field 'lanes' must be a non-empty list"),
    ({"op": "set", "lanes": ["A1"], "t0": 3, "t1": 3, "value": 1}, "field 't1' \\(3\\) must be greater"),
    ({"op": "set", "lanes": ["A1"], "t0": -1, "t1": 3, "value": 1}, "field 't0' must lie in"),
    ({"op": "set", "lanes": ["A1"], "t0": 1.5, "t1": 3, "value": 1}, "field 't0' must be an integer"),
    ({"op": "set", "lanes": ["A1"], "t0": True, "t1": 3, "value": 1}, "field 't0' must be an integer"),
    ({"op": "set", "lanes": ["A1"], "t0": 0, "t1": 3, "value": math.nan}, "field 'value' must be a finite"),
    ({"op": "set", "lanes": ["A1"], "t0": 0, "t1": 3, "value": "0.5"}, "field 'value' must be a finite"),
    ({"op": "scale", "lanes": ["A1"], "t0": 0, "t1": 3, "factor": -2}, "field 'factor' must be >= 0"),
    ({"op": "paste", "t0": 0, "values": {"fans": [[0.1] * 17]}}, "field 'values.fans' has shape"),
    ({"op": "paste", "t0": 0, "values": {"A1": [0.1, math.inf]}}, "field 'values.A1' holds a non-finite"),
    ({"op": "paste", "t0": 0, "values": {"seat": [0.1]}}, "field 'values' has unknown lane 'seat'"),
    ({"op": "pencil", "lane": "A1", "t0": 0, "values": []}, "field 'values' must be a non-empty list"),
    ({"op": "pencil", "lane": "A1", "t0": 0, "values": [[1, 2]]}, "field 'values' has shape"),
    ({"op": "temp_points", "t0": 0, "t1": 5, "points": [[0, 30, 1]]}, "field 'points' has shape"),
    ({"op": "marker_add", "marker": {"id": "m"}}, "field 'marker.t_s' is required"),
    ({"op": "marker_add", "marker": {"id": "", "t_s": 1}}, "field 'marker.id' must be a string"),
    ({"op": "marker_add", "marker": {"id": "m", "t_s": 1, "colour": "red"}}, "field 'marker.colour' is unknown"),
    ({"op": "marker_update", "marker": {"id": "m"}}, "give 'marker.t_s' or 'marker.label'"),
    ({"op": "marker_delete", "id": 3}, "field 'id' must be a string"),
    ({"op": "import", "timeline": {"format": "other"}}, "field 'timeline': not an autohaptics timeline"),
])
def test_invalid_ops_are_refused_naming_the_field(op, message):
    with pytest.raises(ParameterError, match=message):
        validate_op(op)


def test_validate_op_normalises_ticks_and_values():
    op = validate_op({"op": "set", "lanes": ["A1", "A1", "fans"], "t0": 2.0, "t1": 4, "value": 1})
    assert op == {"op": "set", "lanes": ["A1", "fans"], "t0": 2, "t1": 4, "value": 1.0}
    assert isinstance(op["t0"], int)
    assert validate_op({"op": "temp_points", "t0": 0, "t1": 3, "points": [[2, 40], [0, 30]]})["points"] == \
        [[0.0, 30.0], [2.0, 40.0]]


# ----------------------------------------------------------------------- property
_finite = st.floats(min_value=-1e6, max_value=1e6, allow_nan=False)
_tick = st.integers(min_value=0, max_value=2 * N)


@st.composite
def _range(draw):
    t0 = draw(_tick)
    return t0, draw(st.integers(min_value=t0 + 1, max_value=t0 + 2 * N))


@st.composite
def valid_op(draw):
    name = draw(st.sampled_from([o for o in OPS if o not in ("import", "params", "group")]))
    lanes = draw(st.lists(st.sampled_from(LANES), min_size=1, max_size=4))
    t0, t1 = draw(_range())
    if name in ("set", "scale", "clear", "fade_in", "fade_out"):
        op = {"op": name, "lanes": lanes, "t0": t0, "t1": t1}
        if name == "set":
            op["value"] = draw(_finite)
        if name == "scale":
            op["factor"] = draw(st.floats(min_value=0, max_value=1e6))
        return op
    length = draw(st.integers(min_value=1, max_value=N))
    if name == "paste":
        values = {}
        for lane in lanes:
            if lane == "fans":
                values[lane] = np.full((length, FAN_ROWS, FAN_COLS), draw(_finite)).tolist()
            else:
                values[lane] = draw(st.lists(_finite, min_size=1, max_size=N))
        return {"op": name, "t0": t0, "values": values}
    if name == "pencil":
        return {"op": name, "lane": lanes[0], "t0": t0, "values": draw(st.lists(_finite, min_size=1, max_size=N))}
    if name == "temp_points":
        pts = draw(st.lists(st.tuples(_finite, _finite), min_size=1, max_size=5))
        return {"op": name, "t0": t0, "t1": t1, "points": [list(p) for p in pts]}
    if name == "shot_split":  # boundary ops change the shot list, no track
        return {"op": name, "t": t0}
    if name == "shot_merge":
        return {"op": name, "shots": [t0, t1]}
    mid = draw(st.sampled_from(["m1", "m2", "m3"]))
    if name == "marker_add":
        return {"op": name, "marker": {"id": mid, "t_s": draw(st.floats(0, 1e4)), "label": "x"}}
    if name == "marker_update":
        return {"op": name, "marker": {"id": mid, "label": draw(st.text(max_size=5))}}
    return {"op": name, "id": mid}


@settings(max_examples=150, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(st.lists(valid_op(), max_size=12))
def test_any_sequence_of_valid_ops_gives_a_valid_timeline(ops):
    gen = base()
    tl, markers = apply_ops(gen, ops)
    lo, hi = tl.temp_range
    for arr in (tl.vibration, tl.temperature_c, tl.fans):
        assert np.isfinite(arr).all()
    assert tl.vibration.min() >= 0 and tl.vibration.max() <= 1
    assert tl.fans.min() >= 0 and tl.fans.max() <= 1
    assert tl.temperature_c.min() >= lo and tl.temperature_c.max() <= hi
    assert tl.vibration.shape == (N, 9) and tl.fans.shape == (N, FAN_ROWS, FAN_COLS)
    assert all(0 <= m["t_s"] <= tl.duration_s for m in markers)
    assert len({m["id"] for m in markers}) == len(markers)
    Timeline.from_json(tl.to_json())  # the composed timeline is a valid file
    # normalising is idempotent: stored ops recompose identically
    again, _ = apply_ops(gen, [validate_op(op) for op in ops])
    np.testing.assert_array_equal(again.vibration, tl.vibration)


def test_range_ops_on_a_region_of_fan_cells_leave_the_other_fans_alone():
    gen = base()
    cells = [[0, 0], [4, 8], [4, 9], [8, 16]]
    mask = np.zeros((FAN_ROWS, FAN_COLS), dtype=bool)
    for r, c in cells:
        mask[r, c] = True
    for op, inside in (({"op": "set", "value": 0.9}, 0.9), ({"op": "scale", "factor": 0.5}, 0.25),
                       ({"op": "clear"}, 0.0)):
        tl, _ = apply_ops(gen, [{**op, "lanes": ["fans"], "t0": 2, "t1": 5, "cells": cells[::-1]}])
        np.testing.assert_allclose(tl.fans[2:5][:, mask], inside)
        np.testing.assert_allclose(tl.fans[2:5][:, ~mask], 0.5)
        np.testing.assert_allclose(tl.fans[:2], 0.5)
        np.testing.assert_allclose(tl.fans[5:], 0.5)
        np.testing.assert_allclose(tl.vibration, gen.vibration)
    tl, _ = apply_ops(gen, [{"op": "fade_in", "lanes": ["fans"], "t0": 0, "t1": N, "cells": [[4, 8]]}])
    np.testing.assert_allclose(tl.fans[:, 4, 8], 0.5 * np.arange(N) / (N - 1))
    assert tl.fans[:, 4, 7].tolist() == [0.5] * N
    assert validate_op({"op": "clear", "lanes": ["fans"], "t0": 0, "t1": 1, "cells": [[1, 2], [0, 3], [1, 2]]})[
        "cells"] == [[0, 3], [1, 2]]


@pytest.mark.parametrize("op, message", [
    ({"op": "set", "lanes": ["fans", "A1"], "t0": 0, "t1": 2, "value": 1, "cells": [[0, 0]]}, "must be"),
    ({"op": "set", "lanes": ["fans"], "t0": 0, "t1": 2, "value": 1, "cells": []}, "non-empty list"),
    ({"op": "set", "lanes": ["fans"], "t0": 0, "t1": 2, "value": 1, "cells": [[9, 0]]}, "row 0..8"),
    ({"op": "set", "lanes": ["fans"], "t0": 0, "t1": 2, "value": 1, "cells": [[0, 1.5]]}, "each cell"),
    ({"op": "paste", "t0": 0, "values": {"fans": [[[0] * 17] * 9]}, "cells": [[0, 0]]}, "unknown field 'cells'"),
])
def test_a_bad_fan_region_is_refused_in_one_sentence(op, message):
    with pytest.raises(ParameterError, match=message):
        validate_op(op)


def test_a_params_op_changes_no_track_and_is_checked():
    doc = {"preset": "balanced", "mode": "audio", "thresholds": {"loudness": 0.5}, "overrides": {}}
    op = {"op": "params", "from": doc, "to": {**doc, "thresholds": {"loudness": 0.3}}}
    assert validate_op(op) == op
    from autohaptics.timeline import Timeline
    base = Timeline.empty(20)
    base.vibration[:] = 0.5
    out, markers = apply_ops(base, [op])
    assert np.array_equal(out.vibration, base.vibration) and markers == []
    with pytest.raises(ParameterError, match="field 'to' must be an object with exactly the fields"):
        validate_op({"op": "params", "from": doc, "to": {"preset": "balanced"}})
    with pytest.raises(ParameterError, match="'thresholds' and 'overrides' must be objects"):
        validate_op({"op": "params", "from": doc, "to": {**doc, "thresholds": [0.5]}})
