"""Work split into chunks on a thread pool, with progress and cancel
between chunks: Embree and numpy release the GIL for most of a chunk, so two
chunks in flight keep both cores busy."""

from __future__ import annotations

import threading
from concurrent.futures import FIRST_COMPLETED, ThreadPoolExecutor, wait
from functools import partial
from typing import Callable, Optional, TypeVar

from ..errors import Cancelled

T = TypeVar("T")
Progress = Callable[[float, str], None]
Cancel = Callable[[], bool]

# Set on a thread while it runs one of several chunks in flight.
_chunk = threading.local()


class Monitor:
    """The caller's progress and cancel callbacks, checked between chunks."""

    def __init__(self, progress: Optional[Progress] = None, cancel: Optional[Cancel] = None):
        self.progress, self.cancel = progress, cancel

    def step(self, fraction: float, stage: str) -> None:
        if self.cancel is not None and self.cancel():
            raise Cancelled(f"cancelled during the {stage}")
        if self.progress is not None:
            self.progress(min(max(fraction, 0.0), 1.0), stage)


def run_chunks(jobs: list[Callable[[], T]], threads: int, monitor: Monitor, start: float, share: float,
               stage: str, consume: Callable[[T], None]) -> None:
    """Run `jobs` with up to `threads` in flight, reporting progress from
    `start` to `start + share` and checking for cancel as each one ends.
    Each result goes to `consume` on this thread, in the jobs' order
    whichever finishes first, so that whatever is summed from them is summed
    in the same order every time; no more than `threads` results wait."""
    done, consumed = {}, 0
    if len(jobs) > 1:
        jobs = [partial(_as_chunk, job) for job in jobs]
    with ThreadPoolExecutor(threads) as pool:
        pending = {}

        def collect(futures) -> None:
            nonlocal consumed
            for future in futures:
                done[pending.pop(future)] = future.result()
            while consumed in done:
                consume(done.pop(consumed))
                consumed += 1
            monitor.step(start + share * consumed / len(jobs), stage)

        try:
            for index, job in enumerate(jobs):
                pending[pool.submit(job)] = index
                if len(pending) >= threads:
                    collect(wait(pending, return_when=FIRST_COMPLETED)[0])
            while pending:
                collect(wait(pending, return_when=FIRST_COMPLETED)[0])
        except BaseException:
            for future in pending:
                future.cancel()
            raise


def _as_chunk(job: Callable[[], T]) -> T:
    _chunk.active = True
    try:
        return job()
    finally:
        _chunk.active = False


def threads_here(threads: int) -> int:
    """Threads that work begun on this thread may split into: one inside a
    chunk of run_chunks, whose siblings in flight keep the other cores busy
    (splitting it too would only add waits), else `threads`."""
    return 1 if getattr(_chunk, "active", False) else threads


def chunk_size(total: int, limit: int, threads: int) -> int:
    """Items per chunk: at most `limit`, and few enough that each thread
    gets two chunks, so small renders use every core too: one chunk traces
    in Embree while the other shades in numpy."""
    return max(1, min(limit, -(-total // (2 * threads))))
