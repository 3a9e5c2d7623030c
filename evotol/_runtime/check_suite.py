"""Running a conformance suite: every named check, every failure reported (robots, cost models,
measures). Checks call :func:`require` instead of ``assert``, so they hold under ``python -O``."""
from __future__ import annotations

from typing import Callable, Iterable

from evotol.errors import CheckFailed

__all__ = ["CheckFailed", "require", "run_checks"]


def require(condition, message: str) -> None:
    """Raise :class:`CheckFailed` with ``message`` unless ``condition`` holds (a check's ``assert``
    that ``python -O`` does not strip).

    Parameters
    ----------
    condition : bool-like
        What the contract requires.
    message : str
        What failed, with the measured numbers.

    Raises
    ------
    CheckFailed
        ``condition`` is false.
    """
    if not condition:
        raise CheckFailed(message)


def run_checks(subject: str, checks: Iterable[tuple[str, Callable[[], dict]]]) -> dict:
    """Run every ``(name, check)``; returns the merged measurements of the passing checks.

    Parameters
    ----------
    subject : str
        The plugin checked (named in the error).
    checks : iterable of (str, callable)
        Named checks of no argument, each returning a dict of measured numbers.

    Returns
    -------
    dict
        The measurements of every check.

    Raises
    ------
    CheckFailed
        Naming ``subject`` and listing every failed check with its message (not only the first),
        whatever the exception type a check raised.
    """
    report, failures = {}, []
    for name, check in checks:
        try:
            report.update(check())
        except Exception as exc:    # every failure is reported, whatever its type
            failures.append(f"{name}: {type(exc).__name__}: {exc}")
    if failures:
        raise CheckFailed(f"{subject} fails {len(failures)} check(s):\n  " + "\n  ".join(failures))
    return report
