"""Notice Ctrl-C even where a long computation swallows it.

The GA and NSGA-II allocators catch ``KeyboardInterrupt`` and return their best design so far,
which is right for them but left ``evotol run`` unaware that the user asked to stop: the study
finished with exit code 0 and no message (issue 15). :class:`CtrlC` counts every SIGINT that
arrives while it is active and then behaves like Python's default handler (raises
``KeyboardInterrupt``), so callers keep their behaviour and the study can still ask
``ctrl_c.count`` after each step.
"""
from __future__ import annotations

import signal
import threading


class CtrlC:
    """Context manager: ``with CtrlC() as c: ...; if c.count: ...``.

    Outside the main thread (where signal handlers cannot be installed) it counts nothing and
    changes nothing.
    """

    def __init__(self):
        self.count = 0
        self._previous = None

    def _handler(self, signum, frame):
        self.count += 1
        raise KeyboardInterrupt

    def __enter__(self) -> "CtrlC":
        if threading.current_thread() is threading.main_thread():
            self._previous = signal.signal(signal.SIGINT, self._handler)
        return self

    def __exit__(self, *exc) -> bool:
        if self._previous is not None:
            signal.signal(signal.SIGINT, self._previous)
            self._previous = None
        return False
