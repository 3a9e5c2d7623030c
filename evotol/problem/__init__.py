"""The tolerance-allocation problem (:class:`ToleranceProblem`) and the values it is built from.

This package only hands names on: the problem itself lives in :mod:`evotol.problem.tolerance_problem`
(construction, properties, evaluation), with its derived copies in :mod:`evotol.problem.derived`,
its variable mapping in :mod:`evotol.problem.variable_mapping` and its costs in
:mod:`evotol.problem.costs`; ``Tolerance`` and ``COST_WIDTHS`` come from :mod:`evotol.tolerance`,
``Requirement`` from :mod:`evotol.requirement`, ``Evaluation`` from :mod:`evotol.accuracy.base` and
``SHARED_COSTS`` from :mod:`evotol.variables`.
"""
from evotol.accuracy.base import Evaluation
from evotol.problem.tolerance_problem import ToleranceProblem
from evotol.requirement import Requirement
from evotol.tolerance import COST_WIDTHS, Tolerance
from evotol.variables import SHARED_COSTS

__all__ = ["ToleranceProblem", "Tolerance", "Requirement", "Evaluation", "COST_WIDTHS", "SHARED_COSTS"]
