"""autohaptics.runner.heap: the C heap gives freed multi-megabyte temporaries back to the OS."""

import os
import subprocess
import sys
import textwrap

import pytest

from autohaptics.runner import heap

linux_glibc = pytest.mark.skipif(not sys.platform.startswith("linux"), reason="glibc's mallopt/malloc_trim")

_PROBE = textwrap.dedent("""
    import sys, numpy as np
    from autohaptics.runner.heap import bound_heap
    if sys.argv[1] == "bound":
        assert bound_heap()
    def rss():
        with open("/proc/self/statm") as fh:
            return int(fh.read().split()[1]) * 4096 / 2**20
    # What fragments the heap without a fixed threshold: a large block freed (the threshold rises
    # to its size), then many mid-size temporaries, one of which outlives the rest.
    np.ones((8 << 20) // 8)
    keep = []
    for i in range(40):
        a = np.ones((3 << 20) // 8)
        if i % 10 == 9:
            keep.append(np.ones(1024))
    del a
    base = rss()
    print(round(base, 1))
""")


@linux_glibc
def test_release_and_bound_are_accepted_by_glibc():
    assert heap.release_free_memory() in (True, False)  # 1 when memory was released, else 0
    assert heap.bound_heap() is True


@linux_glibc
def test_a_bounded_heap_keeps_less_freed_memory_resident():
    # glibc's MALLOC_* variables (Dask sets MALLOC_TRIM_THRESHOLD_ for its workers) fix the threshold too
    env = {k: v for k, v in os.environ.items() if not k.startswith("MALLOC_") and k != "GLIBC_TUNABLES"}

    def run(mode):
        out = subprocess.run([sys.executable, "-c", _PROBE, mode], capture_output=True, text=True, check=True,
                             env=env)
        return float(out.stdout.strip())

    free, bound = run("default"), run("bound")
    assert bound < free, (free, bound)


_SMAPS = """\
7f0000000000-7f0000200000 r-xp 00000000 08:01 1234                       /usr/lib/libcode.so
Size:               2048 kB
Rss:                 900 kB
Shared_Dirty:          0 kB
Private_Dirty:         0 kB
Anonymous:             0 kB
Locked:                0 kB
7f0000200000-7f0000210000 r--p 00200000 08:01 1234                       /usr/lib/libcode.so
Size:                 64 kB
Rss:                  64 kB
Shared_Dirty:          0 kB
Private_Dirty:        64 kB
Anonymous:            64 kB
Locked:                0 kB
7f0000210000-7f0000220000 rw-p 00210000 08:01 1234                       /usr/lib/libcode.so
Size:                 64 kB
Rss:                  12 kB
Shared_Dirty:          0 kB
Private_Dirty:         0 kB
Anonymous:             0 kB
Locked:                0 kB
7f0000300000-7f0000400000 r--s 00000000 08:01 99                         /dev/shm/shared
Size:               1024 kB
Rss:                 100 kB
Shared_Dirty:          0 kB
Private_Dirty:         0 kB
Anonymous:             0 kB
Locked:                0 kB
7f0000400000-7f0000500000 r--p 00000000 08:01 77                         /data/film.bin
Size:               1024 kB
Rss:                   0 kB
Shared_Dirty:          0 kB
Private_Dirty:         0 kB
Anonymous:             0 kB
Locked:                0 kB
7f0000500000-7f0000600000 r--p 00000000 00:00 0                          [vvar]
Size:               1024 kB
Rss:                   8 kB
Shared_Dirty:          0 kB
Private_Dirty:         0 kB
Anonymous:             0 kB
Locked:                0 kB
7f0000600000-7f0000700000 r-xp 00000000 08:01 55                         /usr/lib/libpinned.so
Size:               1024 kB
Rss:                  40 kB
Shared_Dirty:          0 kB
Private_Dirty:         0 kB
Anonymous:             0 kB
Locked:               40 kB
7ffd00000000-7ffd00021000 rw-p 00000000 00:00 0                          [stack]
Size:                132 kB
Rss:                  40 kB
Anonymous:            40 kB
"""


def test_only_clean_private_read_only_file_pages_are_chosen():
    """Code of a library: yes. Its relocated (copy-on-write) read-only data, its writable data, a
    shared mapping, a mapping with nothing resident, the kernel's [vvar], locked pages: no."""
    assert heap.clean_file_mappings(_SMAPS) == [(0x7f0000000000, 0x200000, 900, "/usr/lib/libcode.so")]
    assert heap.clean_file_mappings("") == []


_RELEASE_PROBE = textwrap.dedent("""
    import numpy as np, cv2, scipy.signal
    from autohaptics.runner.heap import release_library_pages
    def rss():
        with open("/proc/self/statm") as fh:
            return int(fh.read().split()[1]) * 4096 / 2**20
    x = np.linspace(0, 1, 4096)
    sos = scipy.signal.butter(4, 0.1, output="sos")
    before_y = scipy.signal.sosfilt(sos, x)
    before_img = cv2.resize(np.arange(256, dtype=np.uint8).reshape(16, 16), (4, 4), interpolation=cv2.INTER_AREA)
    before = rss()
    released = release_library_pages()
    after = rss()
    # the libraries still run, with the same results
    assert np.array_equal(scipy.signal.sosfilt(sos, x), before_y)
    assert np.array_equal(cv2.resize(np.arange(256, dtype=np.uint8).reshape(16, 16), (4, 4),
                                     interpolation=cv2.INTER_AREA), before_img)
    print(round(before, 1), round(after, 1), released)
""")


@linux_glibc
def test_releasing_library_pages_lowers_rss_and_the_libraries_still_work():
    out = subprocess.run([sys.executable, "-c", _RELEASE_PROBE], capture_output=True, text=True, check=True)
    before, after, released_kb = (float(v) for v in out.stdout.split())
    assert released_kb > 10_000, out.stdout  # numpy, scipy and OpenCV's code: tens of MB
    assert after < before - 10, out.stdout
