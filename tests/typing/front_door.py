"""A user's script through the front door, type-checked by mypy (tests/test_typing.py, .ci/run).

Every name used here comes from ``evotol`` itself; mypy must accept the calls and infer the result
types (``reveal_type`` is not used: the annotations below are what is checked).
"""
from __future__ import annotations

import numpy as np
import pandas as pd

from evotol.cost_models import PowerCost
from evotol import (AllocationResult, LinearStack, MonteCarloResult, ParetoFront, Requirement, Tolerance,
                    ToleranceProblem, ValidationError, allocate_ga, allocate_nsga2, allocate_optimum,
                    assembly_problem, verify)


def study() -> tuple[ToleranceProblem, AllocationResult, MonteCarloResult]:
    stack = LinearStack({"x1": 1.0, "x2": -2.0, "x3": 0.5}, {"gap": 1e-4})
    tolerances = {n: Tolerance(PowerCost(1.0, 1.0, scale=1e-3), lower=1e-7, upper=1e-4) for n in stack.source_names}
    problem: ToleranceProblem = assembly_problem(stack, tolerances)
    best: AllocationResult = allocate_optimum(problem)
    ga: AllocationResult = allocate_ga(problem, pop_size=8, n_gen=2, rng=np.random.default_rng(0))
    front: ParetoFront = allocate_nsga2(problem, pop_size=8, n_gen=2, rng=1)
    mc: MonteCarloResult = verify(problem, best.tolerances, n_samples=100, rng=2)
    table: pd.DataFrame = best.to_frame()
    per_pose: pd.DataFrame = mc.to_frame()
    cost: float = best.cost + ga.cost
    print(repr(problem), table.shape, per_pose.shape, cost, len(front.table))
    return problem, best, mc


def requirement() -> Requirement:
    return Requirement(position=1e-4)


def refused() -> str:
    try:
        allocate_ga(study()[0], rng=-1)
    except ValidationError as err:
        return err.field
    return ""
