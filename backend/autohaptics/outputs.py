"""Writing an output file or folder the user named: a file atomically (a temporary ``.part`` file
renamed into place on success), and every failure one ParameterError naming the path as given,
never the temporary."""

from __future__ import annotations

import contextlib
import os
from collections.abc import Iterator
from pathlib import Path
from typing import IO

from autohaptics.errors import ParameterError


def prepare_folder(folder: Path, *, label: str = "folder") -> Path:
    """``folder`` (a data or output folder), created if missing and writable; else ParameterError
    naming it as given and ``label`` ("output folder X is not a folder")."""
    path = Path(folder)
    if path.exists() and not path.is_dir():
        raise ParameterError(f"{label} {folder} is not a folder")
    try:
        path.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise ParameterError(f"{label} {folder} cannot be created: {exc.strerror or exc}") from None
    if not os.access(path, os.W_OK | os.X_OK):
        raise ParameterError(f"{label} {folder} is not writable")
    return path


def check_output(path: str | os.PathLike) -> Path:
    """``path`` as a Path; ParameterError when it is a folder or its folder does not exist."""
    out = Path(path)
    if out.is_dir():
        raise ParameterError(f"{path}: is a folder; give a file name")
    parent = out.parent if str(out.parent) else Path(".")
    if not parent.is_dir():
        what = "is not a folder" if parent.exists() else "does not exist"
        raise ParameterError(f"{path}: the output folder {parent} {what}")
    return out


@contextlib.contextmanager
def atomic_output(path: str | os.PathLike, *, binary: bool) -> Iterator[IO]:
    """Open ``path`` for writing through a temporary ``.part`` file renamed into place on success.

    A failed write never leaves a truncated file under the final name.
    """
    out = check_output(path)
    tmp = out.with_name(out.name + ".part")
    try:
        try:
            fh = open(tmp, "wb") if binary else open(tmp, "w", encoding="utf-8", newline="")
        except OSError as exc:
            raise ParameterError(f"{path}: cannot write here ({exc.strerror or exc})") from None
        with fh:
            yield fh
        try:
            os.replace(tmp, out)
        except OSError as exc:
            raise ParameterError(f"{path}: cannot write here ({exc.strerror or exc})") from None
    finally:
        if tmp.exists():
            tmp.unlink()
