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

# A thread's share of the cores while it runs a chunk (`threads`), else none.
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
    cores = max(1, threads // max(1, min(threads, len(jobs))))
    jobs = [partial(_as_chunk, job, cores) for job in jobs]
    with ThreadPoolExecutor(threads) as pool:
        pending = {}

        def finished(futures) -> None:
            for future in futures:
                done[pending.pop(future)] = future.result()

        def consume_ready() -> None:
            nonlocal consumed
            while consumed in done:
                consume(done.pop(consumed))
                consumed += 1
            monitor.step(start + share * consumed / len(jobs), stage)

        try:
            for index, job in enumerate(jobs):
                # the next chunk starts before the last results are consumed,
                # so that no core waits while this thread sums them
                pending[pool.submit(job)] = index
                consume_ready()
                if len(pending) >= threads:
                    finished(wait(pending, return_when=FIRST_COMPLETED)[0])
            while consumed < len(jobs):
                finished(wait(pending, return_when=FIRST_COMPLETED)[0])
                consume_ready()
        except BaseException:
            for future in pending:
                future.cancel()
            raise


def _as_chunk(job: Callable[[], T], cores: int) -> T:
    _chunk.threads = cores
    try:
        return job()
    finally:
        _chunk.threads = None


def threads_here(threads: int) -> int:
    """Threads that work begun on this thread may split into, of
    `threads`: inside a chunk of run_chunks, its share of the cores beside
    the chunks in flight with it (one when they are as many as the
    threads: splitting it too would only add waits)."""
    share = getattr(_chunk, "threads", None)
    return threads if share is None else min(threads, share)


def chunk_size(total: int, limit: int, threads: int) -> int:
    """Items per chunk: at most `limit`, and few enough that each thread
    gets two chunks, so small renders use every core too: one chunk traces
    in Embree while the other shades in numpy."""
    return max(1, min(limit, -(-total // (2 * threads))))
