"""The per-user cache folder, for what is built once per machine and reused by every later process
(the compiled loudness and area kernels, the designed filters, the virtual chair).

``$AUTOHAPTICS_CACHE_DIR``, else ``$XDG_CACHE_HOME/autohaptics`` or ``~/.cache/autohaptics``; never
inside the installed package, so a read-only install works. Where that folder cannot be created
or written (a home-less service user), ``<system temp>/autohaptics-cache-<uid>`` is used instead.
Entries are named by a digest of everything they depend on, so a new version never reads an old
entry, and written atomically (a temporary name, then a rename), so processes that build the
same entry at once do not see each other's halves.
"""

from __future__ import annotations

import functools
import hashlib
import os
import tempfile
from collections.abc import Callable
from pathlib import Path

CACHE_ENV = "AUTOHAPTICS_CACHE_DIR"


def cache_dir(*parts: str) -> Path:
    """``<cache folder>/<parts...>``, created if missing."""
    path = _root().joinpath(*parts)
    path.mkdir(parents=True, exist_ok=True)
    return path


@functools.cache
def _root() -> Path:
    env = os.environ.get(CACHE_ENV)
    if env:
        return Path(env)
    base = os.environ.get("XDG_CACHE_HOME") or str(Path.home() / ".cache")
    path = Path(base) / "autohaptics"
    try:
        path.mkdir(parents=True, exist_ok=True)
        if os.access(path, os.W_OK | os.X_OK):
            return path
    except OSError:
        pass
    return Path(tempfile.gettempdir()) / f"autohaptics-cache-{os.getuid()}"


def digest(*items: object) -> str:
    """16 hex digits of SHA-256 over the ``repr`` of ``items`` (bytes are hashed as they are)."""
    h = hashlib.sha256()
    for item in items:
        h.update(item if isinstance(item, bytes) else repr(item).encode())
        h.update(b"\0")
    return h.hexdigest()[:16]


def source_bytes(module_file: str | os.PathLike) -> bytes:
    """The source of a module (``__file__``), for a digest that changes when the code does."""
    return Path(module_file).read_bytes()


def cached_arrays(folder: str, key: str, build: Callable[[], dict]) -> dict:
    """The arrays ``build()`` returns (a dict of name -> numpy array), stored once as
    ``<cache>/<folder>/<key>.npz`` and read from there by later calls and processes. A cache that
    cannot be read or written is rebuilt in memory (the result is the same, only slower)."""
    import numpy as np

    try:
        path = cache_dir(folder) / f"{key}.npz"
        if path.is_file():
            with np.load(path) as npz:
                return {name: npz[name] for name in npz.files}
    except (OSError, ValueError):
        path = None
    arrays = {name: np.asarray(value) for name, value in build().items()}
    if path is not None:
        try:
            fd, tmp = tempfile.mkstemp(prefix=f".{key}.", suffix=".npz", dir=path.parent)
            with os.fdopen(fd, "wb") as fh:
                np.savez(fh, **arrays)
            os.replace(tmp, path)
        except OSError:
            pass
    return arrays
