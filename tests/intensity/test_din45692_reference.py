"""DIN 45692:2009 sharpness on the standard's 41 test signals (../shared/reference, read in place;
skipped with a message when absent).

Tolerance max(5 %, 0.05 acum). Calibration p = x * 0.6334 Pa (the DIN calibration tone: all
signals then measure ~4 sone, as DIN states; see the reference README). Checked twice: the
stationary path (stationary N'(z) -> sharpness) and the product path (the 20 ms frame sharpness
of the streaming features with the default fast loudness, median over the steady part).
"""

from __future__ import annotations

import csv
from pathlib import Path

import numpy as np
import scipy.io.wavfile

from autohaptics.intensity import features as af
from autohaptics.intensity import loudness as L
from autohaptics.intensity import sharpness as S

CAL = 0.6334


def _rows(psycho_dir: Path) -> list[dict]:
    with open(psycho_dir / "din45692" / "reference_values.csv", newline="") as fh:
        return list(csv.DictReader(fh))


def _pressure(psycho_dir: Path, row: dict) -> np.ndarray:
    sr, x = scipy.io.wavfile.read(psycho_dir / "din45692" / row["signal_file"])
    assert sr == 48_000
    return x.astype(np.float64) / 32767.0 * CAL


def _tolerance(ref: float) -> float:
    return max(0.05 * ref, 0.05)


def test_all_41_signals_are_present(psycho_dir):
    rows = _rows(psycho_dir)
    assert len(rows) == 41
    assert sum("narrowband" in r["kind"] for r in rows) == 21


def test_stationary_sharpness_of_all_signals(psycho_dir):
    misses = []
    for row in _rows(psycho_dir):
        ref = float(row["S_ref_acum"])
        total, spec = L.loudness_stationary(_pressure(psycho_dir, row), skip_s=0.5)
        value = float(S.sharpness(specific=spec))
        assert 3.5 < total < 5.0  # DIN: every test signal has a loudness of about 4 sone
        if abs(value - ref) > _tolerance(ref):
            misses.append((row["signal_file"], round(value, 3), ref))
    assert not misses, f"outside max(5 %, 0.05 acum): {misses}"


def test_streaming_frame_sharpness_of_all_signals(psycho_dir):
    params = af.AudioFeatureParams()  # default: fast loudness, film calibration (re-scaled below)
    misses = []
    for row in _rows(psycho_dir):
        ref = float(row["S_ref_acum"])
        x = _pressure(psycho_dir, row) / params.pa_per_unit  # back to digital units of the film scale
        feats = af.compute_audio_features([x.astype(np.float32)], params=params)
        value = float(np.median(feats.sharpness[feats.t_s >= 0.5]))
        if abs(value - ref) > _tolerance(ref):
            misses.append((row["signal_file"], round(value, 3), ref))
    assert not misses, f"outside max(5 %, 0.05 acum): {misses}"
