"""The size of an error, in one room: accuracy measures as plugins -- one protocol
(:class:`Measure`: ``evaluate(problem, T, top_only) -> Evaluation``, :mod:`.protocol`), one registry
(:mod:`.registry`: built-ins plus the entry-point group ``evotol.measures``; their conformance suite is
:mod:`evotol.core.measure_checks`, which builds small problems) -- and the numerics they share.

* Built in (:mod:`.builtin`): ``worst_case`` (:mod:`.builtin.worst_case`), ``rss``
  (:mod:`.builtin.rss`), ``mc_quantile`` (:mod:`.builtin.mc_quantile`) and ``yield``
  (:mod:`.builtin.statistical_yield`).
* The linear model (:mod:`.linear`): direction grids, asymmetric intervals, worst case and RSS, the
  proven support-function bound.
* The requirement as constraint rows for optimisers (:mod:`.constraints`) and the one rule of
  *feasible* (:mod:`.feasibility`).
* Source distributions and yield (:mod:`.statistical`), joint clearances with their certified worst case
  (:mod:`.clearances`), the nonlinear worst case with interval arithmetic (:mod:`.nonlinear`).
"""
from evotol.measures.protocol import ComponentErrors, Evaluation, Measure
from evotol.measures.registry import available, get, names

__all__ = ["ComponentErrors", "Evaluation", "Measure", "available", "get", "names"]
