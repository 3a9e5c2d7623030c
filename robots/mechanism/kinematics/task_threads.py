"""Independent compiled tasks run on the machine's cores by Python threads (issue 43).

The serial-arm Monte Carlo kernels release the GIL (``numba.njit(nogil=True)``) and each writes its own
rows of the output, so a range of tasks can run in any thread. Threads, rather than ``numba.prange``,
because a ``parallel=True`` kernel costs about 4 s more of compilation in every fresh process (the
parfor lowering) and numba's fork-safe threading layer may not be entered from two threads at once;
each task's arithmetic is the same whichever thread runs it, so the results do not depend on the
number of threads.
"""
from __future__ import annotations

import os
import threading
from concurrent.futures import ThreadPoolExecutor
from typing import Callable

#: ranges of tasks per thread (a few, so that two threads end together when tasks differ in cost)
PIECES_PER_THREAD = 4
#: the threads, made at the first parallel call and kept (a pool per call cost 10 % of a shared-samples
#: Monte Carlo of 20 000 samples, which calls :func:`run_tasks` twice per 512 samples)
_POOL: list[tuple[int, ThreadPoolExecutor]] = []


def _forget_pool() -> None:
    """In a forked child the pool's threads do not exist: make a new pool there when one is needed."""
    _POOL.clear()


os.register_at_fork(after_in_child=_forget_pool)


def threads_available() -> int:
    """Threads the compiled tasks may use.

    Returns
    -------
    int
        numba's thread count (``NUMBA_NUM_THREADS``, the machine's cores by default) from the main thread,
        1 from any other (its caller already runs in parallel).
    """
    if threading.current_thread() is not threading.main_thread():
        return 1
    import numba

    return max(1, int(numba.config.NUMBA_NUM_THREADS))


def run_tasks(run: Callable[[int, int], None], total: int, threads: int | None = None) -> None:
    """Call ``run(b0, b1)`` on contiguous ranges covering tasks ``0 <= b < total``, on up to ``threads`` threads.

    Parameters
    ----------
    run : callable
        ``run(b0, b1)`` runs tasks ``b0 <= b < b1`` (a compiled function that releases the GIL and writes
        its own part of the output).
    total : int
        Number of tasks.
    threads : int or None
        Largest number of threads; None: :func:`threads_available`.
    """
    threads = min(total, threads_available() if threads is None else max(1, int(threads)))
    if threads <= 1:
        if total > 0:
            run(0, total)
        return
    if not _POOL or _POOL[0][0] < threads:
        _POOL[:] = [(threads, ThreadPoolExecutor(max_workers=threads, thread_name_prefix="evotol-kernel"))]
    size, pool = _POOL[0]
    pieces = min(total, threads * PIECES_PER_THREAD) if threads == size else threads   # at most `threads` at once
    cuts = [total * k // pieces for k in range(pieces + 1)]
    futures = [pool.submit(run, a, b) for a, b in zip(cuts[:-1], cuts[1:])]
    try:
        for f in futures:
            f.result()
    finally:                        # Ctrl-C or an error: the ranges not started are not run
        for f in futures:
            f.cancel()
