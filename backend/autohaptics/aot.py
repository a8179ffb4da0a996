"""Numba kernels as machine code that loads without numba.

A :class:`KernelSet` names a module of numba functions and the signature each is exported with.
The first use on a machine builds them with numba's ahead-of-time compiler into an extension
module in the cache folder (:mod:`autohaptics.cachedir`, ``kernels/``), named by a digest of the
source, the signatures, numpy and Python; every later process loads that file, about a
millisecond, where importing numba takes 0.5-0.8 s (docs/BENCHMARKS.md, 'Start-up'). Building
needs numba and a C compiler (10-30 s); where it fails, :meth:`KernelSet.built` raises and the
caller takes its fallback.
"""

from __future__ import annotations

import functools
import importlib
import importlib.util
import os
import shutil
import sys
import tempfile
import threading
import types
import warnings
from pathlib import Path

from autohaptics.cachedir import cache_dir, digest, source_bytes

KERNELS_DIR = "kernels"


class KernelSet:
    """The numba functions of module ``source`` exported under ``signatures`` ({name: signature}),
    built into an extension module named ``<prefix>_<digest>``. host_cpu : built for this
    machine's processor (its vector instructions; the digest then names the processor too, so a
    cache folder shared with another machine builds its own), else for any x86-64 / ARM64."""

    def __init__(self, prefix: str, source: str, signatures: dict[str, str], *, host_cpu: bool = False):
        self.prefix, self.source, self.signatures = prefix, source, dict(signatures)
        self.host_cpu = host_cpu and bool(_processor())
        self._module: types.ModuleType | None = None
        self._lock = threading.Lock()  # one build and one load, whichever thread asks first

    def module_name(self) -> str:
        """The extension's module name: changes with the source, signatures, numpy and Python."""
        import numpy as np

        source = source_bytes(importlib.util.find_spec(self.source).origin)
        parts = (source, self.signatures, np.__version__, sys.version, sys.platform)
        return f"{self.prefix}_" + digest(*parts, *((_processor(),) if self.host_cpu else ()))

    def built(self) -> types.ModuleType:
        """The extension module, built first where the cache folder holds none; raises where it
        cannot be built or loaded (no C compiler, no numba, no writable folder)."""
        with self._lock:
            if self._module is None:
                name = self.module_name()
                folder = cache_dir(KERNELS_DIR)
                found = sorted(folder.glob(f"{name}.*")) or [self._build(name, folder)]
                spec = importlib.util.spec_from_file_location(name, found[0])
                module = importlib.util.module_from_spec(spec)
                spec.loader.exec_module(module)
                self._module = module
            return self._module

    def _build(self, name: str, folder: Path) -> Path:
        """Compile the kernels ahead of time into ``folder``; the module file is moved in when complete."""
        os.environ.setdefault("NUMBA_CACHE_DIR", str(cache_dir("numba")))
        from numba.pycc import CC

        kernels = importlib.import_module(self.source)
        with tempfile.TemporaryDirectory(dir=folder, prefix=".build-") as tmp, warnings.catch_warnings():
            warnings.simplefilter("ignore")
            cc = CC(name)
            cc.output_dir = tmp
            cc.verbose = False
            if self.host_cpu:
                cc.target_cpu = "host"
            for kernel, signature in self.signatures.items():
                cc.export(kernel, signature)(getattr(kernels, kernel).py_func)
            cc.compile()
            built = next(Path(tmp).glob(f"{name}.*"))
            target = folder / built.name
            shutil.move(str(built), str(folder / f".{built.name}.tmp"))
            os.replace(folder / f".{built.name}.tmp", target)
        return target


@functools.cache
def _processor() -> str:
    """This machine's processor: its model and instruction-set flags as Linux lists them ("" elsewhere)."""
    try:
        text = Path("/proc/cpuinfo").read_text(errors="replace")
    except OSError:
        return ""
    keep = [line for line in text.split("\n\n")[0].splitlines() if line.split(":")[0].strip() in
            ("vendor_id", "model name", "flags", "Features", "CPU implementer", "CPU part")]
    return "\n".join(keep)
