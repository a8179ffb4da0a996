"""The acceptance of a film's variant against its clean encode (issue 31): the tracks are a
property of the film, not of its encoding or its bars."""

from __future__ import annotations

from autohaptics.metrics import compare_timelines


def assert_same_tracks(ref, test, *, min_fan_ticks: int = 10) -> dict:
    """Fan-tick F1 >= 0.9, tolerant fan IoU >= 0.8, vibration onset F1 >= 0.9 and temperature
    MAE <= 0.5 C between timelines ``ref`` and ``test``, whose reference blows on at least
    ``min_fan_ticks`` ticks (else the fan figures prove nothing). Returns the report."""
    r = compare_timelines(ref, test)
    fans = r["fans"]
    assert fans["ref_ticks_on"] >= min_fan_ticks, f"the reference must blow on {min_fan_ticks} ticks or more: {fans}"
    assert fans["ticks_f1"] >= 0.9, fans
    assert fans["iou_tolerant"] >= 0.8, fans
    assert r["vibration"]["onsets"]["f1"] >= 0.9, r["vibration"]["onsets"]
    assert r["temperature"]["mae_c"] <= 0.5, r["temperature"]
    return r
