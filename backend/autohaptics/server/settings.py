"""The one typed configuration of the service.

Every knob has a default; :meth:`Settings.from_env` reads the environment (``AUTOHAPTICS_DATA``,
``AUTOHAPTICS_JOBS``, ``AUTOHAPTICS_MAX_UPLOAD_MB``, ``AUTOHAPTICS_FRONTEND``, ``AUTOHAPTICS_ALLOW_HOSTS``,
comma-separated) and the CLI
overrides on top. Tests build a ``Settings`` with a temporary ``data_dir``.
"""

from __future__ import annotations

import os
from pathlib import Path
from typing import Literal

from pydantic import BaseModel, ConfigDict, Field, ValidationError

from autohaptics.errors import ParameterError

MIB = 1024 * 1024
GIB = 1024 * MIB


def default_frontend_dir() -> Path:
    """The repository's ``frontend/`` folder, found relative to this package (backend/autohaptics/..)."""
    return Path(__file__).resolve().parents[3] / "frontend"


class Settings(BaseModel):
    """Service configuration.

    data_dir : folder holding the SQLite database and every project's files (created on start).
    frontend_dir : static files served at ``/`` (index.html); None serves no frontend.
    jobs : most generation jobs running at once (size of the one process pool).
    max_upload_bytes : largest accepted media upload; larger ones get 413 and leave nothing behind.
    max_import_bytes : largest accepted timeline import (JSON or CSV).
    mp_context : start method of the job processes ("spawn" or "forkserver"; never fork, because
        the server process runs threads).
    waveform_max_points : most peaks one waveform request may ask for.
    bind_host : the address ``serve --host`` binds; a name (not 0.0.0.0 / ::) is also a name the
        service answers to.
    allowed_hosts : further Host names the service answers to (e.g. a LAN name, on purpose;
        docs/API.md "Security"); 127.0.0.1, localhost and ::1 always are.
    picture_cache_bytes : most bytes of posters and filmstrip tiles kept per project (oldest evicted).
    """

    model_config = ConfigDict(frozen=True)

    data_dir: Path = Field(default_factory=lambda: Path(os.environ.get("AUTOHAPTICS_DATA", "data")))
    frontend_dir: Path | None = Field(default_factory=default_frontend_dir)
    jobs: int = Field(default=1, ge=1, le=64)
    max_upload_bytes: int = Field(default=4 * GIB, ge=1)
    max_import_bytes: int = Field(default=512 * MIB, ge=1)
    mp_context: Literal["spawn", "forkserver"] = "spawn"
    waveform_max_points: int = Field(default=100_000, ge=1)
    bind_host: str | None = None
    allowed_hosts: tuple[str, ...] = ()
    picture_cache_bytes: int = Field(default=100 * MIB, ge=1)

    @classmethod
    def from_env(cls, **overrides) -> "Settings":
        """Settings from the environment, then ``overrides`` (None values are ignored).

        Raises ParameterError naming the variable or setting that is invalid."""
        env: dict = {}
        try:
            if os.environ.get("AUTOHAPTICS_DATA"):
                env["data_dir"] = Path(os.environ["AUTOHAPTICS_DATA"])
            if os.environ.get("AUTOHAPTICS_JOBS"):
                env["jobs"] = int(os.environ["AUTOHAPTICS_JOBS"])
            if os.environ.get("AUTOHAPTICS_MAX_UPLOAD_MB"):
                env["max_upload_bytes"] = int(float(os.environ["AUTOHAPTICS_MAX_UPLOAD_MB"]) * MIB)
        except ValueError as exc:
            raise ParameterError(f"invalid AUTOHAPTICS_JOBS or AUTOHAPTICS_MAX_UPLOAD_MB: {exc}") from None
        if os.environ.get("AUTOHAPTICS_ALLOW_HOSTS"):
            env["allowed_hosts"] = tuple(h for h in os.environ["AUTOHAPTICS_ALLOW_HOSTS"].split(",") if h.strip())
        if os.environ.get("AUTOHAPTICS_FRONTEND"):
            env["frontend_dir"] = Path(os.environ["AUTOHAPTICS_FRONTEND"])
        env.update({k: v for k, v in overrides.items() if v is not None})
        try:
            return cls(**env)
        except ValidationError as exc:
            first = exc.errors()[0]
            raise ParameterError(f"invalid setting {'.'.join(map(str, first['loc']))}: {first['msg']}") from None
