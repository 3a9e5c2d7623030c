"""Worker processes end with their parent (issue 42).

``kill -9`` of ``evotol reproduce`` used to leave its pool workers running (about 280 MB each,
indefinitely): a killed parent cannot tell them to stop. :func:`end_with_parent`, called in each
worker as it starts (the process pool's ``initializer``, a study subprocess's ``preexec_fn``),
asks Linux to send the worker ``SIGTERM`` when its parent dies (``prctl(PR_SET_PDEATHSIG)``,
``man 2 prctl``); elsewhere a daemon thread checks every second whether the parent changed
(``os.getppid()``) and ends the worker then.
"""
from __future__ import annotations

import ctypes
import ctypes.util
import os
import signal
import sys
import threading
import time

from evotol._runtime.atomic_files import pid_alive

PR_SET_PDEATHSIG = 1      # <linux/prctl.h>


def _prctl_death_signal() -> bool:
    """Ask Linux to send SIGTERM to this process when its parent ends; True when it took."""
    if not sys.platform.startswith("linux"):
        return False
    try:
        libc = ctypes.CDLL(ctypes.util.find_library("c") or "libc.so.6", use_errno=True)
        return libc.prctl(PR_SET_PDEATHSIG, int(signal.SIGTERM), 0, 0, 0) == 0
    except (OSError, AttributeError):
        return False


def _watch_parent(parent: int, every: float) -> None:
    while pid_alive(parent):
        time.sleep(every)
    os._exit(1)              # the parent is gone: nobody will read this worker's results


def end_with_parent(parent: int | None = None, every: float = 1.0) -> str:
    """Make this process end when its parent does (module docstring).

    Parameters
    ----------
    parent : int, optional
        The pid of the process whose end ends this one (default: ``os.getppid()`` now; a pool
        started through a fork server passes the pool's owner). If it has already ended, this
        process ends at once.
    every : float, optional
        Seconds between checks of the watchdog thread (non-Linux systems), default 1.

    Returns
    -------
    str
        ``"prctl"`` (Linux) or ``"watchdog"``.
    """
    parent = os.getppid() if parent is None else parent
    if _prctl_death_signal():
        if not pid_alive(parent):         # it died before prctl took effect
            os._exit(1)
        return "prctl"
    threading.Thread(target=_watch_parent, args=(parent, every), daemon=True, name="evotol-parent-watch").start()
    return "watchdog"
