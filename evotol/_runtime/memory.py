"""How much memory the machine can give a study now (bytes): ``MemAvailable`` of ``/proc/meminfo``
(Linux), else the free physical pages (``os.sysconf``); None where neither is known."""
from __future__ import annotations

import os


def available_bytes() -> int | None:
    """The memory a new allocation can take without swapping (bytes), or None if unknown.

    Returns
    -------
    int or None
        ``MemAvailable`` (Linux, kB converted to bytes), else ``SC_AVPHYS_PAGES * SC_PAGE_SIZE``.
    """
    try:
        with open("/proc/meminfo", encoding="ascii") as f:
            for line in f:
                if line.startswith("MemAvailable:"):
                    return int(line.split()[1]) * 1024
    except (OSError, ValueError, IndexError):
        pass
    try:
        return int(os.sysconf("SC_AVPHYS_PAGES")) * int(os.sysconf("SC_PAGE_SIZE"))
    except (AttributeError, ValueError, OSError):
        return None
