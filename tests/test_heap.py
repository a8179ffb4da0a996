"""autohaptics.heap: the C heap gives freed multi-megabyte temporaries back to the OS."""

import os
import subprocess
import sys
import textwrap

import pytest

from autohaptics import heap

linux_glibc = pytest.mark.skipif(not sys.platform.startswith("linux"), reason="glibc's mallopt/malloc_trim")

_PROBE = textwrap.dedent("""
    import sys, numpy as np
    from autohaptics.heap import bound_heap
    if sys.argv[1] == "bound":
        assert bound_heap()
    def rss():
        with open("/proc/self/statm") as fh:
            return int(fh.read().split()[1]) * 4096 / 2**20
    # What fragments the heap without a fixed threshold: a large block freed (the threshold rises
    # to its size), then many mid-size temporaries, one of which outlives the rest.
    np.ones(8 << 20 // 8)
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
