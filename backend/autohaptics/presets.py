"""Quality presets and parameter overrides, with one meaning across the CLI, the API and the editor.

A preset is a set of dotted overrides on :class:`autohaptics.pipeline.GenerateParams`
(``"flow.method": "farneback"``). Every knob a preset sets stays individually overridable
(``--set flow.method=dis`` on the CLI, ``overrides`` in the API) and the resolved values are
recorded in the timeline's ``generator.params``.

- ``reference``: the slowest, most faithful configuration: exact ISO 532-1 filter bank, every
  frame decoded and analysed at the largest sensible proxy (640 px flow, a third of the picture's
  width above 1920 px; 320 px saliency and depth),
  dense DIS flow at its "medium" quality, no skipping.
  Farneback was the planned reference flow; measured, it is the less faithful of the two here:
  on the Sintel trailer at 640 px it reads a median 0.23 of DIS's motion (DIS at 160 and 640 px
  agree within 1 %), on smooth synthetic pans it reads close to zero, and it leaves up to 0.6 px
  of flow on identical frames. It stays available as ``flow.method=farneback`` and the accuracy
  benchmark can run it as an extra configuration.
- ``balanced`` (default): FFmpeg decodes only the reference frames (on H.264 the B-frames are
  skipped: about half the decoding work; the frames it decodes are exact; VP8 and intra-only
  video decode every frame), one frame (plus its successor for flow) per 100 ms tick, flow on a
  proxy an eighth of the picture's width and at least 160 px wide (240 px at 1080p; see
  ``FlowParams.proxy_fraction``),
  256 px saliency (the spectral residual itself always sees the full frame's luma averaged to
  64 x 64; the width sets where the salient shape is cut: measured against the reference on the
  30 s 1080p BBB clip, vibration MAE 0.023 at 192 px and 0.012 at 256 with every frame decoded,
  0.014 at 256 and 0.012 at 320 with reference frames only), 128 px depth, skipping on.
- ``fast``: ``video.stride=3``: the picture is read for every third tick (the frame nearest the
  centre of each group of three ticks, its values shared by all three; the audio stays at 10 Hz),
  which cuts the proxies, flow, saliency and depth to a third; and ``video.decode=sparse``: from
  40 fps up FFmpeg decodes only the I- and P-frames (every B-frame skipped, reference B-frames
  too, which leaves the P-frames that used one approximate), below 40 fps only the non-reference
  frames; the deblocking filter is skipped either way; 128 px flow (a sixteenth of the picture's
  width above 2048 px) at DIS "fast", 128 px
  saliency, 64 px depth. On the 30 s 1080p60 BBB clip that is 495 of 1,800 frames decoded
  (balanced: 930), and decoding them alone takes 1.7 s of fast's 3 s. Measured against the
  reference on the 2 s clip: vibration MAE 0.026 with non-reference skipping only, 0.064 with
  sparse decoding, 0.097 with a stride of 2 and 0.093 with 3. On the Sintel trailer: 0.006 in
  balanced, 0.024 at stride 2, 0.023 at stride 3, with onset F1 0.97, 0.92 and 0.91. A stride of
  3 instead of 2 took 9-10 % off fast's time on both clips; see docs/BENCHMARKS.md.
"""

from __future__ import annotations

import dataclasses
import json
import math
import types
import typing
from typing import Any

from autohaptics.errors import ParameterError

PRESETS: dict[str, dict[str, Any]] = {
    "reference": {
        "audio.loudness_method": "iso",
        "video.analysis": "every",
        "video.decode": "full",
        "video.skip": False,
        "saliency.proxy_width": 320,
        "depth.proxy_width": 320,
        "flow.method": "dis",
        "flow.dis_preset": "medium",
        "flow.proxy_width": 640,
        "flow.proxy_fraction": 1 / 3,
    },
    "balanced": {},
    "fast": {
        "video.decode": "sparse",
        "video.stride": 3,
        "saliency.proxy_width": 128,
        "depth.proxy_width": 64,
        "flow.proxy_width": 128,
        "flow.proxy_fraction": 0.0625,
        "flow.dis_preset": "fast",
    },
}
DEFAULT_PRESET = "balanced"


def preset_overrides(name: str) -> dict[str, Any]:
    """The dotted overrides a preset applies (a copy)."""
    if name not in PRESETS:
        raise ParameterError(f"unknown preset {name!r}; choose one of {sorted(PRESETS)}")
    return dict(PRESETS[name])


def apply_overrides(params: Any, overrides: dict[str, Any]) -> Any:
    """Return a copy of a (nested, frozen) params dataclass with dotted ``overrides`` applied.

    Values may be strings (from the command line); they are converted to the field's type.
    Unknown names raise ParameterError naming the key and the known fields.
    """
    for key, value in overrides.items():
        params = _set_path(params, key.split("."), value, key)
    return params


def parse_assignments(items: list[str] | None) -> dict[str, str]:
    """``["flow.method=dis", "video.proxy_width=128"]`` -> {"flow.method": "dis", ...}."""
    out: dict[str, str] = {}
    for item in items or []:
        if "=" not in item:
            raise ParameterError(f"expected NAME=VALUE, got {item!r}")
        name, value = item.split("=", 1)
        name = name.strip()
        if not name:
            raise ParameterError(f"expected NAME=VALUE, got {item!r}")
        out[name] = value.strip()
    return out


def params_to_dict(params: Any) -> dict:
    """A JSON-serialisable nested dict of a params dataclass."""
    return json.loads(json.dumps(dataclasses.asdict(params), default=_default))


def params_from_dict(cls: type, doc: dict) -> Any:
    """Inverse of :func:`params_to_dict` for a params dataclass (unknown keys are errors)."""
    base = cls()
    flat: dict[str, Any] = {}

    def walk(prefix: str, d: dict, obj: Any):
        for k, v in d.items():
            child = getattr(obj, k, None) if obj is not None else None
            if isinstance(v, dict) and dataclasses.is_dataclass(child):
                walk(f"{prefix}{k}.", v, child)
            else:
                flat[f"{prefix}{k}"] = v

    walk("", doc, base)
    return apply_overrides(base, flat)


# ----------------------------------------------------------------------- private
def _set_path(obj: Any, path: list[str], value: Any, key: str) -> Any:
    if not dataclasses.is_dataclass(obj):
        raise ParameterError(f"cannot set {key!r}: {type(obj).__name__} has no fields")
    names = {f.name: f for f in dataclasses.fields(obj)}
    head = path[0]
    if head not in names:
        raise ParameterError(f"unknown parameter {key!r}; {type(obj).__name__} has {sorted(names)}")
    current = getattr(obj, head)
    if len(path) > 1:
        if isinstance(current, dict):
            new = dict(current)
            new[path[1]] = _convert(value, type(current.get(path[1], 0.0)) if path[1] in current else float, key)
            return dataclasses.replace(obj, **{head: new})
        return dataclasses.replace(obj, **{head: _set_path(current, path[1:], value, key)})
    hints = typing.get_type_hints(type(obj))
    converted = _convert_hint(value, hints.get(head, type(current)), current, key)
    try:
        return dataclasses.replace(obj, **{head: converted})
    except (TypeError, ValueError) as exc:
        raise ParameterError(f"invalid value for {key!r}: {exc}") from None


def _convert_hint(value: Any, hint: Any, current: Any, key: str) -> Any:
    origin = typing.get_origin(hint)
    args = typing.get_args(hint)
    if origin in (typing.Union, types.UnionType):
        if isinstance(value, str) and value.lower() in ("none", "null", "") and type(None) in args:
            return None
        if value is None and type(None) in args:
            return None
        last: Exception | None = None
        for a in args:
            if a is type(None):
                continue
            try:
                return _convert_hint(value, a, current, key)
            except ParameterError as exc:
                last = exc
        raise last or ParameterError(f"invalid value for {key!r}: {value!r}")
    if hint is typing.Any:
        return value
    if origin in (tuple, list):
        if isinstance(value, str):
            value = [v for v in value.replace("x", ",").split(",") if v.strip()]
        inner = args[0] if args else float
        return (tuple if origin is tuple else list)(_convert(v, inner, key) for v in value)
    if origin is dict or hint is dict:
        if isinstance(value, str):
            try:
                value = json.loads(value)
            except json.JSONDecodeError:
                raise ParameterError(f"{key!r} expects a JSON object, got {value!r}") from None
        if not isinstance(value, dict):
            raise ParameterError(f"{key!r} expects an object, got {value!r}")
        return dict(value)
    if isinstance(hint, type):
        return _convert(value, hint, key)
    return value


def _convert(value: Any, typ: type, key: str) -> Any:
    if typ is bool:
        if isinstance(value, bool):
            return value
        s = str(value).strip().lower()
        if s in ("1", "true", "yes", "on"):
            return True
        if s in ("0", "false", "no", "off"):
            return False
        raise ParameterError(f"{key!r} expects true/false, got {value!r}")
    if typ is int:  # "2", 2, "2.0" and 2.0 are 2; 1.5 is refused rather than cut to 1
        try:
            f = float(value)
        except (TypeError, ValueError, OverflowError):
            raise ParameterError(f"{key!r} expects a whole number, got {value!r}") from None
        if not (math.isfinite(f) and f.is_integer()):
            raise ParameterError(f"{key!r} expects a whole number, got {value!r}")
        return int(value) if isinstance(value, int) else int(f)
    if typ is float:
        try:
            v = float(value)
        except (TypeError, ValueError, OverflowError):
            raise ParameterError(f"{key!r} expects a number, got {value!r}") from None
        if not math.isfinite(v):
            raise ParameterError(f"{key!r} must be finite, got {value!r}")
        return v
    if typ is str:
        return str(value)
    return value


def _default(obj: Any) -> Any:
    if isinstance(obj, (set, frozenset, tuple)):
        return list(obj)
    return str(obj)
