"""The tolerance-allocation problem (:class:`ToleranceProblem`) and the values it is built from.

This package only hands names on: the problem itself lives in :mod:`evotol.core.problem.tolerance_problem`
(construction, properties, evaluation), with its derived copies in :mod:`evotol.core.problem.derived`,
its variable mapping in :mod:`evotol.core.problem.variable_mapping` and its costs in
:mod:`evotol.core.problem.costs`; ``Tolerance`` and ``COST_WIDTHS`` come from :mod:`evotol.core.tolerance`,
``Requirement`` from :mod:`evotol.core.requirement`, ``Evaluation`` from :mod:`evotol.measures.protocol` and
``SHARED_COSTS`` from :mod:`evotol.core.variables`.
"""
from evotol.measures.protocol import Evaluation
from evotol.core.problem.tolerance_problem import ToleranceProblem
from evotol.core.requirement import Requirement
from evotol.core.tolerance import COST_WIDTHS, Tolerance
from evotol.core.variables import SHARED_COSTS

__all__ = ["ToleranceProblem", "Tolerance", "Requirement", "Evaluation", "COST_WIDTHS", "SHARED_COSTS"]
