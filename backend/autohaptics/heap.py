"""Keep the C heap from holding freed memory: the 2-hour film's peak RSS (docs/BENCHMARKS.md).

glibc raises its mmap threshold each time a large block is freed (up to 32 MB), after which
numpy's multi-megabyte temporaries come from the heap and, once freed, stay resident as
fragmentation; on a 2-hour film that was 60-90 MB nobody used. :func:`bound_heap` fixes the
threshold at 1 MB for the process (large arrays are mapped and unmapped on their own), and
:func:`release_free_memory` (``malloc_trim``) returns what the decoder and the per-chunk feature
arrays freed between the pipeline's passes. Elsewhere (musl, macOS, Windows) both are no-ops.
"""

from __future__ import annotations

import ctypes
import ctypes.util
import functools


_M_MMAP_THRESHOLD = -3  # mallopt parameter number (malloc.h)
MMAP_THRESHOLD_BYTES = 1 << 20


@functools.cache
def _libc_fn(name: str, argtypes: tuple):
    lib = ctypes.util.find_library("c")
    try:
        fn = getattr(ctypes.CDLL(lib), name) if lib else None
    except (OSError, AttributeError):
        return None
    if fn is not None:
        fn.argtypes, fn.restype = list(argtypes), ctypes.c_int
    return fn


def bound_heap(mmap_threshold_bytes: int = MMAP_THRESHOLD_BYTES) -> bool:
    """Fix glibc's mmap threshold for this process (blocks of at least this many bytes are mapped
    on their own and given back when freed); True when the C library took it. Call once, early."""
    fn = _libc_fn("mallopt", (ctypes.c_int, ctypes.c_int))
    return bool(fn(_M_MMAP_THRESHOLD, int(mmap_threshold_bytes))) if fn is not None else False


def release_free_memory() -> bool:
    """Return the C heap's free pages to the OS; True when the C library could (glibc)."""
    fn = _libc_fn("malloc_trim", (ctypes.c_size_t,))
    return bool(fn(0)) if fn is not None else False


__all__ = ["MMAP_THRESHOLD_BYTES", "bound_heap", "release_free_memory"]
