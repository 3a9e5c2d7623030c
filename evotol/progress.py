"""Progress a log file can show: periodic lines while a study runs, when no terminal is attached.

Progress bars (tqdm) switch themselves off when stdout is not a terminal, so ``evotol reproduce
yao2013 > log`` used to print nothing for 28 s (issue 15). :class:`Heartbeat` prints one line
every ``every`` seconds -- elapsed time and the expected time of a full run -- from a daemon
thread, only when the stream is not a terminal, and stops when the study ends.

``EXPECTED_SECONDS``: full-run times of the seed studies measured on the project's 2-core
machine, each study alone (2026-11-23; the engine studies after the compiled Newton iteration of
issue 13's fourth session, with the numba cache warm; `evotol reproduce all` runs two at a time,
longest first, so these also set its order); ``--quick`` runs are much shorter. They are a
guide, not a promise: the load of the machine changes them.
"""
from __future__ import annotations

import sys
import threading
import time

EXPECTED_SECONDS = {
    "brahmia2023-delta": 42, "chase1990-clutch": 5, "deng2012-5bar": 21, "deng2012-clearalloc": 9,
    "deng2012-dimsynth": 35, "deng2012-irsbot2": 56, "deng2012-tolsynth": 17, "laramolina2019-5r": 33,
    "mechanisms": 8, "process-stack": 4, "yao2013": 30,
}


def expected(name: str) -> str:
    """'about 21 s' / 'about 3 min' for a seed study, '' when unknown."""
    s = EXPECTED_SECONDS.get(name)
    if s is None:
        return ""
    return f"about {s:.0f} s" if s < 100 else f"about {s / 60:.0f} min"


class Heartbeat:
    """``with Heartbeat("yao2013"): study.run(...)`` -- a line every ``every`` s on a non-terminal."""

    def __init__(self, name: str, every: float = 10.0, stream=None, force: bool = False):
        self.name, self.every = name, float(every)
        self.stream = stream if stream is not None else sys.stdout
        isatty = getattr(self.stream, "isatty", lambda: False)
        self.active = force or not isatty()
        self._stop = threading.Event()
        self._thread = None

    def _beat(self) -> None:
        t0 = time.perf_counter()
        hint = expected(self.name)
        while not self._stop.wait(self.every):
            elapsed = time.perf_counter() - t0
            print(f"[evotol] {self.name}: running for {elapsed:.0f} s" + (f" (a full run takes {hint})" if hint else ""),
                  file=self.stream, flush=True)

    def __enter__(self) -> "Heartbeat":
        if self.active:
            self._thread = threading.Thread(target=self._beat, name=f"heartbeat-{self.name}", daemon=True)
            self._thread.start()
        return self

    def __exit__(self, *exc) -> bool:
        self._stop.set()
        if self._thread is not None:
            self._thread.join(timeout=1.0)
        return False
