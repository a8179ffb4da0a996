"""The configurations ``bench accuracy`` compares, and the targets it checks them against."""

from __future__ import annotations

from dataclasses import dataclass

from autohaptics.errors import ParameterError

REFERENCE = "reference"
DEFAULT_CONFIGS = ("reference", "balanced", "fast")
NOSKIP = "balanced-noskip"
TARGETS = {"x_decode": 1.25, "vibration_mae": 0.02, "onset_f1": 0.97, "temperature_mae_c": 0.3, "fan_iou_tolerant": 0.9,
           "fast_speedup": 2.0}  # fast >= 2 x faster than balanced: wall time, stage seconds, wall - decode
SKIP_STAGES = ("saliency", "flow", "depth")


@dataclass(frozen=True)
class Config:
    """One benchmarked configuration: a preset plus dotted overrides."""

    name: str
    preset: str
    overrides: tuple[tuple[str, str], ...] = ()

    def cli_args(self) -> list[str]:
        out = ["--preset", self.preset]
        for k, v in self.overrides:
            out += ["--set", f"{k}={v}"]
        return out


def parse_config(text: str) -> Config:
    """``NAME:k=v,k=v`` -> Config. ``preset=NAME`` picks the base preset (default balanced); a piece
    without ``=`` continues the previous value (``tracks=vibration,fans``). Validated here."""
    from autohaptics.params import resolve_params

    name, sep, rest = text.partition(":")
    name = name.strip()
    if not name or not sep and "=" in name:
        raise ParameterError(f"--config expects NAME:k=v,k=v, got {text!r}")
    pairs: list[list[str]] = []
    for piece in (p for p in rest.split(",") if p.strip()):
        if "=" in piece:
            k, v = piece.split("=", 1)
            pairs.append([k.strip(), v.strip()])
        elif pairs:
            pairs[-1][1] += "," + piece.strip()
        else:
            raise ParameterError(f"--config {name}: expected k=v, got {piece!r}")
    preset = "balanced"
    overrides = []
    for k, v in pairs:
        if k == "preset":
            preset = v
        else:
            overrides.append((k, v))
    resolve_params(preset, dict(overrides))  # raises ParameterError naming a bad key or value
    return Config(name, preset, tuple(overrides))


def default_configs(skip_audit: bool = True) -> list[Config]:
    configs = [Config(name, name) for name in DEFAULT_CONFIGS]
    if skip_audit:
        configs.append(Config(NOSKIP, "balanced", (("video.skip", "false"),)))
    return configs
