"""Best accuracy at a budget B: the checks and the one-parameter search the allocators share.

Every allocator that offers ``budget=`` minimises the (normalised) error subject to
``Σ c_j(t_j) <= B`` instead of the cost subject to the requirement. Because every cost model
decreases with the tolerance, the cheapest design puts every free tolerance at its upper bound;
a budget below its cost admits no design at all and is a :class:`ValidationError` naming that
cost (issue 15: ``allocate_ga(budget=1e-3)`` used to return a design costing 24.7 marked
feasible, ``allocate_optimum(budget=nan)`` ran 60 rounds).

The rule-based allocators (equal tolerance, proportional scaling, equal effect, Lagrange) each
describe a one-parameter family of designs t(p) whose cost falls monotonically as p grows (a
common scale factor; for Lagrange the multiplier 1/λ, since min Σ s_j t_j s.t. Σ c_j <= B and
min Σ c_j s.t. Σ s_j t_j <= 1 share the stationarity condition c_j'(t_j) + λ s_j = 0). Within
the family the error grows with p, so the best accuracy at the budget is the smallest p whose
cost is <= B: :func:`spend_budget` finds it by bisection, always returning a design within the
budget.
"""
from __future__ import annotations

import numbers
from typing import Callable

import numpy as np

from evotol.errors import ValidationError
from evotol.problem import ToleranceProblem
from evotol.quality_loss import has_quality_loss


def cheapest_design(problem: ToleranceProblem) -> np.ndarray:
    """Every free tolerance at its upper bound (locked ones at their value), SI."""
    return problem.full(problem.upper[problem.free][None])[0]


def dearest_design(problem: ToleranceProblem) -> np.ndarray:
    """Every free tolerance at its lower bound: the most accurate design the bounds allow."""
    return problem.full(problem.lower[problem.free][None])[0]


def check_budget(problem: ToleranceProblem, budget, field: str = "budget") -> float:
    """The budget as a float, or a ValidationError naming ``field``, the budget and the cost of
    the cheapest design."""
    if isinstance(budget, bool) or not isinstance(budget, numbers.Real) or not np.isfinite(float(budget)) \
            or float(budget) <= 0:
        raise ValidationError(field, budget, "a finite positive cost, in the cost models' unit")
    if has_quality_loss(problem):
        raise ValidationError(field, budget, "no budget on a problem with a quality-loss term (its cost is not "
                                             "monotone in t): minimise machining cost + loss at the requirement instead")
    budget = float(budget)
    floor = float(problem.cost(cheapest_design(problem)))
    if budget < floor * (1 - 1e-12):
        raise ValidationError(field, budget, f">= {floor:.6g}, the cost of the cheapest design "
                                                "(every free tolerance at its upper bound)")
    return budget


def spend_budget(problem: ToleranceProblem, family: Callable[[float], np.ndarray], budget: float,
                 log_p: tuple[float, float], iters: int = 200) -> np.ndarray:
    """The design of ``family`` with the smallest ``log p`` in ``log_p`` whose cost is <= budget.

    ``family(log_p) -> t`` (full design, SI) must have a cost non-increasing in ``log_p``, with
    ``family(log_p[1])`` within the budget. Bisection keeps the affordable end, so the returned
    design never exceeds the budget.
    """
    lo, hi = log_p
    cost = lambda x: float(problem.cost(family(x)))  # noqa: E731
    if cost(lo) <= budget:
        return family(lo)
    if cost(hi) > budget * (1 + 1e-12):
        raise ValidationError("budget", budget, f">= {cost(hi):.6g}, the cheapest design of this rule")
    for _ in range(iters):
        mid = 0.5 * (lo + hi)
        if cost(mid) <= budget:
            hi = mid
        else:
            lo = mid
        if hi - lo < 1e-13:
            break
    return family(hi)


def scaled_family(problem: ToleranceProblem, shape: np.ndarray) -> tuple[Callable[[float], np.ndarray], tuple]:
    """t(p) = clip(exp(p) · shape, lower, upper) on the free sources, and the range of p from every
    free tolerance at its lower bound to every one at its upper bound."""
    f = problem.free
    shape = np.asarray(shape, dtype=float)[f]
    if np.any(np.isnan(shape)) or np.any(shape <= 0):
        raise ValidationError("design shape", shape.tolist(), "positive tolerances for the free sources (inf: always at the upper bound)")
    lo, hi = problem.lower[f], problem.upper[f]
    moving = np.isfinite(shape)         # inf: a source with no effect, always at its upper bound

    def family(log_s: float) -> np.ndarray:
        return problem.full(np.where(moving, np.clip(np.exp(log_s) * np.where(moving, shape, 1.0), lo, hi), hi)[None])[0]

    if not moving.any():
        return family, (0.0, 0.0)
    return family, (float(np.log(np.min(lo[moving] / shape[moving]))), float(np.log(np.max(hi[moving] / shape[moving]))))


def budget_info(problem: ToleranceProblem, t: np.ndarray, budget: float) -> dict:
    """What a budget-mode result reports besides its cost: the budget and the normalised error
    (max over poses and components of error / bound; <= 1 means the requirement also holds)."""
    ev = problem.evaluate(np.asarray(t, dtype=float)[None])
    return {"budget": budget, "normalised_error": float(ev.violation[0] + 1)}
