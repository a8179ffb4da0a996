"""The ``group`` edit op (several track ops as one) and ``paste`` fitted to ``[t0, t1)``: a group
equals its sub-operations applied one by one, outputs stay finite and in range, a bad sub-op is
refused naming ``ops[i]``; the fit rule with known answers and its properties."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from autohaptics.errors import ParameterError
from autohaptics.layout import FAN_COLS, FAN_ROWS
from autohaptics.timeline.edit_ops import GROUP_OPS, fitted
from autohaptics.timeline.edits import apply_ops, validate_op
from autohaptics.timeline import Timeline

N = 30


def base(n: int = N) -> Timeline:
    tl = Timeline.empty(n, generator={"params": {"temp_low": 30.0, "temp_high": 55.0}})
    tl.vibration[:] = np.linspace(0, 1, n)[:, None]
    tl.temperature_c[:] = 40.0
    tl.fans[:] = 0.5
    return tl.validate()


def test_paste_with_t1_stretches_and_shrinks_by_area():
    tl, _ = apply_ops(base(), [
        {"op": "paste", "t0": 0, "t1": 4, "values": {"A1": [0.0, 1.0]}},           # stretched x2: held
        {"op": "paste", "t0": 4, "t1": 6, "values": {"A2": [0.2, 0.4, 0.6, 0.8]}},  # shrunk x2: means
        {"op": "paste", "t0": 6, "t1": 9, "values": {"A3": [0.0, 0.9]}},           # 2 -> 3 ticks
        {"op": "paste", "t0": 10, "t1": 15, "values": {"temperature": [50.0]}},    # one value fills the range
        {"op": "paste", "t0": 28, "t1": 40, "values": {"A4": [1.0] * 6}},         # cut at the end of the film
    ])
    np.testing.assert_allclose(tl.vibration[0:4, 0], [0, 0, 1, 1])
    np.testing.assert_allclose(tl.vibration[4:6, 1], [0.3, 0.7], rtol=1e-6)
    np.testing.assert_allclose(tl.vibration[6:9, 2], [0.0, 0.45, 0.9], rtol=1e-6)
    np.testing.assert_allclose(tl.temperature_c[10:15], 50.0)
    assert tl.temperature_c[15] == 40.0
    np.testing.assert_allclose(tl.vibration[28:, 3], 1.0)


def test_paste_with_t1_fits_fans_and_without_it_writes_as_given():
    fans = np.zeros((2, FAN_ROWS, FAN_COLS))
    fans[1, 4, 8] = 1.0
    tl, _ = apply_ops(base(), [{"op": "paste", "t0": 2, "t1": 6, "values": {"fans": fans.tolist()}}])
    np.testing.assert_allclose(tl.fans[2:6, 4, 8], [0, 0, 1, 1])
    np.testing.assert_allclose(tl.fans[2:6, 0, 0], 0)
    np.testing.assert_allclose(tl.fans[6:, 0, 0], 0.5)
    plain, _ = apply_ops(base(), [{"op": "paste", "t0": 2, "values": {"A1": [1.0, 1.0]}}])
    np.testing.assert_allclose(plain.vibration[2:5, 0], [1, 1, base().vibration[4, 0]])


@settings(max_examples=200, deadline=None)
@given(st.lists(st.floats(-50, 50), min_size=1, max_size=40), st.integers(1, 90))
def test_fitting_keeps_the_mean_and_the_range(values, length):
    src = np.array(values)
    out = fitted(src, length)
    assert out.shape == (length,) and np.isfinite(out).all()
    assert src.min() - 1e-9 <= out.min() and out.max() <= src.max() + 1e-9
    assert out.mean() == pytest.approx(src.mean(), abs=1e-9)
    np.testing.assert_allclose(fitted(src, length, 3), out[:3])


# ----------------------------------------------------------------------- groups
_value = st.floats(min_value=-100, max_value=100, allow_nan=False)
_lanes = st.lists(st.sampled_from(["A1", "A5", "A9", "temperature", "fans"]), min_size=1, max_size=3)


@st.composite
def sub_op(draw):
    name = draw(st.sampled_from(GROUP_OPS))
    t0 = draw(st.integers(0, N + 5))
    t1 = draw(st.integers(t0 + 1, t0 + N))
    lanes = draw(_lanes)
    if name in ("set", "scale", "clear", "fade_in", "fade_out"):
        op = {"op": name, "lanes": lanes, "t0": t0, "t1": t1}
        if name == "set":
            op["value"] = draw(_value)
        if name == "scale":
            op["factor"] = draw(st.floats(0, 10))
        if lanes == ["fans"] and draw(st.booleans()):
            op["cells"] = [[draw(st.integers(0, FAN_ROWS - 1)), draw(st.integers(0, FAN_COLS - 1))]]
        return op
    n = draw(st.integers(1, 12))
    if name == "paste":
        values = {lane: (np.full((n, FAN_ROWS, FAN_COLS), draw(_value)).tolist() if lane == "fans"
                         else draw(st.lists(_value, min_size=n, max_size=n))) for lane in lanes}
        op = {"op": name, "t0": t0, "values": values}
        if draw(st.booleans()):
            op["t1"] = t1
        return op
    if name == "pencil":
        return {"op": name, "lane": lanes[0], "t0": t0, "values": draw(st.lists(_value, min_size=1, max_size=n))}
    return {"op": name, "t0": t0, "t1": t1, "points": [[draw(st.floats(0, N)), draw(_value)]]}


@settings(max_examples=150, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(st.lists(sub_op(), min_size=1, max_size=8), st.lists(sub_op(), max_size=3))
def test_a_group_equals_its_sub_operations_one_by_one(subs, before):
    gen = base()
    one, _ = apply_ops(gen, [*before, {"op": "group", "ops": subs}])
    each, _ = apply_ops(gen, [*before, *subs])
    for track in ("vibration", "temperature_c", "fans"):
        np.testing.assert_array_equal(getattr(one, track), getattr(each, track))
    lo, hi = one.temp_range
    assert np.isfinite(one.vibration).all() and np.isfinite(one.fans).all() and np.isfinite(one.temperature_c).all()
    assert 0 <= one.vibration.min() and one.vibration.max() <= 1 and 0 <= one.fans.min() and one.fans.max() <= 1
    assert lo <= one.temperature_c.min() and one.temperature_c.max() <= hi
    stored = validate_op({"op": "group", "ops": subs})  # the stored form composes the same
    again, _ = apply_ops(gen, [*before, stored])
    np.testing.assert_array_equal(again.fans, one.fans)
    assert validate_op(stored) == stored


SET = {"op": "set", "lanes": ["A1"], "t0": 0, "t1": 3, "value": 0.5}


@pytest.mark.parametrize("ops, words", [
    ([], "field 'ops' must be a list of 1..10000 operations"),
    ("set", "field 'ops' must be a list"),
    ([SET] * 10_001, "1..10000"),
    ([SET, {"op": "group", "ops": [SET]}], "ops[1] must be one of set"),
    ([SET, SET, {"op": "shot_split", "t": 4}], "ops[2] must be one of"),
    ([{"op": "marker_add", "marker": {"id": "m", "t_s": 0}}], "ops[0] must be one of"),
    ([{"op": "params", "from": {}, "to": {}}], "ops[0] must be one of"),
    ([{"op": "import", "timeline": {}}], "ops[0] must be one of"),
    ([SET, 3], "ops[1] must be one of"),
    ([SET, {**SET, "value": "loud"}], "ops[1] (set): field 'value' must be a finite number"),
    ([{**SET, "t1": 0}], "ops[0] (set): field 't1' (0) must be greater than t0"),
    ([SET, {"op": "paste", "t0": 5, "t1": 5, "values": {"A1": [1]}}], "ops[1] (paste): field 't1' (5)"),
    ([SET, {"op": "scale", "lanes": ["seat"], "t0": 0, "t1": 2, "factor": 1}], "ops[1] (scale): field 'lanes'"),
])
def test_bad_sub_operations_are_refused_naming_their_index(ops, words):
    with pytest.raises(ParameterError) as err:
        validate_op({"op": "group", "ops": ops})
    text = str(err.value)
    assert text.startswith("op 'group': ") and words in text and text.count(". ") == 0


def test_a_sub_operation_past_the_end_is_refused_when_submitted():
    with pytest.raises(ParameterError, match=r"ops\[1\] \(clear\): field 't0' \(40\) lies past the end"):
        apply_ops(base(), [{"op": "group", "ops": [SET, {"op": "clear", "lanes": ["A1"], "t0": 40, "t1": 41}]}],
                  strict=True)
    tl, _ = apply_ops(base(), [{"op": "group", "ops": [SET, {"op": "clear", "lanes": ["A1"], "t0": 40, "t1": 41}]}])
    np.testing.assert_allclose(tl.vibration[:3, 0], 0.5)  # stored history composes: past the end is nothing
