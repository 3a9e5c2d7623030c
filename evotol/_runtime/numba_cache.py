"""``njit(cache=True)`` that survives a cache folder nobody can write (issue 42).

numba caches compiled functions in ``__pycache__`` beside the source file, else in a user-wide
folder; on a read-only install with a read-only home neither works and ``@njit(cache=True)`` raises
``RuntimeError: cannot cache function ...: no locator available`` *at import*, killing every
serial-arm study. :func:`njit` catches that once, points numba at a private folder of the system's
temporary directory (``NUMBA_CACHE_DIR``, also inherited by worker processes), says so on one line
of stderr, and compiles without a cache if even that fails. The serial-arm kernels and the clearance
engine's Newton kernels (:mod:`evotol.robots.clearance.newton_kernel`, which falls back to its NumPy
iteration only when numba itself fails) are compiled through it.
"""
from __future__ import annotations

import logging

import os
import sys
import tempfile

_NOTED: list[str] = []


def _temporary_cache_dir() -> str:
    """A cache folder of this user in the temporary directory (kept between runs when possible)."""
    uid = os.getuid() if hasattr(os, "getuid") else os.getpid()
    folder = os.path.join(tempfile.gettempdir(), f"evotol-numba-cache-{uid}")
    os.makedirs(folder, mode=0o700, exist_ok=True)
    return folder


def _fall_back() -> bool:
    """Point numba at a temporary cache folder (once per process); False when none can be made."""
    import numba

    if not _NOTED:
        try:
            folder = _temporary_cache_dir()
        except OSError:
            folder = ""
        numba.config.CACHE_DIR = folder
        if folder:
            os.environ["NUMBA_CACHE_DIR"] = folder      # worker processes find it too
        _NOTED.append(folder)
    return bool(numba.config.CACHE_DIR)


def _say(exc: Exception, where: str) -> None:
    """One line on stderr, once per process: why and where the kernels are cached now."""
    if len(_NOTED) > 1:
        return
    _NOTED.append(where)
    logging.getLogger(__name__).warning("[evotol] numba cannot write its cache beside the code or in your home "
                                        "(%s); %s -- set NUMBA_CACHE_DIR to a writable folder to choose", exc, where)


def njit(**options):
    """``numba.njit(**options)`` whose ``cache=True`` falls back instead of failing (module docstring).

    Parameters
    ----------
    **options
        numba's ``njit`` options (``cache``, ``inline``, ``error_model``, ...).

    Returns
    -------
    callable
        A decorator compiling the function as ``numba.njit`` does.
    """
    import numba

    def decorate(fn):
        try:
            return numba.njit(**options)(fn)
        except RuntimeError as exc:
            if not options.get("cache") or "cannot cache" not in str(exc):
                raise
            if _fall_back():
                try:
                    compiled = numba.njit(**options)(fn)
                    _say(exc, f"caching in {numba.config.CACHE_DIR} instead")
                    return compiled
                except RuntimeError:
                    pass
            _say(exc, "compiling without a cache (a slower start)")
            return numba.njit(**{**options, "cache": False})(fn)
    return decorate
