"""BLAS threading: evotol's matrices are small (tens of columns), where multi-threaded BLAS only
adds overhead — and on a busy machine OpenBLAS threads can slow a 100×12 @ 12×700 product by two
orders of magnitude (measured: 0.18 ms single-threaded vs 40 ms threaded under load). Hot paths
run under :func:`one_blas_thread` (a ``with`` block) or :func:`single_threaded_blas` (a
decorator); parallelism comes from processes (:mod:`evotol._runtime.executor`) instead, and workers must
not oversubscribe the cores.
"""
from __future__ import annotations

import functools
from typing import Callable, ParamSpec, TypeVar

from threadpoolctl import threadpool_limits

P = ParamSpec("P")
R = TypeVar("R")


def one_blas_thread():
    """Context manager: BLAS limited to one thread inside the ``with`` block (restored after).

    Returns
    -------
    threadpoolctl.threadpool_limits
        The context manager; entering it limits the BLAS thread pools to one thread, leaving it
        restores the previous limits.
    """
    return threadpool_limits(limits=1, user_api="blas")


def single_threaded_blas(func: Callable[P, R]) -> Callable[P, R]:
    """Decorator: run ``func`` with BLAS limited to one thread.

    Parameters
    ----------
    func : callable
        The function to wrap.

    Returns
    -------
    callable
        A wrapper with ``func``'s name and docstring that calls ``func`` inside
        :func:`one_blas_thread` and returns its result.
    """

    @functools.wraps(func)
    def wrapper(*args: P.args, **kwargs: P.kwargs) -> R:
        with one_blas_thread():
            return func(*args, **kwargs)

    return wrapper
