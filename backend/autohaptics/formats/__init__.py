"""Exporters: a timeline to other haptic formats (docs/EXPORT.md has the mapping and limits).

``FORMATS`` maps a format name to an :class:`ExportFormat` (file suffix, media type, whether the
output is binary, and its writer ``write(tl, stream, **options)``). :func:`export_timeline` writes
one format to a path (atomically) or to an open stream:

>>> export_timeline(tl, "csv", "movie.csv")                # doctest: +SKIP
>>> export_timeline(tl, "ahap", open("movie.zip", "wb"))   # doctest: +SKIP
"""

from __future__ import annotations

import inspect
import io
import os
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import IO, Any

from autohaptics.errors import ParameterError
from autohaptics.formats.common import as_played, ensure_valid
from autohaptics.outputs import atomic_output
from autohaptics.formats.ahap import write_ahap_zip
from autohaptics.formats.csv import write_csv, write_csv_sidecar
from autohaptics.formats.hjif import write_hjif
from autohaptics.formats.mpegv import write_sem
from autohaptics.formats.native import write_json
from autohaptics.timeline import Timeline


@dataclass(frozen=True)
class ExportFormat:
    name: str
    suffix: str  # file name suffix, with the dot
    media_type: str
    binary: bool  # the writer takes a binary stream (else a text stream)
    write: Callable[..., None]
    description: str

    @property
    def options(self) -> tuple[str, ...]:
        """The keyword options its writer takes (e.g. ``date``, ``sharpness``)."""
        params = inspect.signature(self.write).parameters
        return tuple(p for p, v in params.items() if v.kind is inspect.Parameter.KEYWORD_ONLY)


FORMATS: dict[str, ExportFormat] = {
    f.name: f
    for f in (
        ExportFormat("csv", ".csv", "text/csv", False, write_csv,
                     "one row per 100 ms tick: time_s, A1..A9, temperature_c, 153 fan cells"),
        ExportFormat("json", ".json", "application/json", False, write_json,
                     "the native autohaptics timeline file (lossless)"),
        ExportFormat("ahap", ".zip", "application/zip", True, write_ahap_zip,
                     "Apple Core Haptics: a zip of nine AHAP patterns, one per actuator"),
        ExportFormat("hjif", ".hjif", "application/json", False, write_hjif,
                     "MPEG-I Haptics (ISO/IEC 23090-31) interchange JSON"),
        ExportFormat("mpegv", ".xml", "application/xml", False, write_sem,
                     "MPEG-V (ISO/IEC 23005-3) Sensory Effect Metadata XML"),
    )
}


def get_format(fmt: str) -> ExportFormat:
    """The :class:`ExportFormat` called ``fmt``; ParameterError naming the known ones otherwise."""
    try:
        return FORMATS[str(fmt).lower()]
    except KeyError:
        raise ParameterError(
            f"unknown export format {fmt!r}; choose one of {', '.join(FORMATS)}") from None


def export_timeline(tl: Timeline, fmt: str, out: str | os.PathLike | IO, **options: Any) -> Path | None:
    """Export ``tl`` in format ``fmt`` to ``out``: a path (written atomically, returned) or a stream.

    A text format accepts a text stream or a binary one (written as UTF-8); ``ahap`` needs a binary
    stream. Every format carries the temperature the chair plays (:func:`~autohaptics.formats.common.as_played`).
    ``options`` go to the format's writer (e.g. ``sharpness=`` for ahap, ``date=`` for
    ahap and hjif, the formats that carry a date); an option the writer does not take is a ParameterError.
    """
    spec = get_format(fmt)
    _check_options(spec, options)
    tl = as_played(ensure_valid(tl))
    if isinstance(out, (str, os.PathLike)):
        path = Path(out)
        with atomic_output(path, binary=spec.binary) as fh:
            spec.write(tl, fh, **options)
        return path
    if spec.binary:
        if isinstance(out, io.TextIOBase):
            raise ParameterError(f"{spec.name} is a binary format ({spec.media_type}); "
                                 "pass a binary stream or a path")
        spec.write(tl, out, **options)
    elif isinstance(out, io.TextIOBase):
        spec.write(tl, out, **options)
    else:
        text = io.TextIOWrapper(out, encoding="utf-8", newline="")
        try:
            spec.write(tl, text, **options)
            text.flush()
        finally:
            text.detach()
    return None


def _check_options(spec: ExportFormat, options: dict) -> None:
    allowed = spec.options
    unknown = sorted(set(options) - set(allowed))
    if unknown:
        raise ParameterError(
            f"export format {spec.name} takes no option {', '.join(unknown)}"
            + (f" (it takes: {', '.join(allowed)})" if allowed else " (it takes none)"))


__all__ = ["FORMATS", "ExportFormat", "export_timeline", "get_format", "write_ahap_zip", "write_csv",
           "write_csv_sidecar", "write_hjif", "write_json", "write_sem"]
