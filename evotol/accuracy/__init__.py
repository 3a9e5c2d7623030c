"""Accuracy measures as plugins: one protocol (:class:`Measure`: ``evaluate(problem, T, top_only)
-> Evaluation``), one registry (built-ins plus the entry-point group ``evotol.measures``) and a
conformance suite (:mod:`evotol.accuracy_checks`).

Built in: ``worst_case`` (:mod:`.worst_case`), ``rss`` (:mod:`.rss`), ``mc_quantile``
(:mod:`.mc_quantile`) and ``yield`` (:mod:`.statistical_yield`). The numerics they share live in
:mod:`evotol.measures` (support function, RSS) and :mod:`evotol.statistical` (first-order yield).
"""
from evotol.accuracy.base import ComponentErrors, Evaluation, Measure
from evotol.accuracy.registry import available, get, names

__all__ = ["ComponentErrors", "Evaluation", "Measure", "available", "get", "names"]
