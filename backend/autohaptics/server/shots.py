"""A project's shots for the routes: the analysis's boundaries with the boundary operations of the
applied edits (:mod:`autohaptics.shots.model`), each shot summarised from the composed timeline
and the analysis (:mod:`autohaptics.shots.summary`). The boundaries come from the analysis alone,
so a threshold change or an edit changes the summaries, never the boundaries."""

from __future__ import annotations

import threading
from collections import OrderedDict

import numpy as np

from autohaptics.server.posters import poster_tick
from autohaptics.server.store import Conflict, NotFound
from autohaptics.shots.model import KIND_NAMES, SHOT_OPS, apply_shot_ops, base_starts, shot_arrays
from autohaptics.shots.similar import nearest, shot_features
from autohaptics.shots.summary import summarise

_lock = threading.Lock()
_answers: OrderedDict[tuple, dict] = OrderedDict()  # (project, revision) -> answer: every change bumps the revision
_features: OrderedDict[str, tuple] = OrderedDict()  # project -> (analysis, shot starts, features)
_KEEP = 8


def check_op(analysis, applied_ops: list[dict], op: dict, n_ticks: int) -> None:
    """Refuse (ParameterError, one sentence) a boundary operation that does not fit the shots
    after ``applied_ops``: a split outside a shot, an unknown shot, a merge of non-neighbours."""
    if op.get("op") not in SHOT_OPS:
        return
    if analysis is None:
        raise Conflict("the project has no analysis yet; its shots come from the analysis")
    starts = apply_shot_ops(base_starts(analysis.shots, n_ticks), applied_ops, n_ticks)
    apply_shot_ops(starts, [op], n_ticks, strict=True)


def shot_list(pid: str, analysis, composed) -> dict:
    """``{revision, n_ticks, tick_s, shots: [...]}`` (docs/API.md, "Shots"); kept per revision."""
    if analysis is None:
        raise Conflict("the project has no analysis yet; its shots come from the analysis")
    key = (pid, composed.revision)
    with _lock:
        hit = _answers.get(key)
        if hit is not None:
            return hit
    answer = _build(pid, analysis, composed)
    with _lock:
        _answers[key] = answer
        while len(_answers) > _KEEP:
            _answers.popitem(last=False)
    return answer


def poster_ticks(analysis, composed) -> list[int]:
    """The poster tick of every shot of the composed timeline's shot list, in film order."""
    t0, t1 = _bounds(analysis, composed)[:2]
    return [poster_tick(a, b) for a, b in zip(t0.tolist(), t1.tolist())]


def _bounds(analysis, composed) -> tuple:
    """(t0, t1, kind codes) of the shots at the composed revision."""
    n = int(composed.timeline.n_ticks)
    return shot_arrays(apply_shot_ops(base_starts(analysis.shots, n), composed.ops, n), n)


def similar_shots(pid: str, analysis, composed, shot_id: int) -> dict:
    """``{revision, shot, similar: [{id, distance}]}``: every other shot of the list at the composed
    revision by ascending distance (:mod:`autohaptics.shots.similar`)."""
    t0, features = features_of(pid, analysis, composed)
    i = int(np.searchsorted(t0, shot_id))
    if i >= t0.size or t0[i] != shot_id:
        raise NotFound(f"no shot starts at tick {shot_id} (shot ids are their first ticks)")
    order, d = nearest(features, i)
    ids, dist = t0[order].tolist(), np.round(d, 4).tolist()
    return {"revision": composed.revision, "shot": int(shot_id),
            "similar": [{"id": a, "distance": b} for a, b in zip(ids, dist)]}


def features_of(pid: str, analysis, composed) -> tuple[np.ndarray, np.ndarray]:
    """(shot starts, features) of the shots at the composed revision; kept while the analysis and the
    boundaries are the same (a track edit or a threshold change keeps them)."""
    if analysis is None:
        raise Conflict("the project has no analysis yet; its shots come from the analysis")
    n = int(composed.timeline.n_ticks)
    t0, t1, _ = _bounds(analysis, composed)
    key = t0.tobytes()
    with _lock:
        hit = _features.get(pid)
    if hit is not None and hit[0] is analysis and hit[1] == key:
        return t0, hit[2]
    v = analysis.video if analysis.video is not None and analysis.n_ticks == n else None
    features = shot_features(t0, t1, mean_rgb=v.mean_rgb if v is not None and v.mean_rgb.any() else None,
                             motion=v.motion if v is not None else None,
                             loudness=(analysis.audio or {}).get("loudness") if analysis.n_ticks == n else None,
                             beta=v.beta if v is not None else None,
                             saliency_mask=v.saliency_mask if v is not None else None)
    with _lock:
        _features[pid] = (analysis, key, features)
        _features.move_to_end(pid)
        while len(_features) > _KEEP:
            _features.popitem(last=False)
    return t0, features


def _build(pid: str, analysis, composed) -> dict:
    tl = composed.timeline
    n = int(tl.n_ticks)
    t0, t1, kinds = _bounds(analysis, composed)
    v = analysis.video if analysis.video is not None and analysis.n_ticks == n else None
    audio = analysis.audio or {}
    s = summarise(t0, t1, vibration=tl.vibration, temperature_c=tl.temperature_c, fans=tl.fans,
                  loudness=audio.get("loudness") if analysis.n_ticks == n else None,
                  mean_rgb=v.mean_rgb if v is not None and v.mean_rgb.any() else None,
                  motion=v.motion if v is not None else None)

    def col(name, digits):
        values = s[name]
        return [None] * t0.size if values is None else np.round(values, digits).tolist()

    colour = [None] * t0.size if s["colour"] is None else [
        "#%02x%02x%02x" % tuple(int(c) for c in np.clip(np.rint(rgb), 0, 255)) for rgb in s["colour"]]
    rows = zip(t0.tolist(), t1.tolist(), kinds.tolist(), col("vibration_mean", 4), col("vibration_peak", 4),
               col("temperature_mean_c", 3), col("fans_share", 4), col("loudness_sone", 4), colour,
               col("motion", 5))
    shots = [{"id": a, "t0": a, "t1": b, "kind": KIND_NAMES[k], "vibration_mean": vm, "vibration_peak": vp,
              "temperature_mean_c": tm, "fans_share": fs, "loudness_sone": ld, "colour": c, "motion": mo,
              "poster_url": f"/api/projects/{pid}/posters/{poster_tick(a, b)}.jpg"}
             for a, b, k, vm, vp, tm, fs, ld, c, mo in rows]
    return {"revision": composed.revision, "n_ticks": n, "tick_s": float(tl.tick_s), "shots": shots}
