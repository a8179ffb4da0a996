"""``/health``, ``/api/config`` and ``/api/session``."""

from __future__ import annotations

from fastapi import APIRouter, Request

from autohaptics import __version__, fusion, intensity, layout
from autohaptics.formats import FORMATS
from autohaptics.params import DEFAULT_PRESET, PRESETS
from autohaptics.timeline import edit_ops as edits
from autohaptics.timeline import op_fields
from autohaptics.server.deps import SettingsDep
from autohaptics.server.schemas import ConfigOut, HealthOut, SessionOut
from autohaptics.timebase import TICK_S
from autohaptics.timeline import NORMALISED_FEATURES

router = APIRouter(tags=["service"])


@router.get("/health", response_model=HealthOut)
def health() -> HealthOut:
    return HealthOut(version=__version__)


@router.get("/api/config", response_model=ConfigOut)
def config(settings: SettingsDep) -> ConfigOut:
    return ConfigOut(
        version=__version__,
        presets=list(PRESETS),
        default_preset=DEFAULT_PRESET,
        modes=list(fusion.MODES),
        default_thresholds=dict(intensity.DEFAULT_THRESHOLDS),
        features=list(intensity.FEATURES),
        normalised_features=sorted(NORMALISED_FEATURES),
        lanes=list(op_fields.LANES),
        vibration_lanes=list(op_fields.VIBRATION_LANES),
        edit_ops=list(edits.OPS),
        tick_s=TICK_S,
        upload_limit_bytes=settings.max_upload_bytes,
        import_limit_bytes=settings.max_import_bytes,
        layout=layout.layout_dict(),
        zones=list(layout.ZONES),
        temperature={"neutral_c": layout.TEMP_NEUTRAL_C, "low_c": layout.TEMP_LOW_C, "high_c": layout.TEMP_HIGH_C,
                     "device_min_c": layout.DEVICE_TEMP_MIN_C, "device_max_c": layout.DEVICE_TEMP_MAX_C,
                     "device_rate_c_per_s": layout.DEVICE_TEMP_RATE_C_PER_S},
        export_formats=[{"name": f.name, "suffix": f.suffix, "media_type": f.media_type,
                         "description": f.description} for f in FORMATS.values()],
        import_formats=["json", "csv"],
    )


@router.get("/api/session", response_model=SessionOut)
def session(request: Request) -> SessionOut:
    """The session token for programs that are not the editor (docs/API.md "Security"); a foreign
    page cannot read it (no CORS) and a rebinding one never gets past the Host check."""
    return SessionOut(token=request.app.state.token)
