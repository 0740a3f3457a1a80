"""glibc's malloc as a render sets it (util.heap): memory a worker thread
frees comes back to the next allocation without new pages from the kernel.
Importing the engine changes nothing in the process."""

import ctypes
import os
import resource
import subprocess
import sys
import threading
from pathlib import Path

import pytest

from caustic_addon.util import heap

libc = heap._glibc()
pytestmark = pytest.mark.skipif(libc is None, reason="glibc's malloc")

PAGE = os.sysconf("SC_PAGE_SIZE")
# 40 MB: above the largest size glibc would otherwise serve from its heap (32 MB)
SIZE, ROUNDS = 40 << 20, 10
REPO = Path(__file__).resolve().parents[2]


def faults_of(work) -> int:
    """The page faults (minor) the process takes while a new thread runs `work()`."""
    before = resource.getrusage(resource.RUSAGE_SELF).ru_minflt
    thread = threading.Thread(target=work)
    thread.start()
    thread.join()
    return resource.getrusage(resource.RUSAGE_SELF).ru_minflt - before


def allocate_touch_free():
    libc.malloc.restype, libc.malloc.argtypes = ctypes.c_void_p, [ctypes.c_size_t]
    libc.free.argtypes = [ctypes.c_void_p]
    for _ in range(ROUNDS):
        block = libc.malloc(SIZE)
        ctypes.memset(block, 1, SIZE)
        libc.free(block)


@pytest.mark.skipif(heap.tuned_by_environment(), reason="the environment tunes malloc")
def test_a_worker_threads_freed_arrays_are_reused_not_faulted_in_again():
    assert heap.reuse_freed_memory()
    assert faults_of(allocate_touch_free) < ROUNDS * SIZE // PAGE / 4


@pytest.mark.skipif(heap.tuned_by_environment(), reason="the environment tunes malloc")
def test_importing_the_engine_leaves_malloc_as_it_was():
    """In a fresh process that imports the engine, the same blocks are new
    pages each round, as glibc's own settings give them."""
    script = ("import sys; sys.path.insert(0, sys.argv[1]); import caustic_addon\n"
              "from test_heap import faults_of, allocate_touch_free; print(faults_of(allocate_touch_free))")
    out = subprocess.run([sys.executable, "-c", script, str(REPO)], capture_output=True, text=True, check=True,
                         cwd=Path(__file__).parent, env={**os.environ, "PYTHONPATH": str(Path(__file__).parent)})
    assert int(out.stdout.split()[-1]) > ROUNDS * SIZE // PAGE / 2


def test_the_environments_own_tuning_is_left_alone(monkeypatch):
    monkeypatch.setenv("MALLOC_ARENA_MAX", "4")
    assert heap.reuse_freed_memory() is False
