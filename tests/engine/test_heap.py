"""glibc's malloc as the engine sets it (util.heap): memory a worker thread
frees comes back to the next allocation without new pages from the kernel."""

import ctypes
import os
import resource
import threading

import pytest

import caustic_addon  # noqa: F401  (importing the engine sets the heap)
from caustic_addon.util import heap

libc = heap._glibc()
pytestmark = pytest.mark.skipif(libc is None, reason="glibc's malloc")

PAGE = os.sysconf("SC_PAGE_SIZE")


def faults_of(work) -> int:
    """The page faults (minor) the process takes while a new thread runs `work()`."""
    before = resource.getrusage(resource.RUSAGE_SELF).ru_minflt
    thread = threading.Thread(target=work)
    thread.start()
    thread.join()
    return resource.getrusage(resource.RUSAGE_SELF).ru_minflt - before


@pytest.mark.skipif(heap.tuned_by_environment(), reason="the environment tunes malloc")
def test_a_worker_threads_freed_arrays_are_reused_not_faulted_in_again():
    # 40 MB: above the largest size glibc would otherwise serve from its heap (32 MB)
    size, rounds = 40 << 20, 10
    libc.malloc.restype, libc.malloc.argtypes = ctypes.c_void_p, [ctypes.c_size_t]
    libc.free.argtypes = [ctypes.c_void_p]

    def allocate_touch_free():
        for _ in range(rounds):
            block = libc.malloc(size)
            ctypes.memset(block, 1, size)
            libc.free(block)

    pages = rounds * size // PAGE
    assert faults_of(allocate_touch_free) < pages / 4


def test_the_environments_own_tuning_is_left_alone(monkeypatch):
    monkeypatch.setenv("MALLOC_ARENA_MAX", "4")
    assert heap.reuse_freed_memory() is False
