"""Request and response schemas (docs/API.md): one input and one output model per entity."""

from __future__ import annotations

from typing import Any, Literal

from pydantic import BaseModel, ConfigDict, Field

JobStatus = Literal["queued", "running", "done", "failed", "cancelled"]
ProjectStatus = Literal["new", "running", "ready", "failed", "cancelled"]


class _In(BaseModel):
    model_config = ConfigDict(extra="forbid")


# ---------------------------------------------------------------------- service
class HealthOut(BaseModel):
    status: Literal["ok"] = "ok"
    version: str


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
    preset: str | None = None
    mode: str | None = None
    thresholds: dict[str, float] | None = None
    overrides: dict[str, Any] | None = None


class ParamsOut(BaseModel):
    revision: int
    derived: bool
    seconds: float | None = None
    job: JobOut | None = None


class WaveformOut(BaseModel):
    points: int
    duration_s: float
    has_audio: bool
    min: list[float]
    max: list[float]


# ------------------------------------------------------------------------ edits
class EditIn(_In):
    base_revision: int
    op: dict[str, Any]


class RevisionIn(_In):
    base_revision: int


class RevisionOut(BaseModel):
    revision: int
    cursor: int


class EditOut(RevisionOut):
    op: dict[str, Any]


class EditsOut(RevisionOut):
    ops: list[dict[str, Any]]
