"""Known answers for the "events" vibration rule under a lossy re-encode of the same sound: its
onsets stay put (docs/GUIDE.md "Vibration"; docs/BENCHMARKS.md "Onsets under lossy sound"), and
properties of the pieces that keep them (:func:`trailing_median`, :func:`bridge_pauses`)."""

import numpy as np
import pytest
from hypothesis import given, settings, strategies as st
from hypothesis.extra import numpy as hnp

from autohaptics import intensity as it
from autohaptics.errors import ParameterError
from autohaptics.intensity.novelty import trailing_median
from autohaptics.intensity.rule import bridge_pauses
from autohaptics.metrics import onset_scores
from autohaptics.params import resolve_params
from autohaptics.pipeline.generate import generate
from autohaptics.testing import Noise, Scene, Segment, Tone, write_scene
from autohaptics.testing.reencode import reencode
from autohaptics.testing.scenes import impact

DURATION_S = 30.0
PREVIOUS = {"intensity.normaliser": "max", "intensity.smoothing_s": 0.0}  # the rule before issue 31


def hits_near_the_gate() -> Scene:
    """A quiet score, a hit every 1.2 s from -36 to -24 dBFS in 0.5 dB steps (some near the loudness
    gate) and one 4 ms click at -6 dBFS at 12.5 s: the film's loudest frame, which a lossy codec
    spreads and so moves (at -12 dBFS, under the loudest hits' frames, it moved the gate only
    while the decoder spliced the Opus stream's rounded timestamps)."""
    audio = [Tone(0.0, DURATION_S, f, level_dbfs=-34.0, ramp_s=0.05) for f in (130.81, 261.63, 329.63, 392.0)]
    for j, t in enumerate(np.arange(1.0, DURATION_S - 1.0, 1.2)):
        audio += impact(float(t), level_dbfs=-36.0 + 0.5 * j, seed=j + 1)
    audio.append(Noise(12.5, 12.504, level_dbfs=-6.0, colour="white", seed=99, ramp_s=0.0005))
    return Scene(DURATION_S, [Segment(0.0, DURATION_S, (90, 90, 90))], [], audio)


@pytest.fixture(scope="module")
def clips(tmp_path_factory):
    """The scene (H.264 + AAC) and its sound again as Opus at 48, 64 and 96 kbit/s, picture copied."""
    root = tmp_path_factory.mktemp("codec")
    src = write_scene(root / "hits.mp4", hits_near_the_gate(), width=160, height=90, fps=25)
    out = {"src": src}
    for rate in (48000, 64000, 96000):
        out[rate] = reencode(src, root / f"opus{rate}.mkv", video_codec="copy", audio_codec="libopus",
                             audio_layout="stereo", audio_bit_rate=rate)
    return out


def _onset_f1(a, b, overrides) -> tuple[float, int]:
    params, _ = resolve_params("balanced", {"mode": "audio", "tracks": ["vibration"], **overrides})
    s = onset_scores(generate(a, params).vibration, generate(b, params).vibration)
    return s["f1"], s["ref_onsets"]


@pytest.mark.parametrize("rate", [48000, 64000, 96000])
def test_onsets_stay_put_under_a_lossy_sound_re_encode(clips, rate):
    f1, onsets = _onset_f1(clips["src"], clips[rate], {})
    assert onsets >= 6 and f1 >= 0.95, (f1, onsets)


def test_the_previous_rule_loses_hits_there(clips):
    """The scene tells the rules apart: the film's loudest frame set the previous gate's reference
    (at 96 kbit/s the novelty's floor keeps the previous rule's hits too)."""
    f1, _ = _onset_f1(clips["src"], clips[48000], PREVIOUS)
    assert f1 < 0.95


def test_smoothing_is_validated_and_off_under_the_thesis_rule():
    with pytest.raises(ParameterError, match="smoothing_s"):
        it.IntensityParams(smoothing_s=0.6)
    assert it.IntensityParams().smoothing_frames() == 5
    assert it.IntensityParams(rule="thesis").smoothing_frames() == 0
    assert it.IntensityParams(smoothing_s=0.0).smoothing_frames() == 0


def test_bridge_pauses_fills_short_pauses_between_runs_only():
    on = np.array([0, 1, 1, 0, 0, 1, 0, 0, 0, 0, 1, 0], bool)
    assert bridge_pauses(on, 2).astype(int).tolist() == [0, 1, 1, 1, 1, 1, 0, 0, 0, 0, 1, 0]
    assert bridge_pauses(on, 4).astype(int).tolist() == [0, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 0]
    assert (bridge_pauses(on, 0) == on).all()


@given(hnp.arrays(np.float64, st.integers(1, 60), elements=st.floats(0, 1e3)), st.integers(1, 9))
@settings(max_examples=60, deadline=None)
def test_trailing_median_stays_within_its_window(v, n):
    out = trailing_median(v, n)
    padded = np.concatenate([np.full(n - 1, np.median(v[:n])), v])
    for t in range(v.size):
        window = padded[t:t + n]
        assert window.min() <= out[t] <= window.max()
    if n == 1:
        assert (out == v).all()


def test_trailing_median_drops_a_peak_in_the_first_frames_too():
    """A codec's start-up transient (one frame) goes as a peak later in the curve does."""
    v = np.array([0.8, 0.45, 0.43, 0.43, 0.44, 0.43, 0.43, 2.0, 0.43, 0.43, 0.44, 0.43])
    out = trailing_median(v, 5)
    assert out.max() <= 0.45
    assert np.allclose(trailing_median(np.full(8, 3.0), 5), 3.0)
