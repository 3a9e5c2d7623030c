"""Running a conformance suite: every named check, every failure reported (robots, cost models)."""
from __future__ import annotations

from typing import Callable, Iterable


def run_checks(subject: str, checks: Iterable[tuple[str, Callable[[], dict]]]) -> dict:
    """Run every ``(name, check)``; returns the merged measurements of the passing checks.

    Raises one ``AssertionError`` naming ``subject`` and listing every failed check with its
    message (not only the first), whatever the exception type a check raised."""
    report, failures = {}, []
    for name, check in checks:
        try:
            report.update(check())
        except Exception as exc:    # every failure is reported, whatever its type
            failures.append(f"{name}: {type(exc).__name__}: {exc}")
    if failures:
        raise AssertionError(f"{subject} fails {len(failures)} check(s):\n  " + "\n  ".join(failures))
    return report
