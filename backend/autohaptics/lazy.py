"""Package attributes imported on first use, so that importing a package (or one light module of it)
does not load its heavy siblings: ``__getattr__ = lazy_attributes(__name__, {"Name": "module"})``."""

from __future__ import annotations

import importlib
from typing import Any, Callable


def lazy_attributes(package: str, where: dict[str, str]) -> Callable[[str], Any]:
    """A module-level ``__getattr__`` for ``package`` that imports ``package.<where[name]>`` when
    ``name`` is first asked for and returns its attribute of that name."""

    def __getattr__(name: str) -> Any:
        if name in where:
            return getattr(importlib.import_module(f"{package}.{where[name]}"), name)
        raise AttributeError(f"module {package!r} has no attribute {name!r}")

    return __getattr__
