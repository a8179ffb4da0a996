"""The chair service's stored settings (latency offset, comfort) and the status it reports."""

from __future__ import annotations

import logging

from autohaptics.chair import Comfort
from autohaptics.chair.comfort import MUTABLE_ZONES
from autohaptics.chair.player import check_latency_offset_ms
from autohaptics.errors import ParameterError
from autohaptics.server.store import Store

log = logging.getLogger("autohaptics.server.chair")
SETTINGS_KEY = "chair"
_DEFAULT_SETTINGS = {"latency_ms": 0.0, "comfort": {"scale": 1.0, "mute": {z: False for z in MUTABLE_ZONES}}}


def settings_to_comfort(settings: dict) -> Comfort:
    """The :class:`~autohaptics.chair.Comfort` of stored settings."""
    c = settings["comfort"]
    return Comfort(intensity=c["scale"], mute=frozenset(z for z, muted in c["mute"].items() if muted))


def merge_settings(current: dict, *, latency_ms: float | None = None, scale: float | None = None,
                   mute: dict[str, bool] | None = None) -> dict:
    """New chair settings: the given fields replace the current ones; checked (ParameterError)."""
    latency = current["latency_ms"] if latency_ms is None else check_latency_offset_ms(latency_ms)
    new_mute = dict(current["comfort"]["mute"])
    for zone, muted in (mute or {}).items():
        if zone not in MUTABLE_ZONES:
            raise ParameterError(f"unknown comfort zone {zone!r}; zones are {', '.join(MUTABLE_ZONES)}")
        new_mute[zone] = bool(muted)
    doc = {"latency_ms": float(latency),
           "comfort": {"scale": float(current["comfort"]["scale"] if scale is None else scale), "mute": new_mute}}
    settings_to_comfort(doc)  # validates the scale
    return doc


def stored_settings(store: Store) -> dict:
    """The settings in ``store``, checked; the defaults where none (or damaged ones) are stored."""
    stored = store.get_setting(SETTINGS_KEY) or {}
    doc = {"latency_ms": _DEFAULT_SETTINGS["latency_ms"],
           "comfort": {"scale": 1.0, "mute": dict(_DEFAULT_SETTINGS["comfort"]["mute"])}}
    try:
        comfort = stored.get("comfort") or {}
        return merge_settings(doc, latency_ms=stored.get("latency_ms"), scale=comfort.get("scale"),
                              mute={z: v for z, v in (comfort.get("mute") or {}).items() if z in MUTABLE_ZONES})
    except (ParameterError, AttributeError, TypeError):  # a damaged row: start from the defaults
        log.warning("ignoring invalid stored chair settings %r", stored)
        return doc


def diagnostics(ls: dict | None) -> dict | None:
    """The chair's own counters and state (its last STATUS) and the host side's, for the panel."""
    if ls is None:
        return None
    chair = ls["chair"]
    keys = ("crc_errors", "length_errors", "overflows", "version_errors", "type_errors", "stale_frames", "seq_gaps",
            "late_frames", "watchdog_trips", "frames_ok", "safe", "stopped", "safe_reason", "temp_target_c",
            "temp_setpoint_c")
    return {
        "chair": {k: chair[k] for k in keys} if chair else None,
        "chair_status_age_s": ls["chair_status_age_s"],
        "host_rx": ls["rx"],
        "last_error": ls["last_error"],
        "errors": ls["errors"],
    }


def signature(status: dict) -> tuple:
    """What makes a status "changed" for the SSE stream (counters and the position move all the time)."""
    chair = (status["diagnostics"] or {}).get("chair") or {}
    push = status["push"] or {}
    return (status["connected"], status["state"], status["port"], status["error"], status["reconnects"],
            status["playback"]["state"], status["playback"]["project_id"], status["playback"]["revision"],
            chair.get("safe"), chair.get("stopped"), chair.get("crc_errors"), chair.get("length_errors"),
            push.get("state"), repr(status["settings"]))
