"""Keep the C heap from holding freed memory: the 2-hour film's peak RSS (docs/BENCHMARKS.md).

glibc raises its mmap threshold each time a large block is freed (up to 32 MB), after which
numpy's multi-megabyte temporaries come from the heap and, once freed, stay resident as
fragmentation; on a 2-hour film that was 60-90 MB nobody used. :func:`bound_heap` fixes the
threshold at 1 MB for the process (large arrays are mapped and unmapped on their own), and
:func:`release_free_memory` (``malloc_trim``) returns what the decoder and the per-chunk feature
arrays freed between the pipeline's passes. Elsewhere (musl, macOS, Windows) both are no-ops.

:func:`release_library_pages` drops the process's clean pages of mapped files (the code and
read-only data of shared libraries) from its page tables; they stay in the page cache and come
back on the next touch. Right after a package is installed its files are wholly in the page
cache, so every page fault also maps the cached neighbours ("fault-around"): the same run then
held 467-501 MiB at its peak instead of 385-387 (libllvmlite.so alone 69 against 36 MiB, for
LLVM code that runs only while numba loads the compiled loudness kernels). Called between the
passes, what stays mapped is the code the next pass runs. Only mappings that are private, not
writable and hold no anonymous (copy-on-write) page are touched: their content is the file's.
"""

from __future__ import annotations

import ctypes
import functools


_M_MMAP_THRESHOLD = -3  # mallopt parameter number (malloc.h)
MMAP_THRESHOLD_BYTES = 1 << 20


@functools.cache
def _libc_fn(name: str, argtypes: tuple):
    """The C library's ``name``, looked up among the process's own symbols (``ctypes.util.find_library``
    would run ``ldconfig -p`` in a child process); None where there is none."""
    try:
        fn = getattr(ctypes.CDLL(None), name)
    except (OSError, AttributeError, TypeError):
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


_MADV_DONTNEED = 4
_SMAPS_FIELDS = ("Rss", "Anonymous", "Private_Dirty", "Shared_Dirty", "Locked")


def clean_file_mappings(smaps_text: str) -> list[tuple[int, int, int, str]]:
    """The mappings of a ``/proc/PID/smaps`` text that :func:`release_library_pages` may drop:
    file-backed, private, not writable, resident, with no anonymous, dirty or locked page.
    Returns (start, length in bytes, resident kB, path) per mapping."""
    out = []

    def flush(cur):
        if cur is None:
            return
        start, end, perms, path, f = cur
        if (path and not path.startswith("[") and perms[1] != "w" and perms[3] == "p"
                and f.get("Rss", 0) > 0 and not any(f.get(k, 1) for k in _SMAPS_FIELDS[1:])):
            out.append((start, end - start, f["Rss"], path))

    cur = None
    for line in smaps_text.splitlines():
        head = line.split(None, 5)
        if len(head) >= 5 and "-" in head[0] and ":" in head[3] and not head[0].endswith(":"):
            flush(cur)
            lo, hi = head[0].split("-")
            cur = (int(lo, 16), int(hi, 16), head[1], head[5].strip() if len(head) > 5 else "", {})
        elif cur is not None and len(head) >= 2 and head[0].endswith(":") and head[0][:-1] in _SMAPS_FIELDS:
            cur[4][head[0][:-1]] = int(head[1])
    flush(cur)
    return out


def release_library_pages() -> int:
    """Drop the clean pages of mapped files from this process (module docstring); the kB it held
    in them. 0 where there is no /proc/self/smaps or no madvise (not Linux)."""
    try:
        with open("/proc/self/smaps") as fh:
            text = fh.read()
    except OSError:
        return 0
    madvise = _libc_fn("madvise", (ctypes.c_void_p, ctypes.c_size_t, ctypes.c_int))
    if madvise is None:
        return 0
    released = 0
    for start, length, rss_kb, _path in clean_file_mappings(text):
        if madvise(ctypes.c_void_p(start), ctypes.c_size_t(length), _MADV_DONTNEED) == 0:
            released += rss_kb
    return released





def release_between_passes() -> None:
    """What a process that runs the pipeline does between its audio and video passes: the decoder's
    and the feature chunks' freed heap back to the OS, and the library pages only the finished pass
    touched (e.g. LLVM's code, which ran only to load the compiled kernels) dropped."""
    release_free_memory()
    release_library_pages()
