"""The installed entry points of one group, read once per ``sys.path`` (issue 43).

``importlib.metadata.entry_points(group=...)`` reads every installed distribution's metadata on each
call: about 15 ms on a machine with a few hundred packages. A study file names a cost model per
tolerance table and a robot or measure per lookup, so a 36-source study spent 0.56 s of its
0.7 s of set-up reading the same files 38 times. The entry points are kept per group and per
``sys.path`` (a folder added to it, as a plugin beside a script, is read anew).
"""
from __future__ import annotations

import sys
from functools import lru_cache
from importlib.metadata import EntryPoint, entry_points


@lru_cache(maxsize=64)
def _read(group: str, path: tuple) -> tuple[EntryPoint, ...]:
    return tuple(entry_points(group=group))


def group_entry_points(group: str) -> tuple[EntryPoint, ...]:
    """The installed entry points of ``group`` (``importlib.metadata.entry_points(group=group)``).

    Parameters
    ----------
    group : str
        The entry-point group, e.g. ``"evotol.cost_models"``.

    Returns
    -------
    tuple of importlib.metadata.EntryPoint
        As installed when this ``sys.path`` was first read; not loaded.
    """
    return _read(group, tuple(sys.path))
