"""Run a serial numba kernel on contiguous ranges of its rows, on several threads at once.

The solver's kernels are compiled without ``parallel=True`` (numba's parallel-loop passes triple the
compile time of a kernel, and that compile time is what a first run waits for) and with ``nogil=True``,
so that plain Python threads run them side by side. A kernel takes ``(worker, lo, hi, *args)`` and does
rows ``lo .. hi - 1``; ``worker`` (``0 .. threads - 1``) is unique among the calls running at the same
time, for per-thread scratch space. The number of threads is numba's (:func:`numba.get_num_threads`
of the calling thread, which ``NUMBA_NUM_THREADS`` and :func:`numba.set_num_threads` set).
"""

from __future__ import annotations

import itertools
import os
import threading
from concurrent.futures import ThreadPoolExecutor

import numba

#: Ranges per thread: more than one so that threads whose rows are cheap take over the rest.
PIECES_PER_THREAD = 4
#: Ranges per thread when :func:`for_ranges` reports progress (each report is a chance to stop).
PROGRESS_PIECES_PER_THREAD = 32

_lock = threading.Lock()
_pool: ThreadPoolExecutor | None = None
_pool_size = 0
_pool_pid = 0


def thread_count() -> int:
    """Threads a kernel call uses: numba's setting for the calling thread."""
    return max(1, int(numba.get_num_threads()))


def _executor(size: int) -> ThreadPoolExecutor:
    global _pool, _pool_size, _pool_pid
    with _lock:
        if _pool is None or _pool_pid != os.getpid() or _pool_size < size:
            _pool = ThreadPoolExecutor(max_workers=size, thread_name_prefix="translucency-kernel")
            _pool_size, _pool_pid = size, os.getpid()
        return _pool


def for_ranges(kernel, n: int, *args, pieces_per_thread: int = PIECES_PER_THREAD, progress=None) -> None:
    """Call ``kernel(worker, lo, hi, *args)`` over ``range(n)`` cut into contiguous ranges, in parallel.

    Parameters
    ----------
    kernel : numba dispatcher compiled with ``nogil=True``
        Does rows ``lo .. hi - 1``; must write disjoint rows of its outputs.
    n : int
        Number of rows.
    pieces_per_thread : int
        Ranges per thread (taken in turn by whichever thread is free).
    progress : callable, optional
        ``progress(fraction)`` after each range, on the thread that did it (the ranges are then
        :data:`PROGRESS_PIECES_PER_THREAD` per thread). If it raises, no further range is started and the
        exception is raised once the ranges running have ended.
    """
    threads = min(thread_count(), max(int(n), 1))
    if threads == 1:
        if n > 0:
            kernel(0, 0, n, *args)
        return
    if progress is not None:
        pieces_per_thread = max(pieces_per_thread, PROGRESS_PIECES_PER_THREAD)
    pieces = pieces_per_thread * threads
    bounds = [n * i // pieces for i in range(pieces + 1)]
    turn = itertools.count()  # next() on a count is atomic under the GIL
    stopped = threading.Event()

    finished = itertools.count(1)

    def run(worker):
        while not stopped.is_set():
            i = next(turn)
            if i >= pieces:
                return
            if bounds[i] < bounds[i + 1]:
                kernel(worker, bounds[i], bounds[i + 1], *args)
            if progress is not None:
                try:
                    progress(min(next(finished), pieces) / pieces)
                except BaseException:
                    stopped.set()
                    raise

    pool = _executor(threads - 1)
    helpers = [pool.submit(run, worker) for worker in range(1, threads)]
    try:
        run(0)
    finally:
        for helper in helpers:
            helper.result()
