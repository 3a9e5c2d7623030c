"""BLAS threading: evotol's matrices are small (tens of columns), where multi-threaded BLAS only
adds overhead — and on a busy machine OpenBLAS threads can slow a 100×12 @ 12×700 product by two
orders of magnitude (measured: 0.18 ms single-threaded vs 40 ms threaded under load). Hot paths
run under :func:`single_threaded_blas`; parallelism comes from processes (studies) instead.
"""
from __future__ import annotations

import functools

from threadpoolctl import threadpool_limits


def single_threaded_blas(func):
    """Decorator: run ``func`` with BLAS limited to one thread."""

    @functools.wraps(func)
    def wrapper(*args, **kwargs):
        with threadpool_limits(limits=1, user_api="blas"):
            return func(*args, **kwargs)

    return wrapper
