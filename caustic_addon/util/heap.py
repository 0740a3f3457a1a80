"""glibc's malloc, set so that a render's arrays take the memory the last
chunk freed rather than fresh pages from the kernel.

Every bounce of every chunk allocates its arrays anew, a few MB each, from
two worker threads. glibc by default gives each thread an arena of its own,
hands back to the kernel the top of an arena that frees more than a few MB
(at most 2 x 32 MB) and a thread arena's 64 MB heaps once empty, and serves
anything larger than its adaptive threshold (128 kB at start, 32 MB at
most) with mmap, which is unmapped on free. So the same arrays keep coming
back as new pages, each a fault that the kernel zeroes.

`reuse_freed_memory` sets, for the whole process: one arena (M_ARENA_MAX),
mmap only above 64 MB (M_MMAP_THRESHOLD), free memory returned to the
kernel only above 1 GB at the top of the heap (M_TRIM_THRESHOLD), and
64 MB kept spare at the top of every heap (M_TOP_PAD), which also keeps an
arena's heaps mapped once empty. The process then keeps up to 1 GB it no
longer uses, much as jemalloc keeps its freed pages for a while:
Blender's Linux builds link jemalloc in place of glibc's malloc (the bpy
module does not), and there this changes nothing. It does nothing where
malloc is not glibc's (Windows, macOS), and leaves alone a process whose
environment already tunes glibc's malloc.

The renderer applies it where a render starts, never at import: importing
the engine leaves the process as it was. Threads that already have an
arena keep it; the pad keeps theirs from shrinking. benchmarks/allocator.py
measures it inside Blender against glibc's default."""

from __future__ import annotations

import ctypes
import os

# mallopt's parameters (glibc, malloc.h)
M_TRIM_THRESHOLD, M_TOP_PAD, M_MMAP_THRESHOLD, M_ARENA_MAX = -1, -2, -3, -8
MMAP_ABOVE = 64 << 20
TRIM_ABOVE = 1 << 30
TOP_PAD = 64 << 20
# The environment's own tunings of glibc's malloc, which are left as they are.
_TUNED_BY = ("GLIBC_TUNABLES", "MALLOC_ARENA_MAX", "MALLOC_MMAP_THRESHOLD_", "MALLOC_TRIM_THRESHOLD_",
             "MALLOC_TOP_PAD_")


def _glibc():
    """The process's C library if it is glibc (it says its version and has
    mallopt), else None."""
    try:
        libc = ctypes.CDLL(None)
        libc.gnu_get_libc_version, libc.mallopt
    except (OSError, TypeError, AttributeError):
        return None
    return libc


def tuned_by_environment() -> bool:
    """Does the environment set glibc's malloc itself?"""
    return any(name in os.environ for name in _TUNED_BY)


def reuse_freed_memory() -> bool:
    """Set glibc's malloc as the module says; True if it was set."""
    libc = _glibc()
    if libc is None or tuned_by_environment():
        return False
    return all(libc.mallopt(option, value) == 1 for option, value in (
        (M_ARENA_MAX, 1), (M_MMAP_THRESHOLD, MMAP_ABOVE), (M_TRIM_THRESHOLD, TRIM_ABOVE), (M_TOP_PAD, TOP_PAD)))
