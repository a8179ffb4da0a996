"""A batch's films and outputs: which files are films, what each output is called, and whether an
existing timeline is up to date (the manifest, or the timeline's own ``source`` and ``generator``)."""

from __future__ import annotations

import glob
import hashlib
import json
import os
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Iterable

from autohaptics.errors import ParameterError
from autohaptics.records import params_to_dict

MANIFEST_NAME = "batch-manifest.json"
MANIFEST_FORMAT = "autohaptics.batch-manifest"
OUTPUT_SUFFIX = ".timeline.json"
MEDIA_SUFFIXES = frozenset({
    ".mp4", ".m4v", ".mov", ".mkv", ".webm", ".avi", ".mpg", ".mpeg", ".ts", ".m2ts", ".mts", ".wmv",
    ".flv", ".ogv", ".3gp", ".wav", ".flac", ".mp3", ".m4a", ".aac", ".ogg", ".oga", ".opus",
})
_GLOB_CHARS = frozenset("*?[")


@dataclass
class FilmResult:
    """What happened to one film.

    status : "done" (timeline written), "skipped" (an up-to-date timeline was there) or "failed".
    reason : one line, for a failed film.
    seconds : wall time of the film's generation (done films only).
    """

    source: Path
    output: Path
    status: str
    reason: str | None = None
    seconds: float | None = None


@dataclass
class BatchReport:
    """The outcome of :func:`run_batch`, one :class:`FilmResult` per input film (input order)."""

    out_dir: Path
    results: list[FilmResult] = field(default_factory=list)

    def _with(self, status: str) -> list[FilmResult]:
        return [r for r in self.results if r.status == status]

    @property
    def done(self) -> list[FilmResult]:
        return self._with("done")

    @property
    def skipped(self) -> list[FilmResult]:
        return self._with("skipped")

    @property
    def failed(self) -> list[FilmResult]:
        return self._with("failed")

    @property
    def exit_status(self) -> int:
        """0 when every film has an up-to-date timeline, 1 when some failed."""
        return 1 if self.failed else 0

    def summary(self) -> str:
        return (f"{len(self.results)} film(s): {len(self.done)} done, {len(self.skipped)} skipped "
                f"(up to date), {len(self.failed)} failed; timelines in {self.out_dir}")


def collect_inputs(specs: Iterable[str | os.PathLike]) -> list[Path]:
    """Expand files, folders (their files with a media suffix) and glob patterns into film paths.

    Sorted by path, duplicates (same resolved file) removed. Raises ParameterError naming an input
    that does not exist or a pattern that matches nothing, and when no film is found at all.
    """
    specs = list(specs)
    found: dict[Path, Path] = {}
    for spec in specs:
        text = os.fspath(spec)
        p = Path(text).expanduser()
        if p.is_dir():
            files = [c for c in p.iterdir() if c.is_file() and c.suffix.lower() in MEDIA_SUFFIXES]
        elif p.is_file():
            files = [p]
        elif _GLOB_CHARS & set(text):
            files = [Path(m) for m in glob.glob(os.path.expanduser(text), recursive=True) if Path(m).is_file()]
            if not files:
                raise ParameterError(f"{text}: the pattern matches no file")
        else:
            raise ParameterError(f"{text}: no such file or folder")
        for f in files:
            found.setdefault(f.resolve(), f.absolute())
    if not found:
        raise ParameterError("no media files found in " + ", ".join(os.fspath(s) for s in specs))
    return sorted(found.values())


def output_names(sources: list[Path], manifest: dict[str, dict]) -> dict[Path, str]:
    """Output name (without ``.timeline.json``) per source: the name the manifest gave that source
    earlier, else its stem, else the stem with 8 hex digits of the path's SHA-1 when the stem is taken.

    Names are compared case-insensitively, so outputs never collide on a case-insensitive disk.
    """
    names: dict[Path, str] = {}
    taken: set[str] = set()
    by_source = {str(e.get("source")): name for name, e in manifest.items()}
    for src in sources:
        name = by_source.get(str(src))
        if name is not None and name.casefold() not in taken:
            names[src] = name
            taken.add(name.casefold())
    wanted = {str(s) for s in sources}
    for name, entry in manifest.items():  # films of earlier runs that still exist keep their names
        other = str(entry.get("source"))
        if other not in wanted and Path(other).exists():
            taken.add(name.casefold())
    for src in sources:
        if src in names:
            continue
        name = _safe_stem(src)
        if name.casefold() in taken:
            tag = hashlib.sha1(str(src).encode()).hexdigest()[:8]
            name, k = f"{name}-{tag}", 2
            while name.casefold() in taken:
                name, k = f"{_safe_stem(src)}-{tag}-{k}", k + 1
        names[src] = name
        taken.add(name.casefold())
    return names


def _safe_stem(src: Path) -> str:
    stem = src.stem.strip() or "film"
    return stem if not stem.startswith(".") else "_" + stem[1:]


def params_digest(params: Any, preset: str, style: Any = None) -> str:
    """SHA-256 of the resolved parameters, the preset name and the style's document, if any (what
    makes a timeline up to date)."""
    doc = {"params": params_to_dict(params), "preset": preset}
    if style is not None:
        doc["style"] = style.to_dict()
    return hashlib.sha256(json.dumps(doc, sort_keys=True).encode()).hexdigest()


def load_manifest(out_dir: Path) -> dict[str, dict]:
    """The manifest's films ({output name: entry}); empty when absent or unreadable (the existing
    timelines are then read instead)."""
    try:
        doc = json.loads((out_dir / MANIFEST_NAME).read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return {}
    films = doc.get("films") if isinstance(doc, dict) and doc.get("format") == MANIFEST_FORMAT else None
    return {k: v for k, v in films.items() if isinstance(v, dict)} if isinstance(films, dict) else {}


def save_manifest(out_dir: Path, films: dict[str, dict]) -> None:
    """Write the manifest atomically (a temporary file renamed into place)."""
    path = out_dir / MANIFEST_NAME
    tmp = path.with_name(path.name + ".part")
    doc = {"format": MANIFEST_FORMAT, "version": 1, "films": dict(sorted(films.items()))}
    tmp.write_text(json.dumps(doc, indent=1) + "\n", encoding="utf-8")
    os.replace(tmp, path)


def recorded_sha(output: Path, entry: dict | None, source: Path, digest: str, params: Any,
                  preset: str, style: Any = None) -> str | None:
    """The source SHA-256 an existing, parameter-matching timeline was made from (None: redo)."""
    if not output.is_file():
        return None
    if entry is not None:
        if entry.get("source") == str(source) and entry.get("params_digest") == digest:
            return entry.get("sha256")
        return None
    return _timeline_sha(output, params, preset, style)


def _timeline_sha(output: Path, params: Any, preset: str, style: Any = None) -> str | None:
    """``source.sha256`` of a timeline file whose ``generator`` matches ``params``, ``preset`` and
    ``style``."""
    try:
        with open(output, encoding="utf-8") as fh:
            doc = json.load(fh)
        gen, src = doc["generator"], doc["source"]
        stored = gen["params"]
    except (OSError, ValueError, KeyError, TypeError):
        return None
    if gen.get("preset") != preset or not isinstance(stored, dict):
        return None
    if gen.get("style") != (None if style is None else style.to_dict()):
        return None
    if any(stored.get(k) != v for k, v in params_to_dict(params).items()):
        return None
    sha = src.get("sha256") if isinstance(src, dict) else None
    return sha if isinstance(sha, str) else None
