"""Shots: the boundaries found in the analysis (:mod:`.detect`), the shot list after the
designer's split and merge operations (:mod:`.model`), and each shot's summary (:mod:`.summary`)."""

from autohaptics.shots.detect import KINDS, Boundaries, ShotParams, detect

__all__ = ["KINDS", "Boundaries", "ShotParams", "detect"]
