"""The loudness kernels of :mod:`.kernels` as machine code that loads without numba.

``from autohaptics.intensity import compiled as K; K.slopes(...)``: the first use in a process
imports an extension module that numba's ahead-of-time compiler built once per machine into the
cache folder (:mod:`autohaptics.cachedir`, ``kernels/``), named by a digest of the kernels'
source, their signatures, numpy and Python; loading it takes about a millisecond, where importing
numba and loading its JIT cache took 0.5-0.8 s of every process (docs/BENCHMARKS.md, 'Start-up').
The first process on a machine builds it (numba and a C compiler, 10-30 s); where that fails,
the kernels run as numba's JIT functions (cached too), and with ``NUMBA_DISABLE_JIT=1`` as plain
Python, which is the slow reference path. Arrays may have any layout; the signatures are the
types every caller passes (float64 arrays, int64 arrays and scalars).
"""

from __future__ import annotations

import functools
import importlib.util
import os
import shutil
import sys
import tempfile
import types
import warnings
from pathlib import Path

from autohaptics.cachedir import cache_dir, digest, source_bytes

SIGNATURES = {
    "bank_square_smooth": "void(f8[:], f8[:,:,:], f8[:], f8[:], f8[:,:,:], f8[:,:], i8, i8, f8[:,:])",
    "sos_decimate": "void(f8[:], f8[:,:], f8[:,:], i8, i8, f8[:])",
    "core_loudness": "void(f8[:,:], f8, f8, f8, f8[:,:], f8[:,:], i8[:], i8, f8[:], f8[:], f8[:], f8[:], f8[:,:])",
    "nonlinear_decay": "void(f8[:,:], f8[:], i8, f8, f8[:], f8[:], f8[:], i8[:], f8[:,:])",
    "slopes": "void(f8[:,:], f8[:], f8[:], f8[:,:], i8[:], f8[:], f8[:,:])",
    "first_order": "void(f8[:], f8, f8, f8, f8[:], f8[:])",
    "bank_mean_square": "void(f8[:], f8[:,:,:], f8[:], i8, f8[:])",
}
KERNELS_DIR = "kernels"


def __getattr__(name: str):
    if name in SIGNATURES:
        return getattr(load(), name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


@functools.cache
def load() -> types.ModuleType:
    """The kernels: the cached extension module, built first if missing; numba's JIT functions
    where it cannot be built; the plain Python source under ``NUMBA_DISABLE_JIT=1``."""
    if os.environ.get("NUMBA_DISABLE_JIT", "0") not in ("", "0"):
        return _jit_kernels()
    name = module_name()
    try:
        folder = cache_dir(KERNELS_DIR)
        found = sorted(folder.glob(f"{name}.*")) or [_build(name, folder)]
    except Exception:  # no cache folder, no C compiler: the JIT path computes the same
        return _jit_kernels()
    spec = importlib.util.spec_from_file_location(name, found[0])
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def module_name() -> str:
    """The extension's module name: changes with the kernels' source, signatures, numpy and Python."""
    import numpy as np

    source = source_bytes(Path(__file__).with_name("kernels.py"))
    return "ahkernels_" + digest(source, SIGNATURES, np.__version__, sys.version, sys.platform)


def _build(name: str, folder: Path) -> Path:
    """Compile the kernels ahead of time into ``folder``; the module file is moved in when complete."""
    os.environ.setdefault("NUMBA_CACHE_DIR", str(cache_dir("numba")))
    from numba.pycc import CC

    from autohaptics.intensity import kernels

    with tempfile.TemporaryDirectory(dir=folder, prefix=".build-") as tmp, warnings.catch_warnings():
        warnings.simplefilter("ignore")
        cc = CC(name)
        cc.output_dir = tmp
        cc.verbose = False
        for kernel, signature in SIGNATURES.items():
            cc.export(kernel, signature)(getattr(kernels, kernel).py_func)
        cc.compile()
        built = next(Path(tmp).glob(f"{name}.*"))
        target = folder / built.name
        shutil.move(str(built), str(folder / f".{built.name}.tmp"))
        os.replace(folder / f".{built.name}.tmp", target)
    return target


def _jit_kernels() -> types.ModuleType:
    os.environ.setdefault("NUMBA_CACHE_DIR", str(cache_dir("numba")))
    from autohaptics.intensity import kernels

    return kernels
