"""Request and response schemas (docs/API.md): one input and one output model per entity."""

from __future__ import annotations

from typing import Annotated, Any, Literal

from pydantic import BaseModel, ConfigDict, Field

JobStatus = Literal["queued", "running", "done", "failed", "cancelled"]
ProjectStatus = Literal["new", "running", "ready", "failed", "cancelled"]


class _In(BaseModel):
    """Every input: unknown fields refused, numbers finite (docs/API.md "Security")."""
    model_config = ConfigDict(extra="forbid", allow_inf_nan=False)


MAX_SECONDS = 1e7  # a position or range end, s (115 days: beyond any film)
Revision = Annotated[int, Field(ge=0, le=2**53)]
Name = Annotated[str, Field(max_length=200)]
ProjectId = Annotated[str, Field(min_length=1, max_length=200)]
StyleId = Annotated[str, Field(min_length=1, max_length=200)]


# ---------------------------------------------------------------------- service
class HealthOut(BaseModel):
    status: Literal["ok"] = "ok"
    version: str


class SessionOut(BaseModel):
    token: str


class ConfigOut(BaseModel):
    version: str
    presets: list[str]
    default_preset: str
    modes: list[str]
    default_thresholds: dict[str, float]
    features: list[str]
    normalised_features: list[str]
    lanes: list[str]
    vibration_lanes: list[str]
    edit_ops: list[str]
    tick_s: float
    upload_limit_bytes: int
    import_limit_bytes: int
    layout: dict[str, Any]
    zones: list[str]
    temperature: dict[str, float]
    export_formats: list[dict[str, str]]
    import_formats: list[str]


# ------------------------------------------------------------------------- jobs
class JobOut(BaseModel):
    id: str
    project_id: str
    status: JobStatus
    progress: float
    stage: str
    error: str | None
    params: dict[str, Any]
    created_at: str | None
    started_at: str | None
    finished_at: str | None


class JobAccepted(BaseModel):
    job: JobOut


# --------------------------------------------------------------------- projects
class ParamsDoc(BaseModel):
    """Stored parameters; ``style`` ({id, name, document}, the learned style they derive in) only
    when there is one, so a document without a style reads as it is stored."""
    model_config = ConfigDict(extra="allow")

    preset: str
    mode: str
    thresholds: dict[str, float]
    overrides: dict[str, Any]


class ProjectOut(BaseModel):
    id: str
    name: str
    created_at: str
    updated_at: str
    status: ProjectStatus
    duration_s: float
    n_ticks: int
    source: dict[str, Any]
    media_type: str
    has_timeline: bool
    params: ParamsDoc
    revision: int
    cursor: int
    view: dict[str, Any]
    job: JobOut | None


class ProjectPatch(_In):
    name: str | None = Field(default=None, max_length=1000)
    view: dict[str, Any] | None = None


class ParamsIn(_In):
    preset: Name | None = None
    mode: Name | None = None
    thresholds: dict[str, float] | None = None
    overrides: dict[str, Any] | None = None
    style: StyleId | None = None  # a stored style's id; null drops the style, left out keeps it


class ParamsOut(BaseModel):
    revision: int
    derived: bool
    seconds: float | None = None
    job: JobOut | None = None
    cursor: int | None = None  # the edit history's cursor after the change was recorded (a 'params' op)


class WaveformOut(BaseModel):
    points: int
    duration_s: float
    has_audio: bool
    min: list[float]
    max: list[float]


class ChairTemperatureOut(BaseModel):
    revision: int
    tick_s: float
    min_c: float
    max_c: float
    neutral_c: float
    rate_c_per_s: float
    values: list[float]


class LaneValuesOut(BaseModel):
    revision: int
    t0: int
    t1: int
    values: dict[str, list]


# ------------------------------------------------------------------------ edits
class EditIn(_In):
    base_revision: Revision
    op: dict[str, Any]


class RevisionIn(_In):
    base_revision: Revision


class RevisionOut(BaseModel):
    revision: int
    cursor: int


class MarkerOut(BaseModel):
    id: str
    t_s: float
    label: str


class HistoryOut(RevisionOut):
    markers: list[MarkerOut]


class StepOut(HistoryOut):
    """Undo / redo: a 'params' op stepped over brings its parameters back (``params``, and ``job``
    when they need a new analysis)."""

    params: ParamsDoc | None = None
    job: JobOut | None = None


class EditOut(HistoryOut):
    op: dict[str, Any]


class EditsOut(HistoryOut):
    ops: list[dict[str, Any]]


# ------------------------------------------------------------------------ shots
class ShotOut(BaseModel):
    """One shot ``[t0, t1)`` (ticks; ``id`` is ``t0``), how it begins, and its summary (null where
    the film has no such stream)."""

    id: int
    t0: int
    t1: int
    kind: Literal["start", "cut", "fade", "dissolve", "split"]
    vibration_mean: float
    vibration_peak: float
    temperature_mean_c: float
    fans_share: float
    loudness_sone: float | None
    colour: str | None
    motion: float | None
    poster_url: str


class ShotsOut(BaseModel):
    revision: int
    n_ticks: int
    tick_s: float
    shots: list[ShotOut]


class FilmstripOut(BaseModel):
    """Frames ``frame_w`` x ``frame_h`` px, ``per_tile`` to a tile, at each of ``steps`` (ticks apart)."""

    frame_w: int
    frame_h: int
    per_tile: int
    steps: list[int]


class SimilarShotOut(BaseModel):
    id: int
    distance: float = Field(ge=0.0, le=1.0)


class SimilarOut(BaseModel):
    """Every other shot by ascending distance (0..1) to ``shot``."""

    revision: int
    shot: int
    similar: list[SimilarShotOut]


# ------------------------------------------------------------------------ chair
class PortOut(BaseModel):
    device: str
    description: str
    kind: Literal["usb", "serial", "virtual"]
    vid: int | None = None
    pid: int | None = None
    serial_number: str | None = None
    manufacturer: str | None = None
    likely_chair: bool


class ChairConnectIn(_In):
    port: str = Field(min_length=1, max_length=4096)


class ChairPlaybackIn(_In):
    project_id: ProjectId
    state: Literal["play", "pause", "seek"]
    position_s: float = Field(ge=0, le=MAX_SECONDS)
    heartbeat: bool = False
    initial: bool = False


class ChairMuteIn(_In):
    back: bool | None = None
    armrests: bool | None = None
    seat: bool | None = None
    heat: bool | None = None
    fans: bool | None = None


class ChairComfortIn(_In):
    scale: float | None = Field(default=None, ge=0, le=1)
    mute: ChairMuteIn | None = None


class ChairSettingsIn(_In):
    latency_ms: float | None = Field(default=None, ge=-500, le=500)
    comfort: ChairComfortIn | None = None


class ChairComfortOut(BaseModel):
    scale: float
    mute: dict[str, bool]


class ChairSettingsOut(BaseModel):
    latency_ms: float
    comfort: ChairComfortOut


class ChairPushIn(_In):
    project_id: ProjectId
    start_s: float = Field(ge=0, le=MAX_SECONDS)
    end_s: float = Field(gt=0, le=MAX_SECONDS)


class ChairPlaybackOut(BaseModel):
    state: str
    project_id: str | None
    revision: int | None
    duration_s: float | None
    ticks_skipped: int
    clock_priority: str | None
    drift_s: float | None
    drift_seeks: int


class ChairPushOut(BaseModel):
    project_id: str
    start_s: float
    end_s: float
    state: Literal["running", "done", "cancelled", "failed"]
    progress: float
    error: str | None


class ChairStatusOut(BaseModel):
    connected: bool
    state: Literal["idle", "connected", "reconnecting", "disconnected", "closed"]
    port: str | None
    capabilities: dict[str, Any] | None
    frames_sent: int
    frames_dropped: int
    last_tick: int | None
    reconnects: int
    diagnostics: dict[str, Any] | None
    error: str | None
    playing: bool
    position_s: float
    playback: ChairPlaybackOut
    push: ChairPushOut | None
    settings: ChairSettingsOut


# ----------------------------------------------------------------------- styles
class StyleLearnIn(_In):
    name: Annotated[str, Field(min_length=1, max_length=200)]
    project_ids: Annotated[list[ProjectId], Field(min_length=1, max_length=20)]
    dry_run: bool = False  # learn and report, store nothing (the editor's preview)


class StyleFilm(BaseModel):
    project_id: str
    name: str
    plain: dict[str, float | None]
    styled: dict[str, float | None]
    explained: float | None


class StyleOut(BaseModel):
    id: str | None  # null for a dry run
    name: str
    created_at: str | None
    films: list[dict[str, str]]
    report: list[StyleFilm]


class StyleDetailOut(StyleOut):
    document: dict[str, Any]
