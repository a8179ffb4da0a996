"""records.param / Record: every declared bound is checked, with a message naming group.field."""

from __future__ import annotations

import math

import pytest

from autohaptics.errors import ParameterError
from autohaptics.fusion import SaliencyParams
from autohaptics.params import GenerateParams, VideoParams
from autohaptics.airflow.depth import DepthParams
from autohaptics.airflow.cuts import CutParams


@pytest.mark.parametrize("make, message", [
    (lambda: SaliencyParams(backend="nope"), "saliency.backend must be one of"),
    (lambda: SaliencyParams(proxy_width=4), "saliency.proxy_width must lie in 8..4096 px, got 4"),
    (lambda: SaliencyParams(proxy_width=64.5), "saliency.proxy_width must be a whole number"),
    (lambda: SaliencyParams(blur=math.nan), "saliency.blur must be a finite number"),
    (lambda: SaliencyParams(motion_weight="x"), "saliency.motion_weight must be a finite number"),
    (lambda: SaliencyParams(onnx_channel_order="rbg"), "saliency.onnx_channel_order must be one of"),
    (lambda: SaliencyParams(backend="onnx"), "saliency.backend 'onnx' needs saliency.onnx_model"),
    (lambda: DepthParams(w_detail=-0.1), "depth.w_detail must lie in 0.."),
    (lambda: DepthParams(expansion_full=0.0), "depth.expansion_full must be above 0 1/s"),
    (lambda: DepthParams(w_position=0, w_detail=0, w_expansion=0), "at least one positive cue weight"),
    (lambda: CutParams(hist_threshold=0.0), "cuts.hist_threshold must be above 0"),
    (lambda: VideoParams(stride=True), "video.stride must be a whole number of ticks"),
    (lambda: VideoParams(stride=2, analysis="every"), "needs video.analysis='tick'"),
    (lambda: GenerateParams(mode="loud"), "mode must be one of"),
    (lambda: GenerateParams(lfe_gain_db=30.0), "lfe_gain_db must lie in -40..20 dB"),
])
def test_out_of_bounds_is_a_parameter_error_naming_the_field(make, message):
    with pytest.raises(ParameterError, match=message.replace("(", r"\(").replace(".", r"\.")):
        make()


def test_bounds_are_inclusive_and_none_passes():
    assert SaliencyParams(proxy_width=8, motion_weight=1.0).proxy_width == 8
    assert CutParams(hist_threshold=1.0, corr_threshold=-1.0).corr_threshold == -1.0
    assert DepthParams(onnx_model=None).onnx_model is None
