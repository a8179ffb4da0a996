"""What a derive keeps, handed from one process to another: a generate job's worker derives the
timeline, and the server, which loads the same feature cache from the file the job wrote, would
compute the same picture tracks (the fan track most of all) and intensity decision inputs again
for the first threshold commit after the job. :func:`kept_of` (in the worker) says what its
derives kept; :func:`seed` (in the server) keeps them for the loaded cache, so the next derive
computes neither. A derive from the seeded cache gives the same timeline, bit for bit.
"""

from __future__ import annotations

import importlib
import weakref

import numpy as np

from autohaptics.pipeline.cache import Analysis
from autohaptics.timeline import Timeline

_derive = importlib.import_module("autohaptics.pipeline.derive")  # the package's ``derive`` is the function

_LAYER_ARRAYS = ("temperature_c", "fans")
_LAYER_FEATURES = ("temperature_target_c", "motion", "motion_fw_per_s")


def _picture_arrays(tl: Timeline) -> dict[str, np.ndarray]:
    """The arrays a derive's kept picture entry holds, as ``tl`` (a derived timeline) has them."""
    return {**{name: getattr(tl, name) for name in _LAYER_ARRAYS},
            **{name: tl.features[name] for name in _LAYER_FEATURES if name in tl.features}}


def _audio_ident(audio: dict) -> tuple:
    return tuple((name, id(values)) for name, values in sorted(audio.items()))


def kept_of(analysis: Analysis, layer: Timeline) -> dict:
    """What this process's derives keep of ``analysis``: ``{"inputs": [(key, inputs)], "picture":
    [(key, stats)]}``. A picture entry is included only when ``layer`` (the timeline derived from
    it, as written) holds its arrays bit for bit (no style reshaped them), since the arrays
    themselves do not travel: :func:`seed` takes them from the layer."""
    out: dict[str, list] = {"inputs": [], "picture": []}
    if analysis.audio is not None:
        ident = _audio_ident(analysis.audio)
        with _derive._CURVES_LOCK:
            hit = _derive._CURVES.get(ident)
        if hit is not None and all(ref() is values for ref, (_, values) in zip(hit[0], sorted(analysis.audio.items()))):
            out["inputs"].append((hit[1], hit[2]))
    if analysis.video is not None:
        with _derive._PICTURE_LOCK:
            hit = _derive._PICTURE.get(id(analysis.video))
        shown = _picture_arrays(layer)
        if (hit is not None and hit[0]() is analysis.video and set(hit[2]) == set(shown)
                and all(np.array_equal(hit[2][name], np.asarray(shown[name], np.float32)) for name in shown)):
            out["picture"].append((hit[1], hit[3]))
    return out


def _keep(table: dict, lock, ident, entry: tuple) -> None:
    with lock:
        table[ident] = entry
        while len(table) > _derive._PICTURE_KEPT:
            table.pop(next(iter(table)))


def seed(analysis: Analysis, kept: dict, layer: Timeline | None) -> bool:
    """Keep ``kept`` (:func:`kept_of` in another process, of the same feature cache as the file
    ``analysis`` was loaded from) for ``analysis``; its picture entries take their arrays from
    ``layer`` (the timeline :func:`kept_of` was given, loaded, as read-only views; None: they are
    not kept).
    Returns whether a derive from ``analysis`` with ``kept``'s parameters now computes neither."""
    audio = video = False
    if analysis.audio is not None:
        audio = sorted(analysis.audio.items())
        for key, inputs in kept.get("inputs", []):
            for curves in inputs:
                for values in curves.values():
                    values.flags.writeable = False
            entry = ([weakref.ref(values) for _, values in audio], key, inputs)
            _keep(_derive._CURVES, _derive._CURVES_LOCK, _audio_ident(analysis.audio), entry)
            audio = True
    if analysis.video is not None and layer is not None and layer.n_ticks == analysis.n_ticks:
        for key, stats in kept.get("picture", []):
            arrays = {}
            for name, values in _picture_arrays(layer).items():  # read-only views: no layer's track is written
                arrays[name] = np.asarray(values, dtype=np.float32).view()
                arrays[name].flags.writeable = False
            _keep(_derive._PICTURE, _derive._PICTURE_LOCK, id(analysis.video),
                  (weakref.ref(analysis.video), key, arrays, stats))
            video = True
    return (audio or analysis.audio is None) and (video or analysis.video is None)
