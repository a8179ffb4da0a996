"""The loudness kernels of :mod:`.kernels` as machine code that loads without numba.

``from autohaptics.intensity import compiled as K; K.slopes(...)``: the first use in a process
loads the extension module built once per machine (:class:`autohaptics.aot.KernelSet`); where it
cannot be built the kernels run as numba's JIT functions (cached too), and with
``NUMBA_DISABLE_JIT=1`` as plain Python, which is the slow reference path. Arrays may have any
layout; the signatures are the types every caller passes (float64 arrays, int64 arrays and scalars).
"""

from __future__ import annotations

import functools
import os
import types

from autohaptics.aot import KernelSet
from autohaptics.cachedir import cache_dir

SIGNATURES = {
    "bank_square_smooth": "void(f8[:], f8[:,:,:], f8[:], f8[:], f8[:,:,:], f8[:,:], i8, i8, f8[:,:])",
    "sos_decimate": "void(f8[:], f8[:,:], f8[:,:], i8, i8, f8[:])",
    "core_loudness": "void(f8[:,:], f8, f8, f8, f8[:,:], f8[:,:], i8[:], i8, f8[:], f8[:], f8[:], f8[:], f8[:,:])",
    "nonlinear_decay": "void(f8[:,:], f8[:], i8, f8, f8[:], f8[:], f8[:], i8[:], f8[:,:])",
    "slopes": "void(f8[:,:], f8[:], f8[:], f8[:,:], i8[:], f8[:], f8[:,:])",
    "first_order": "void(f8[:], f8, f8, f8, f8[:], f8[:])",
    "bank_mean_square": "void(f8[:], f8[:,:,:], f8[:], i8, f8[:])",
}
KERNELS = KernelSet("ahkernels", "autohaptics.intensity.kernels", SIGNATURES)


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
    try:
        return KERNELS.built()
    except Exception:  # no cache folder, no C compiler: the JIT path computes the same
        return _jit_kernels()


def module_name() -> str:
    """The extension's module name: changes with the kernels' source, signatures, numpy and Python."""
    return KERNELS.module_name()


def _jit_kernels() -> types.ModuleType:
    os.environ.setdefault("NUMBA_CACHE_DIR", str(cache_dir("numba")))
    from autohaptics.intensity import kernels

    return kernels
