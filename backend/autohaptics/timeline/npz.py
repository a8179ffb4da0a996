"""The generated timeline on disk: an uncompressed ``.npz`` (``projects/<id>/generated.npz``).

A 2-hour film's generated timeline is ~26 MB of JSON that takes seconds to write and to parse;
the same arrays as ``.npz`` are written and read in tens of milliseconds, bit for bit (float32).
The JSON form stays what the API exports (``GET /timeline?layer=generated``).

Members::

    meta.json          uint8 [shape=(k,)], UTF-8 JSON {format, version, n_ticks, tick_s, source,
                       generator, stats, layout, extra, features: [names in order]}
    vibration          float32 [shape=(n_ticks, 9)]
    temperature_c      float32 [shape=(n_ticks,)]
    fans               float32 [shape=(n_ticks, 9, 17)]
    feature.<name>     float32 [shape=(n_ticks,)], one per feature curve
"""

from __future__ import annotations

import json
import os
import zipfile
from pathlib import Path

import numpy as np

from autohaptics.errors import ParameterError
from autohaptics.timeline.model import Timeline, json_default

FORMAT = "autohaptics.generated-npz"
VERSION = 1


def save_npz(tl: Timeline, path: str | os.PathLike) -> Path:
    """Validate ``tl`` and write it to ``path`` atomically (a temporary file renamed into place)."""
    tl.validate()
    path = Path(path)
    meta = {"format": FORMAT, "version": VERSION, "n_ticks": int(tl.n_ticks), "tick_s": tl.tick_s,
            "source": tl.source, "generator": tl.generator, "stats": tl.stats, "layout": tl.layout,
            "extra": tl.extra, "features": list(tl.features)}
    arrays = {"meta.json": np.frombuffer(json.dumps(meta, default=json_default).encode("utf-8"), dtype=np.uint8),
              "vibration": tl.vibration, "temperature_c": tl.temperature_c, "fans": tl.fans}
    for name, values in tl.features.items():
        arrays[f"feature.{name}"] = np.asarray(values, dtype=np.float32)
    tmp = path.with_name(path.name + ".part")
    try:
        with open(tmp, "wb") as fh:
            np.savez(fh, **arrays)
        os.replace(tmp, path)
    finally:
        tmp.unlink(missing_ok=True)
    return path


def load_npz(path: str | os.PathLike) -> Timeline:
    """Read a timeline written by :func:`save_npz`; ParameterError naming the file when it is not one."""
    path = Path(path)
    try:
        with np.load(path, allow_pickle=False) as z:
            meta = json.loads(bytes(z["meta.json"]).decode("utf-8"))
            if meta.get("format") != FORMAT or meta.get("version") != VERSION:
                raise ParameterError(f"{path}: not a generated timeline (format {meta.get('format')!r}, "
                                     f"version {meta.get('version')!r})")
            tl = Timeline(n_ticks=int(meta["n_ticks"]), vibration=z["vibration"], temperature_c=z["temperature_c"],
                          fans=z["fans"], source=meta["source"], generator=meta["generator"],
                          features={name: z[f"feature.{name}"] for name in meta["features"]}, stats=meta["stats"],
                          extra=meta["extra"], layout=meta["layout"], tick_s=float(meta["tick_s"]))
    except FileNotFoundError:
        raise ParameterError(f"{path}: no such file") from None
    except (OSError, KeyError, ValueError, zipfile.BadZipFile) as exc:
        raise ParameterError(f"{path}: not a generated timeline ({type(exc).__name__}: {exc})") from None
    try:
        return tl.validate()
    except ParameterError as exc:
        raise ParameterError(f"{path}: {exc}") from None
