"""The one artefact every part shares: the per-100-ms haptic timeline (format "autohaptics.timeline",
version 1; ../shared/docs/TIMELINE.md).

:mod:`.model` (the :class:`Timeline` type, its validation and its JSON file), :mod:`.edits` (the
designer's edit operations, applied over the generated tracks), :mod:`.npz` (the generated timeline
on disk), :mod:`.wire` (the editor's compact binary form), :mod:`.quantise` (the one 0..255 step,
shared with the chair) and :mod:`.numeric_json` (the JSON file's big arrays read straight into numpy).
"""

from autohaptics.timeline.model import FORMAT, NORMALISED_FEATURES, VERSION, Timeline, default_generator, json_default

__all__ = ["FORMAT", "NORMALISED_FEATURES", "VERSION", "Timeline", "default_generator", "json_default"]
