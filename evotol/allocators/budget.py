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

The parameters several definitions of this module share are described once, here.

Parameters
----------
budget : float
    The budget (cost units).
"""
from __future__ import annotations

import numbers
from typing import Callable

import numpy as np

from evotol.errors import ValidationError
from evotol.core.problem import ToleranceProblem
from evotol.core.quality_loss import has_quality_loss


def cheapest_design(problem: ToleranceProblem) -> np.ndarray:
    """Every free tolerance at its upper bound (locked ones at their value), SI.

    Returns
    -------
    numpy.ndarray
        (n_sources,) the design (m or rad), the cheapest the bounds allow.
    """
    return problem.full(problem.upper[problem.free][None])[0]


def dearest_design(problem: ToleranceProblem) -> np.ndarray:
    """Every free tolerance at its lower bound: the most accurate design the bounds allow.

    Returns
    -------
    numpy.ndarray
        (n_sources,) the design (m or rad; locked tolerances at their value).
    """
    return problem.full(problem.lower[problem.free][None])[0]


def check_budget(problem: ToleranceProblem, budget, field: str = "budget") -> float:
    """The budget as a float, or a ValidationError naming ``field``, the budget and the cost of
    the cheapest design.

    Parameters
    ----------
    budget : float
        The budget (cost models' unit).
    field : str
        Name of the field in the error message.

    Returns
    -------
    float
        The budget (cost units).

    Raises
    ------
    ValidationError
        A budget that is not a finite positive number, a problem with a quality-loss term (its
        cost is not monotone in t), or a budget below the cost of :func:`cheapest_design`.
    """
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

    Parameters
    ----------
    problem : ToleranceProblem
        The problem (its cost prices the designs).
    family : callable
        ``family(log_p)`` -> (n_sources,) full design (m or rad), cost non-increasing in
        ``log_p``.
    log_p : tuple of float
        ``(lo, hi)`` range of ``log p`` searched.
    iters : int
        Maximum number of bisection steps (it also stops when the bracket is below 1e-13).

    Returns
    -------
    numpy.ndarray
        (n_sources,) the design (m or rad) with cost <= budget: ``family(lo)`` if it already
        fits, else the affordable end of the bisection bracket.

    Raises
    ------
    ValidationError
        If even ``family(log_p[1])`` costs more than the budget.
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
    free tolerance at its lower bound to every one at its upper bound.

    Parameters
    ----------
    shape : array_like, (n_sources,)
        Relative tolerances of the design (m or rad; only ratios matter). Positive on the free
        sources; ``inf`` keeps a source at its upper bound.

    Returns
    -------
    family : callable
        ``family(p)`` -> (n_sources,) full design (m or rad).
    log_p : tuple of float
        ``(lo, hi)``: p from every free tolerance at its lower bound to every one at its upper
        bound; ``(0.0, 0.0)`` if no source moves.

    Raises
    ------
    ValidationError
        If ``shape`` is NaN or not positive on a free source.
    """
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
    (max over poses and components of error / bound; <= 1 means the requirement also holds).

    Returns
    -------
    dict
        ``{"budget": budget, "normalised_error": float}`` (normalised error dimensionless).
    """
    ev = problem.evaluate(np.asarray(t, dtype=float)[None])
    return {"budget": budget, "normalised_error": float(ev.violation[0] + 1)}
