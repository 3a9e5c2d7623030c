"""BLAS threading: evotol's matrices are small (tens of columns), where multi-threaded BLAS only
adds overhead — and on a busy machine OpenBLAS threads can slow a 100×12 @ 12×700 product by two
orders of magnitude (measured: 0.18 ms single-threaded vs 40 ms threaded under load). Hot paths
run under :func:`one_blas_thread` (a ``with`` block) or :func:`single_threaded_blas` (a
decorator); parallelism comes from processes (:mod:`evotol._runtime.executor`) instead, and workers must
not oversubscribe the cores.
"""
from __future__ import annotations

import functools
import sys
from typing import Callable, ParamSpec, TypeVar

from threadpoolctl import ThreadpoolController

P = ParamSpec("P")
R = TypeVar("R")


def _controller() -> ThreadpoolController:
    """The process's :class:`threadpoolctl.ThreadpoolController`, made again after any new import.

    ``threadpool_limits`` makes a new controller at every call: it walks every loaded shared library (about
    5 ms in a study process, where numba, Pinocchio and pyarrow are loaded; 136 calls in the clearance
    allocation study). A BLAS library is loaded by an import (NumPy's, SciPy's), so a controller made
    before the last import may miss one: it is made again whenever the number of imported modules changed.
    """
    return _controller_at(len(sys.modules))


@functools.lru_cache(maxsize=1)
def _controller_at(n_modules: int) -> ThreadpoolController:
    """A controller of the libraries loaded while ``n_modules`` modules are imported (kept until that changes)."""
    return ThreadpoolController()


def one_blas_thread():
    """Context manager: BLAS limited to one thread inside the ``with`` block (restored after).

    Returns
    -------
    context manager
        threadpoolctl's limiter (``ThreadpoolController.limit``); entering it limits the BLAS thread
        pools to one thread, leaving it restores the limits they had before.
    """
    return _controller().limit(limits=1, user_api="blas")


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
