"""Textbook allocation baselines, usable as GA seeds.

All use the aggregated sensitivity s_j of :func:`aggregated_sensitivity` (largest effect of source j
per unit tolerance over the poses, relative to the bound), i.e. the single-stack-up model::

    worst case:  Σ_j s_j t_j <= 1          RSS:  Σ_j s_j² t_j² <= 1,

which is conservative for the real multi-pose problem (so the baselines are feasible).

* equal tolerance: every free t_j equal, the largest value that holds the *exact* requirement;
* proportional scaling: t_j ∝ w_j (default: the upper bounds), scaled to hold it exactly;
* Lagrange closed forms (Spotts 1973; Chase & Greenwood 1988): minimise Σ c_j(t_j) on the
  single stack-up. Stationarity c_j'(t_j) + λ ∂g/∂t_j = 0 gives, with c = a0·exp(-a1 t/σ)::

      worst case  t_j = (σ/a1)·ln(a0 a1 / (σ λ s_j));   RSS  t_j = (σ/a1)·W(a0 a1² / (2 λ s_j² σ²))

  (W: Lambert W), and with c = a0·(t/σ)^(-k)::

      worst case  t_j = σ·(a0 k / (σ λ s_j))^(1/(k+1));   RSS  t_j = (a0 k σ^k / (2 λ s_j²))^(1/(k+2)).

  λ > 0 is found by a 1-D root solve so the stack-up holds with equality; other cost models use
  a 1-D bisection for each t_j(λ). Results are clipped to the bounds.
"""
from __future__ import annotations

import time

import numpy as np
from scipy.optimize import brentq
from scipy.special import lambertw

from evotol.cost_models.exponential import ExponentialCost
from evotol.cost_models.power import PowerCost
from evotol.allocators.budget import budget_info, check_budget, scaled_family, spend_budget
from evotol.allocators.sensitivity import aggregated_sensitivity
from evotol.measures.constraints import ConstraintRows
from evotol.errors import ValidationError
from evotol.core.problem import ToleranceProblem
from evotol.core.plausibility import issue
from evotol.measures import feasibility
from evotol.core.result import AllocationResult, make_result
from evotol._runtime.blas_threads import single_threaded_blas


def _scale_exact(problem: ToleranceProblem, t: np.ndarray, rows: ConstraintRows | None = None) -> np.ndarray:
    """Scale the free tolerances by one factor so the exact requirement holds with equality."""
    measure = problem.requirement.measure
    if measure in ("worst_case", "rss"):
        rows = rows or ConstraintRows(problem)
        for _ in range(10):
            t = rows.scale_to_boundary(t[None])[0]
            viol, added = rows.check(t[None])
            if viol[0] <= 1e-10 and added == 0:
                break
        return t
    # mc_quantile: bisection on the exact evaluation
    lo, hi = 0.0, 1.0
    f = problem.free
    while problem.evaluate(problem.full((t[f] * hi)[None])).violation[0] <= 0 and hi < 1e6:
        lo, hi = hi, hi * 2
    for _ in range(40):
        mid = 0.5 * (lo + hi)
        ok = problem.evaluate(problem.full((t[f] * mid)[None])).violation[0] <= 0
        lo, hi = (mid, hi) if ok else (lo, mid)
    return problem.full(np.clip(t[f] * lo, problem.lower[f], problem.upper[f])[None])[0]   # followers of shared groups too


def equal_design(problem: ToleranceProblem, rows: ConstraintRows | None = None) -> np.ndarray:
    """The equal-tolerance design: one common t for every free source, scaled so the exact
    requirement holds with equality (start: the smallest geometric mean of the free bounds).

    Parameters
    ----------
    rows : ConstraintRows or None
        Constraint rows to reuse (``worst_case``/``rss``); default: built from ``problem``.

    Returns
    -------
    numpy.ndarray
        (n_sources,) the design (m or rad), clipped to the bounds.
    """
    f = problem.free
    t = problem.full(np.full(int(f.sum()), np.sqrt(problem.lower[f] * problem.upper[f]).min())[None])[0]
    return _scale_exact(problem, t, rows)


def proportional_design(problem: ToleranceProblem, weights=None) -> np.ndarray:
    """The proportional-scaling design: t_j ∝ w_j on the free sources, scaled so the exact
    requirement holds with equality.

    Parameters
    ----------
    weights : array_like, mapping or None
        Weights w_j per source (anything ``problem.as_array`` takes; only ratios matter);
        default: the upper bounds.

    Returns
    -------
    numpy.ndarray
        (n_sources,) the design (m or rad), clipped to the bounds.

    Raises
    ------
    ValidationError
        If a weight of a free source is not positive.
    """
    f = problem.free
    w = problem.upper if weights is None else problem.as_array(weights)
    if np.any(w[f] <= 0):
        raise ValidationError("weights", w.tolist(), "positive weights for the free sources")
    t = problem.full((w[f] / np.max(w[f]) * problem.upper[f].min())[None])[0]
    return _scale_exact(problem, t)


def _t_of_lambda(problem: ToleranceProblem, s: np.ndarray, lam: float, measure: str) -> np.ndarray:
    t = problem.locked_values.copy()
    M = problem.variable_matrix
    members = {j: np.flatnonzero(M[:, v]) for v, j in enumerate(np.flatnonzero(problem.free))}
    for j in np.flatnonzero(problem.free):
        tol = problem.tolerances[problem.names[j]]
        cm = tol.cost
        lo, hi = problem.lower[j], problem.upper[j]
        sig = cm.scale
        simple = members[j].size == 1 and tol.width_factor == 1 and problem.cost_weight[j] == 1
        if not simple:   # shared variable or cost on a scaled width: bisection on the collected derivative
            mem = members[j]
            sv = float(np.sum(s[mem])) if measure == "worst_case" else float(np.sum(s[mem] ** 2))

            def g(x):
                dc = sum(problem.cost_weight[k] * float(problem.tolerances[problem.names[k]].dcost_of(x)) for k in mem)
                return dc + lam * (sv if measure == "worst_case" else 2 * sv * x)
            tj = lo if g(lo) >= 0 else hi if g(hi) <= 0 else brentq(g, lo, hi, xtol=1e-15 * hi)
        elif isinstance(cm, (ExponentialCost, PowerCost)) and \
                lam * (s[j] if measure == "worst_case" else s[j] ** 2) == 0:
            # no effect on the requirement (or a product that underflows to 0): the closed forms' limit
            # as lambda s_j -> 0+ is t -> infinity, clipped to the upper bound (no division by zero, issue 33)
            tj = hi
        elif isinstance(cm, ExponentialCost):
            a0, a1 = cm.p
            if measure == "worst_case":
                arg = a0 * a1 / (sig * lam * s[j])
                tj = sig / a1 * np.log(arg) if arg > 0 else lo
            else:
                tj = sig / a1 * float(np.real(lambertw(a0 * a1 ** 2 / (2 * lam * s[j] ** 2 * sig ** 2))))
        elif isinstance(cm, PowerCost):
            a0, k = cm.p
            if measure == "worst_case":
                tj = sig * (a0 * k / (sig * lam * s[j])) ** (1 / (k + 1))
            else:
                tj = (a0 * k * sig ** k / (2 * lam * s[j] ** 2)) ** (1 / (k + 2))
        else:  # generic convex model: solve c'(t) + λ g'(t) = 0 by bisection
            def g(x):
                dg = s[j] if measure == "worst_case" else 2 * s[j] ** 2 * x
                return float(cm.dcost(x)) + lam * dg
            if g(lo) >= 0:
                tj = lo
            elif g(hi) <= 0:
                tj = hi
            else:
                tj = brentq(g, lo, hi, xtol=1e-15 * hi)
        t[j] = np.clip(tj, lo, hi)
    return problem.full(t[problem.free][None])[0]


def lagrange_design(problem: ToleranceProblem, measure: str | None = None) -> np.ndarray:
    """The Lagrange closed-form design on the single stack-up (module docstring): λ found by a
    root solve in log λ so the stack-up of the aggregated sensitivities equals 1.

    Parameters
    ----------
    measure : {"worst_case", "rss"} or None
        Stack-up (default: the requirement's measure; any other measure uses ``"rss"``).

    Returns
    -------
    numpy.ndarray
        (n_sources,) the design (m or rad), clipped to the bounds; every free tolerance at its
        upper bound if those already hold the stack-up. Not rescaled onto the exact requirement.

    Raises
    ------
    ValidationError
        If the lower tolerance limits cannot hold the stack-up.
    """
    measure = measure or problem.requirement.measure
    if measure not in ("worst_case", "rss"):
        measure = "rss"
    s = aggregated_sensitivity(problem)

    def stack(t):
        return float(np.sum(s * t)) if measure == "worst_case" else float(np.sqrt(np.sum((s * t) ** 2)))

    def resid(loglam):
        return stack(_t_of_lambda(problem, s, np.exp(loglam), measure)) - 1

    lo, hi = -50.0, 50.0
    if resid(lo) < 0:       # even the loosest tolerances hold: all at upper bound
        return _t_of_lambda(problem, s, np.exp(lo), measure)
    if resid(hi) > 0:
        raise ValidationError("requirement", problem.requirement, "a bound the lower tolerance limits can hold")
    loglam = brentq(resid, lo, hi, xtol=1e-12)
    return _t_of_lambda(problem, s, np.exp(loglam), measure)


def _at_budget(problem: ToleranceProblem, name: str, budget, t0, family, log_p):
    """Best accuracy at ``budget`` within a one-parameter family (see :mod:`evotol.allocators.budget`)."""
    budget = check_budget(problem, budget)
    t = spend_budget(problem, family, budget, log_p)
    return issue(make_result(problem, f"{name} (best accuracy at budget)", t, seconds=time.perf_counter() - t0,
                             info=budget_info(problem, t, budget), budget=budget))


@single_threaded_blas
def allocate_equal(problem: ToleranceProblem, *, budget: float | None = None) -> AllocationResult:
    """Equal tolerances: one common t for every free source, scaled onto the requirement.

    Parameters
    ----------
    problem : evotol.core.problem.ToleranceProblem
        The problem (tolerances in SI: m or rad).
    budget : float or None
        If given (cost models' unit), the smallest common tolerance whose cost fits the budget.

    Returns
    -------
    evotol.core.result.AllocationResult
        The design (tolerances in SI: m or rad), its cost (cost models' unit), its errors at every
        pose (m, rad) and the feasibility repair applied (:mod:`evotol.measures.feasibility`).

    Raises
    ------
    evotol.errors.ValidationError
        A ``budget`` that is not a finite positive cost, or below the cost of the cheapest
        design (every free tolerance at its upper bound).

    Examples
    --------
    >>> from evotol.cost_models import PowerCost
    >>> from evotol import LinearStack, Tolerance, assembly_problem
    >>> stack = LinearStack({"x1": 1.0, "x2": -2.0, "x3": 0.5}, {"gap": 1e-4})  # gap = x1 - 2 x2 + x3 / 2
    >>> tol = {n: Tolerance(PowerCost(1.0, 1.0, scale=1e-3), lower=1e-7, upper=1e-4)
    ...        for n in stack.source_names}                                   # cost 1e-3 / t
    >>> problem = assembly_problem(stack, tol)                                # worst case <= 0.1 mm
    >>> from evotol import allocate_equal
    >>> res = allocate_equal(problem)                          # one t with 3.5 t = 1e-4 m
    >>> round(res.tolerances["x1"] * 1e6, 3), round(res.cost, 6)
    (28.571, 105.0)
    """
    t0 = time.perf_counter()
    if budget is not None:
        return _at_budget(problem, "equal tolerance", budget, t0, *scaled_family(problem, np.ones(problem.n_sources)))
    t, ev, repair = feasibility.hold_to_rule(problem, equal_design(problem))
    return issue(make_result(problem, "equal tolerance", t, evaluation=ev, seconds=time.perf_counter() - t0, info=repair))


@single_threaded_blas
def allocate_proportional(problem: ToleranceProblem, *, budget: float | None = None, weights=None) -> AllocationResult:
    """Proportional scaling: t_j ∝ w_j, scaled onto the requirement.

    Parameters
    ----------
    problem : evotol.core.problem.ToleranceProblem
        The problem (tolerances in SI: m or rad).
    budget : float or None
        If given (cost models' unit), the design scaled down until its cost fits the budget.
    weights : array_like or None
        Positive weights w_j of the free sources (default: their upper bounds).

    Returns
    -------
    evotol.core.result.AllocationResult
        The design (tolerances in SI: m or rad), its cost (cost models' unit), its errors at every
        pose (m, rad) and the feasibility repair applied (:mod:`evotol.measures.feasibility`).

    Raises
    ------
    evotol.errors.ValidationError
        A ``budget`` that is not a finite positive cost, or below the cost of the cheapest
        design (every free tolerance at its upper bound).
    evotol.errors.ValidationError
        Weights that are not positive.

    Examples
    --------
    >>> from evotol.cost_models import PowerCost
    >>> from evotol import LinearStack, Tolerance, assembly_problem
    >>> stack = LinearStack({"x1": 1.0, "x2": -2.0, "x3": 0.5}, {"gap": 1e-4})  # gap = x1 - 2 x2 + x3 / 2
    >>> tol = {n: Tolerance(PowerCost(1.0, 1.0, scale=1e-3), lower=1e-7, upper=1e-4)
    ...        for n in stack.source_names}                                   # cost 1e-3 / t
    >>> problem = assembly_problem(stack, tol)                                # worst case <= 0.1 mm
    >>> from evotol import allocate_proportional
    >>> res = allocate_proportional(problem, weights={"x1": 1.0, "x2": 1.0, "x3": 2.0})
    >>> round(res.tolerances["x3"] / res.tolerances["x1"], 6), res.feasible
    (2.0, True)
    """
    t0 = time.perf_counter()
    if budget is not None:
        w = problem.upper if weights is None else problem.as_array(weights)
        return _at_budget(problem, "proportional scaling", budget, t0, *scaled_family(problem, w))
    t, ev, repair = feasibility.hold_to_rule(problem, proportional_design(problem, weights))
    return issue(make_result(problem, "proportional scaling", t, evaluation=ev, seconds=time.perf_counter() - t0,
                             info=repair))


@single_threaded_blas
def allocate_lagrange(problem: ToleranceProblem, *, budget: float | None = None, measure: str | None = None) -> AllocationResult:
    """Lagrange closed forms: the stationarity condition of min cost s.t. stack-up = requirement.

    Parameters
    ----------
    problem : evotol.core.problem.ToleranceProblem
        The problem (tolerances in SI: m or rad).
    budget : float or None
        If given (cost models' unit), the multiplier λ chosen so the cost is the budget (the same
        stationarity condition solves min stack-up s.t. cost <= budget).
    measure : {"worst_case", "rss"} or None
        Stack-up of the closed form (default: the requirement's measure).

    Returns
    -------
    evotol.core.result.AllocationResult
        The design (tolerances in SI: m or rad), its cost (cost models' unit), its errors at every
        pose (m, rad) and the feasibility repair applied (:mod:`evotol.measures.feasibility`).

    Raises
    ------
    evotol.errors.ValidationError
        A ``budget`` that is not a finite positive cost, or below the cost of the cheapest
        design (every free tolerance at its upper bound).
    evotol.errors.ValidationError
        A requirement the lower tolerance limits cannot hold.

    Examples
    --------
    >>> from evotol.cost_models import PowerCost
    >>> from evotol import LinearStack, Tolerance, assembly_problem
    >>> stack = LinearStack({"x1": 1.0, "x2": -2.0, "x3": 0.5}, {"gap": 1e-4})  # gap = x1 - 2 x2 + x3 / 2
    >>> tol = {n: Tolerance(PowerCost(1.0, 1.0, scale=1e-3), lower=1e-7, upper=1e-4)
    ...        for n in stack.source_names}                                   # cost 1e-3 / t
    >>> problem = assembly_problem(stack, tol)                                # worst case <= 0.1 mm
    >>> from evotol import allocate_lagrange
    >>> res = allocate_lagrange(problem)                       # closed form for power costs
    >>> round(res.cost, 3), res.feasible
    (97.426, True)
    """
    t0 = time.perf_counter()
    if budget is not None:
        m = measure or problem.requirement.measure
        m = m if m in ("worst_case", "rss") else "rss"
        s = aggregated_sensitivity(problem)
        return _at_budget(problem, "Lagrange closed form", budget, t0,
                          lambda x: _t_of_lambda(problem, s, np.exp(-x), m), (-50.0, 50.0))
    t = lagrange_design(problem, measure)
    t, ev, repair = feasibility.hold_to_rule(problem, t)
    return issue(make_result(problem, "Lagrange closed form", t, evaluation=ev, seconds=time.perf_counter() - t0,
                             info={"stack_up": measure or problem.requirement.measure, **repair}))
