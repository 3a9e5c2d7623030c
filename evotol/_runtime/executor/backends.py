"""Where chunks run: in this process, on local processes, or on a Dask cluster.

The chunks do not depend on where they run, so all three return identical results; callers
choose the chunking (a fixed chunk size keeps local and Dask runs comparable).

The parameters several definitions of this module share are described once, here.

Parameters
----------
fn : callable
    Picklable (a module-level function) when it runs in other processes.
items : sequence
    The items, one call each.
"""
from __future__ import annotations

import asyncio
import logging
import os
from concurrent.futures import FIRST_COMPLETED, CancelledError, ProcessPoolExecutor, wait
from typing import Any, Callable, Sequence

from evotol._runtime.orphans import end_with_parent
from evotol.errors import EvotolError, SchedulerLost, ValidationError

#: ``on_done(index, result)``: called in this process for every finished item
OnDone = Callable[[int, Any], None]

#: the Dask scheduler address ``evotol reproduce --scheduler ADDRESS`` hands to the studies
SCHEDULER_ENV = "EVOTOL_DASK_SCHEDULER"


def scheduler_of(configured=None):
    """The Dask scheduler a run uses.

    Parameters
    ----------
    configured : str, distributed.Client or None
        The study config's ``scheduler``.

    Returns
    -------
    str, Client or None
        ``configured`` if given, else the address in the environment variable ``EVOTOL_DASK_SCHEDULER``
        (set by ``evotol reproduce --scheduler``), else None: local processes.
    """
    return configured or os.environ.get(SCHEDULER_ENV) or None


def worker_count(workers: int | None) -> int:
    """Number of local processes: ``workers``, or all cores when None; a ValidationError below 1.

    Parameters
    ----------
    workers : int or None
        The processes asked for (anything ``int()`` accepts); None: ``os.cpu_count()``.

    Returns
    -------
    int
        The number of processes, at least 1.

    Raises
    ------
    ValidationError
        ``workers`` is not an integer or is below 1.
    """
    if workers is None:
        return os.cpu_count() or 1
    try:
        n = int(workers)
    except (TypeError, ValueError):
        n = 0
    if n < 1:
        raise ValidationError("workers", workers, "a positive number of processes")
    return n


def run_chunks(fn: Callable, items: Sequence, on_done: OnDone, *, common: tuple = (),
               workers: int | None = None, scheduler=None) -> str:
    """Call ``fn(*common, items[i])`` for every i and ``on_done(i, result)`` as each finishes.

    An exception in ``fn`` or ``on_done``, or a Ctrl-C, stops the running items (local
    processes are terminated, Dask futures cancelled) and is raised again; the items finished
    before it have been handed to ``on_done``.

    Parameters
    ----------
    on_done : callable
        ``on_done(i, result)``, called in this process for every finished item, in the order
        they finish.
    common : tuple, optional
        Arguments shared by all items (e.g. an evaluator); on Dask they are scattered to every
        worker once instead of travelling with every item.
    workers : int, optional
        Local processes (None: all cores; 1 or a single item: in this process, no pickling).
    scheduler : str or distributed.Client, optional
        A Dask scheduler address (``"tcp://host:8786"``, ``"inproc://..."``) or a
        ``distributed.Client``; the items then run on that cluster (``workers`` is ignored).

    Returns
    -------
    str
        A short description of the backend used ("in-process", "2 local processes",
        "dask ...", or "nothing to run" for no items).

    Raises
    ------
    ValidationError
        ``workers`` below 1 (:func:`worker_count`), or a ``scheduler`` without
        ``dask.distributed`` installed.
    evotol.errors.SchedulerLost
        The Dask scheduler did not answer at the start, or was lost during the run (its connection
        closed; distributed's reconnection tracebacks are not logged); the items finished before
        have been handed to ``on_done``.
    """
    items = list(items)
    if not items:
        return "nothing to run"
    if scheduler is not None:
        _run_dask(scheduler, fn, common, items, on_done)
        return f"dask {scheduler}"
    n = min(worker_count(workers), len(items))
    if n == 1:
        for i, x in enumerate(items):
            on_done(i, fn(*common, x))
        return "in-process"
    _run_processes(n, fn, common, items, on_done)
    return f"{n} local processes"


def parallel_map(fn: Callable, items: Sequence, *, common: tuple = (), workers: int | None = None,
                 scheduler=None) -> list:
    """``[fn(*common, x) for x in items]`` on local processes or a Dask cluster; order preserved.

    Parameters
    ----------
    common : tuple, optional
        Arguments shared by all items, passed before the item.
    workers : int, optional
        Local processes (None: all cores); see :func:`run_chunks`.
    scheduler : str or distributed.Client, optional
        A Dask scheduler; see :func:`run_chunks`.

    Returns
    -------
    list
        ``fn``'s result for every item, in the order of ``items``.

    Raises
    ------
    ValidationError
        As :func:`run_chunks`.
    """
    items = list(items)
    out: list = [None] * len(items)

    def keep(i, r):
        out[i] = r

    run_chunks(fn, items, keep, common=common, workers=workers, scheduler=scheduler)
    return out


def _run_processes(n: int, fn, common, items, on_done: OnDone) -> None:
    # initargs: the parent's pid as the worker starts would be the pool's manager; this process is the parent
    pool = ProcessPoolExecutor(max_workers=n, initializer=end_with_parent, initargs=(os.getpid(),))
    pending = {pool.submit(fn, *common, x): i for i, x in enumerate(items)}
    try:
        while pending:
            finished, _ = wait(pending, return_when=FIRST_COMPLETED)
            for fut in finished:
                on_done(pending.pop(fut), fut.result())
    except BaseException:
        # interrupted (Ctrl-C) or an item failed: what finished was handed on; stop the running
        # items now instead of waiting for them
        for fut in pending:
            fut.cancel()
        for proc in list((getattr(pool, "_processes", None) or {}).values()):
            proc.terminate()
        pool.shutdown(wait=False, cancel_futures=True)
        raise
    pool.shutdown(wait=True)


class _QuietReconnect(logging.Filter):
    """Drops what distributed's client logs while it tries to reach a lost scheduler again (the
    tracebacks of a reconnection given up): the run ends with one :class:`SchedulerLost` line."""

    def filter(self, record: logging.LogRecord) -> bool:
        exc = record.exc_info[1] if record.exc_info else None
        return not (isinstance(exc, (asyncio.CancelledError, CancelledError, OSError))
                    or record.getMessage().startswith("Failed to reconnect"))


def _lost(client, exc: BaseException) -> bool:
    """Whether ``exc`` means the scheduler is gone: its futures were cancelled for a lost
    connection, or a cancellation or a comm error while the client is no longer running (an
    OSError raised by ``fn`` itself, with the scheduler there, is not)."""
    if isinstance(exc, EvotolError):
        return False
    if getattr(exc, "reason", None) == "scheduler-connection-lost":
        return True
    return (isinstance(exc, (asyncio.CancelledError, CancelledError, OSError, TimeoutError))
            and getattr(client, "status", "running") != "running")


def _run_dask(scheduler, fn, common, items, on_done: OnDone) -> None:
    try:
        from distributed import Client, as_completed
    except ImportError as exc:   # pragma: no cover - dask is an optional dependency
        raise ValidationError("scheduler", scheduler, "dask[distributed] installed (pip install evotol[dask])") from exc
    own = not isinstance(scheduler, Client)
    address = str(scheduler) if own else str(getattr(scheduler.scheduler, "address", scheduler))
    quiet, client_log = _QuietReconnect(), logging.getLogger("distributed.client")
    client_log.addFilter(quiet)
    client = None
    try:
        try:
            client = Client(scheduler, set_as_default=False) if own else scheduler
        except (OSError, TimeoutError) as exc:       # nothing answers there (distributed's connect timeout)
            raise SchedulerLost(address, f"no answer at the start: {(str(exc).splitlines() or [type(exc).__name__])[0]}") from exc
        futures: dict = {}
        done = 0
        try:
            shared = client.scatter(list(common), broadcast=True) if common else []
            futures = {client.submit(fn, *shared, x, pure=False): i for i, x in enumerate(items)}
            for fut in as_completed(list(futures), loop=client.loop):
                result = fut.result()
                on_done(futures[fut], result)
                done += 1
        except BaseException as exc:
            if _lost(client, exc):
                raise SchedulerLost(address, f"the connection closed after {done} of the {len(items)} chunks "
                                             "sent to it") from exc
            client.cancel(list(futures))
            raise
    finally:
        if own and client is not None:
            client.close()
        client_log.removeFilter(quiet)
