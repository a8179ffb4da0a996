"""Every parameter that shapes a timeline: :class:`GenerateParams`, one group per stage (each group
the stage's own record), the quality presets, and which fields the analysis depends on.

Each record is frozen and validates itself. A field is "analysis" (changing it needs the film
decoded and analysed again) or "derive" (thresholds, mappings, the fan rule: re-derived from the
cached analysis in milliseconds): a record's ``STAGE`` says which for all its fields, a field's
``metadata["stage"]`` where one differs. :func:`analysis_key` follows these tags.

Presets (dotted overrides, each knob individually overridable; docs/GUIDE.md and
docs/BENCHMARKS.md have the figures behind them):

- ``reference``: the exact ISO 532-1 filter bank, every frame decoded and analysed, flow on a third
  of the picture's width (at least 640 px), 320 px saliency and depth, nothing skipped.
- ``balanced`` (default): FFmpeg decodes only the reference frames, one frame (plus the next distinct
  frame for flow) per 100 ms tick, flow on an eighth of the picture's width (at least 160 px), 256 px
  saliency, 128 px depth, skipping on.
- ``fast``: the picture read for every third tick, only I- and P-frames decoded from 40 fps up,
  128 px flow at DIS "fast", 128 px saliency, 64 px depth.
- ``thesis``: ``balanced`` with the vibration rule, the colour mapping and the fans' frame pairing
  and nearness back on the thesis's rules (:data:`THESIS_RULES`); the other decisions stay (cuts,
  the loudness gate, the fan smoothing). The same rules combine with any preset through ``--set``.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field
from typing import Any, ClassVar

from autohaptics.airflow import AirflowParams, FlowParams
from autohaptics.airflow.cuts import CutParams
from autohaptics.airflow.depth import DepthParams
from autohaptics.errors import ParameterError
from autohaptics.fusion import MODES, FusionParams, SaliencyParams
from autohaptics.intensity import FEATURES, AudioFeatureParams, IntensityParams
from autohaptics.media import DECODE_MODES
from autohaptics.records import (ANALYSIS, DERIVE, Record, apply_overrides, param, params_to_dict,
                                 parse_assignments, stage, stage_of)
from autohaptics.temperature import ThermalParams

TRACKS = ("vibration", "temperature", "fans")
ANALYSIS_MODES = ("tick", "every")
ACTIVE_AREAS = ("auto", "full")
OVERLAY_MODES = ("auto", "keep")
STEREO_MODES = ("auto", "2d", "side_by_side", "top_bottom")


@dataclass(frozen=True)
class VideoParams(Record):
    """Which frames, and what of them, the video pass analyses. Proxy sizes are the stages' own parameters
    (each proxy at the picture's aspect on screen): the gray proxy (static check, flow, in-pair cuts) is
    ``flow.width_for(picture width)`` wide (``stats["flow"]["proxy_width"]``), the RGB proxy (colour,
    saliency, depth, cuts between ticks) ``max(saliency.proxy_width, depth.proxy_width)``, but with the
    spectral saliency (the full frame's luma at 64 x 64) at most the gray proxy's width.

    analysis : "tick" (one frame plus its successor per 100 ms tick) or "every" (every decoded frame; reference).
    skip : skip what a scene does not need (the module docstring; False computes everything).
    prefetch : frames decoded ahead in a background thread, beside the analysis (0 = in the calling thread).
    decode : "full" (every frame, exactly), "nonref" (default: FFmpeg skips non-reference frames, about half the
        decoding work on H.264; the frames it decodes are exact), "fast" (also skips the deblocking filter) or
        "sparse" (the fast preset: also every B-frame at 40 fps and up, so P-frames that referenced one come out
        approximate; :func:`media.iter_video`). With skipped frames the analysed frame is the decoded one nearest the
        tick's centre and a flow pair ends on a decoded frame (``flow.min_span_frames``), timed by its real interval.
        None is skipped in a variable-rate stream, at 29-40 fps but in "sparse", from 40 fps where the pictures repeat
        (``stats["frames"]["decode"]``), or after skipping left two frames in a row out (MPEG-2, x265).
    stride : ticks per analysed frame, 1..10 (default 1; fast: 3; only with ``analysis="tick"``): the frame nearest the
        centre of each group of s ticks is analysed (and its successor), its values each tick's (at most s x 50 ms off).
    active_area : "auto" (default): every stage reads only the picture inside constant black bars
        (:func:`media.find_active_area`, ``stats["active_area"]``); "full": the whole frame, bars included.
    stereo : a 3D film's packed views: "auto" (default: as the file declares, else as its pictures show,
        :mod:`media.stereo`), "2d", "side_by_side" or "top_bottom"; read from the first view.
    overlays : "auto" (default): burnt-in overlays are found (:mod:`media.overlays`, ``stats["overlays"]``), a timecode
        or a logo filled from the picture around it, a watermark across the picture unblended; "keep": read as picture.
    """

    STAGE: ClassVar[str] = ANALYSIS
    GROUP: ClassVar[str] = "video"

    analysis: str = param("tick", choices=ANALYSIS_MODES)
    skip: bool = True
    prefetch: int = param(8, 0, 256, unit="frames", whole=True)
    decode: str = param("nonref", choices=DECODE_MODES)
    stride: int = param(1, 1, 10, unit="ticks", whole=True)
    active_area: str = param("auto", choices=ACTIVE_AREAS)
    stereo: str = param("auto", choices=STEREO_MODES)
    overlays: str = param("auto", choices=OVERLAY_MODES)

    def check(self) -> None:
        if self.stride > 1 and self.analysis != "tick":
            raise ParameterError(f"video.stride={self.stride} needs video.analysis='tick' "
                                 f"(the 'every' analysis reads every frame), got {self.analysis!r}")


@dataclass(frozen=True)
class GenerateParams(Record):
    """Every parameter that shapes a timeline (recorded in ``generator.params``).

    mode : vibration rendering, the thesis's study conditions (table 4.1): "multimodal" (audio
        intensity spread by saliency fusion, the full pipeline), "audio" (A1, A2, A5 from the audio
        intensity), "visual" (the salient area's actuators, no audio), "random" (seeded random events).
    tracks : which tracks to compute; a track left out is still present, off (zeros / neutral).
    seed : random generator seed of the "random" mode.
    lfe_gain_db : gain of the LFE channel in the downmix, dB, over one main channel's equal share
        (cinema playback: +10); the main channels are read as FFmpeg's default stereo downmix of them
        (``media.audio``), so a 5.1 film and its stereo copy are the same sound at the same level.
    allow_truncated : accept a file whose streams decode shorter than declared (the missing part
        is silence); otherwise such a file is an error.
    """

    STAGE: ClassVar[str] = ANALYSIS

    mode: str = param("multimodal", choices=MODES, stage=DERIVE)
    tracks: tuple[str, ...] = TRACKS
    seed: int = field(default=0, metadata=stage(DERIVE))
    lfe_gain_db: float = param(10.0, -40.0, 20.0, unit="dB")
    allow_truncated: bool = False
    audio: AudioFeatureParams = field(default_factory=AudioFeatureParams)
    intensity: IntensityParams = field(default_factory=IntensityParams)
    video: VideoParams = field(default_factory=VideoParams)
    saliency: SaliencyParams = field(default_factory=SaliencyParams)
    fusion: FusionParams = field(default_factory=FusionParams)
    thermal: ThermalParams = field(default_factory=ThermalParams)
    flow: FlowParams = field(default_factory=FlowParams)
    airflow: AirflowParams = field(default_factory=AirflowParams)
    cuts: CutParams = field(default_factory=CutParams)
    depth: DepthParams = field(default_factory=DepthParams)

    def check(self) -> None:
        bad = [t for t in self.tracks if t not in TRACKS]
        if bad:
            raise ParameterError(f"unknown track(s) {bad}; choose from {list(TRACKS)}")


# The dotted overrides that undo ALGORITHM.md's 2026-11 decisions, putting the thesis's rules back;
# every other field keeps its default, earlier decisions included (docs/GUIDE.md, section 5).
THESIS_RULES: dict[str, Any] = {
    "intensity.rule": "thesis",  # the default follows events: each feature against its recent baseline
    "intensity.loudness_gate": 0.05,  # the default gate, 0.2, is 23 phon below the film's loud level
    "intensity.normaliser": "max",  # the default divides by the 99.5th percentile: a robust film level
    "flow.repeat_wait_s": 0.0,  # the default waits for the next distinct frame (repeats give no motion)
    "flow.min_span_frames": 0.0,  # the default pairs frames two apart, whichever frames are decoded
    "flow.cadence_ratio": 0.0,  # the default times a pair by its picture steps under a repeat cadence
    "depth.expansion_grain": 0.0,  # the default counts expansion only where it holds over more than a block
    "airflow.static_noise": 0.0,  # the default raises the static test's level with the pair's noise (film grain)
    "airflow.cell_rel": 0.5,  # the default's cell bar is 0.55 of the tick's strong motion, not 0.5 of its strongest cell
    "airflow.peak_cells": 1,  # the default's strong motion is the mean of the five strongest cells
    "airflow.motion_sigma_ticks": 0.0,  # the default judges a tick on its shot's motion around it
    "airflow.near_sigma_ticks": 0.0,  # the default smooths nearness over neighbouring ticks of the shot
    "airflow.near_share": 0.0,  # the default counts the nearest 40 % of each tick's cells as near too
    "airflow.threshold_motion": "judged",  # the default takes the threshold from the motion without one-tick spikes
    "airflow.spike_ratio": 0.0,  # the default judges a tick over 10 x both its neighbours' at theirs
    "fusion.sigma_ticks": 0.0,  # the default spreads each tick's saliency weights over its shot's neighbouring frames
    "thermal.mapping": "thesis",  # the default maps a warm-cool measure around 33 C into the device range
    "cuts.in_one_step": False,  # the default confirms a cut between two ticks' frames over the frame between
}

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
    "thesis": THESIS_RULES,
    "fast": {
        "video.decode": "sparse",
        "video.stride": 3,
        "saliency.proxy_width": 128,
        "depth.proxy_width": 64,
        "flow.proxy_width": 128,
        "flow.proxy_fraction": 0.0625,
        "flow.dis_preset": "fast",
        # pairs of the next decoded frame: at DIS "fast" on 128 px, pairs two frames apart read the Sintel
        # trailer further from the reference (tolerant fan IoU 0.464 -> 0.367; docs/BENCHMARKS.md)
        "flow.min_span_frames": 0.0,
    },
}
DEFAULT_PRESET = "balanced"


def preset_overrides(name: str) -> dict[str, Any]:
    """The dotted overrides a preset applies (a copy)."""
    if name not in PRESETS:
        raise ParameterError(f"unknown preset {name!r}; choose one of {sorted(PRESETS)}")
    return dict(PRESETS[name])


def resolve_params(preset: str = DEFAULT_PRESET, overrides: dict[str, Any] | None = None,
                   thresholds: dict[str, Any] | None = None) -> tuple[GenerateParams, str]:
    """Build :class:`GenerateParams` from a preset, dotted overrides and threshold overrides."""
    params = apply_overrides(GenerateParams(), preset_overrides(preset))
    params = apply_overrides(params, overrides or {})
    if thresholds:
        th = dict(params.intensity.thresholds)
        for name, value in thresholds.items():
            if name not in FEATURES:
                raise ParameterError(f"unknown threshold {name!r}; expected one of {list(FEATURES)}")
            try:
                th[name] = float(value)
            except (TypeError, ValueError):
                raise ParameterError(f"threshold {name} must be a number, got {value!r}") from None
        params = dataclasses.replace(params, intensity=dataclasses.replace(params.intensity, thresholds=th))
    return params, preset


# A project's stored parameters: {preset, mode, thresholds (the four effective values), overrides
# (the user's dotted overrides)} and, with a learned style, ``style`` (server/styles.py); the
# editor and the API change them field by field.
DEFAULT_PARAMS = {"preset": DEFAULT_PRESET, "mode": None, "thresholds": {}, "overrides": {}}


def params_from_doc(doc: dict) -> tuple[GenerateParams, str]:
    """(GenerateParams, preset) for a stored parameter document."""
    overrides = dict(doc.get("overrides") or {})
    if doc.get("mode"):
        overrides["mode"] = doc["mode"]
    return resolve_params(doc.get("preset") or DEFAULT_PRESET, overrides, doc.get("thresholds") or {})


def resolve_doc(current: dict | None, *, preset: str | None = None, mode: str | None = None,
            thresholds: dict | None = None, overrides: dict | None = None) -> tuple[dict, GenerateParams]:
    """New stored parameters: each given field replaces the current one whole, the others stay."""
    cur = {**DEFAULT_PARAMS, **(current or {})}
    doc = {
        "preset": preset if preset is not None else cur["preset"],
        "mode": mode if mode is not None else cur["mode"],
        "thresholds": dict(thresholds) if thresholds is not None else dict(cur["thresholds"]),
        "overrides": dict(overrides) if overrides is not None else dict(cur["overrides"]),
    }
    params, preset_name = params_from_doc(doc)
    doc["preset"] = preset_name
    doc["mode"] = params.mode
    doc["thresholds"] = dict(params.intensity.thresholds)
    if cur.get("style"):  # a learned style the service named (server/styles.py) stays until changed
        doc["style"] = cur["style"]
    return doc, params




def same_analysis(a: dict, b: dict) -> bool:
    """True when two stored parameter documents need the same analysis of the film."""
    return analysis_key(params_to_dict(params_from_doc(a)[0])) == analysis_key(params_to_dict(params_from_doc(b)[0]))


# ------------------------------------------------------------------ the command line
def add_generation_options(p) -> None:
    """Options shared by every command that generates (generate, batch, bench)."""
    p.add_argument("--mode", choices=MODES, default=None,
                   help="vibration rendering (the thesis's study conditions); default from the params")
    p.add_argument("--preset", choices=sorted(PRESETS), default="balanced",
                   help="quality preset (default: balanced)")
    p.add_argument("--threshold", action="append", metavar="NAME=VALUE", default=[],
                   help="feature threshold after normalisation, 0..1: sharpness, booming, low_energy, "
                        "loudness (repeatable)")
    p.add_argument("--set", action="append", metavar="PARAM=VALUE", default=[], dest="overrides",
                   help="override any parameter by its dotted name, e.g. audio.pa_per_unit=3.5566 "
                        "or intensity.normaliser=percentile (repeatable)")
    p.add_argument("--pa-per-unit", type=float, default=None,
                   help="calibration, pascal per digital full-scale unit (film default 3.5566: "
                        "0 dBFS rms = 105 dB SPL)")
    p.add_argument("--allow-truncated", action="store_true",
                   help="accept a damaged file that decodes shorter than declared")


def params_from_args(args):
    """(GenerateParams, preset name) from parsed generation options."""
    overrides = parse_assignments(args.overrides)
    if args.mode:
        overrides["mode"] = args.mode
    if args.pa_per_unit is not None:
        overrides["audio.pa_per_unit"] = args.pa_per_unit
    if getattr(args, "allow_truncated", False):
        overrides["allow_truncated"] = True
    thresholds = parse_assignments(args.threshold)
    return resolve_params(args.preset, overrides, thresholds)


# Analysis-time fields whose default analyses otherwise than the analysis did before the field
# existed: a document without the field was analysed with this value (dotted name -> value).
ABSENT_AS = {"flow.min_span_frames": 0.0, "flow.cadence_ratio": 0.0, "depth.expansion_grain": 0.0,
             "cuts.in_one_step": False, "video.stereo": "2d", "video.overlays": "keep",
             "airflow.static_noise": 0.0}


def analysis_key(doc: dict) -> dict:
    """The part of a ``generator.params``-style dict (:func:`~autohaptics.overrides.params_to_dict`)
    that the analysis depends on: compare two to know whether a cached analysis can serve. A field
    the document lacks counts at what the analysis did before the field existed: its default, or
    its value in ``ABSENT_AS``."""
    return _analysis_part(_DEFAULT, doc, "")


def _analysis_part(record: Any, doc: dict, prefix: str) -> dict:
    key = {}
    defaults = params_to_dict(record)
    for name, value in ABSENT_AS.items():  # each a field of a group of this record
        group, _, field_name = name[len(prefix):].rpartition(".")
        if name.startswith(prefix) and isinstance(defaults.get(group), dict):
            defaults[group] = {**defaults[group], field_name: value}
    for f in dataclasses.fields(record):
        value = getattr(record, f.name)
        if dataclasses.is_dataclass(value):
            stages = {stage_of(value, g.name) for g in dataclasses.fields(value)}
            if stages == {ANALYSIS}:  # a group the analysis reads whole
                given = doc.get(f.name)
                key[prefix + f.name] = {**defaults[f.name], **given} if isinstance(given, dict) else given
            elif ANALYSIS in stages:  # a derive-time group with some analysis-time fields
                key.update(_analysis_part(value, doc.get(f.name) or {}, prefix + f.name + "."))
        elif stage_of(record, f.name) == ANALYSIS:
            key[prefix + f.name] = doc.get(f.name, defaults[f.name])
    return key


_DEFAULT = GenerateParams()
