"""The ``evotol`` command's messages: the library logs through :mod:`logging`, the command shows them.

Library modules write ``logging.getLogger(__name__).info(...)`` and never print; what they say is
progress and notes, not results. The command line installs one handler on the ``evotol``, ``robots``
and ``cost_models`` loggers that writes to standard error, so ``evotol run study.toml 2>/dev/null``
shows the results only (issue 40). ``-q`` shows warnings and errors only; ``-v`` adds debug lines.
A Python user who configures no logging sees the warnings (Python's last-resort handler) and no
progress lines; ``logging.basicConfig(level=logging.INFO)`` shows them.
"""
from __future__ import annotations

import logging
import sys

#: the loggers of evotol's import packages
LOGGERS = ("evotol", "robots", "cost_models")


class _CurrentStderr(logging.StreamHandler):
    """A handler writing to whatever ``sys.stderr`` is at the time of the message (a test's
    captured stream, a redirected one), not the one of the first ``main()`` call."""

    def __init__(self):
        super().__init__(sys.stderr)

    @property
    def stream(self):
        return sys.stderr

    @stream.setter
    def stream(self, value):           # StreamHandler.__init__ sets it; the property always reads sys.stderr
        pass


class _Format(logging.Formatter):
    """``[evotol] message`` for progress and notes, ``evotol: warning: message`` for warnings (the
    form of the command's one-line errors)."""

    def format(self, record: logging.LogRecord) -> str:
        text = record.getMessage()
        if record.levelno >= logging.WARNING:
            return f"evotol: {record.levelname.lower()}: {text}"
        return f"[evotol] {text}"


def level_for(quiet: int, verbose: int) -> int:
    """The logging level of ``-q`` / ``-v`` counts: WARNING with ``-q``, DEBUG with ``-v``, else INFO.

    Parameters
    ----------
    quiet, verbose : int
        How many times ``-q`` and ``-v`` were given.

    Returns
    -------
    int
        A :mod:`logging` level.
    """
    step = int(verbose or 0) - int(quiet or 0)
    return logging.DEBUG if step > 0 else logging.INFO if step == 0 else logging.WARNING


def configure(level: int = logging.INFO) -> None:
    """Show the library's messages at ``level`` and above on standard error, one line each.

    Installs the handler once (a second call only changes the level), so calling ``main()`` many
    times in one process (the tests) does not repeat lines.

    Parameters
    ----------
    level : int
        A :mod:`logging` level (:func:`level_for`).
    """
    for name in LOGGERS:
        logger = logging.getLogger(name)
        logger.setLevel(level)
        if not any(isinstance(h, _CurrentStderr) for h in logger.handlers):
            handler = _CurrentStderr()
            handler.setFormatter(_Format())
            logger.addHandler(handler)
