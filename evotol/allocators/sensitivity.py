"""Sensitivity-based allocation ("equal effect"), the rule accuracy-synthesis papers compare against.

Rule (documented exactly): let s_j = max over poses and constrained components of ‖B_j‖₂ / E_c
(source j's largest effect per unit tolerance, relative to the bound E_c of that component). Each
free source receives the same share of the error budget:

* worst-case measure:  s_j t_j = (1 − Σ_locked s_k t_k) / m         (linear stack-up);
* RSS measure:         s_j t_j = sqrt((1 − Σ_locked (s_k t_k)²) / m)  (root-sum-square stack-up);

m = number of free sources that move the end-effector (sources with no effect get their upper
bound). Tolerances are then clipped to their bounds. Shared tolerances: a variable's sensitivity
is the sum (worst case) or root sum square (RSS) of its members'. Asymmetric intervals: s_j is
taken per unit t of the interval's farthest end, ``s_j (ρ_j + |κ_j|)``, and the fixed offsets'
largest effect ``max_p |Σ_j B_j offset_j| / E`` is taken off the budget first. The allocation holds
the requirement by construction (sum/RSS of per-source maxima bounds the true error) but ignores
cost entirely.
"""
from __future__ import annotations

import time

import numpy as np

from evotol.measures import linear as measures
from evotol.errors import ValidationError
from evotol.allocators.budget import budget_info, check_budget, spend_budget
from evotol.allocators.budget import scaled_family as _scaled
from evotol.core.problem import ToleranceProblem
from evotol.core.plausibility import issue
from evotol.measures import feasibility
from evotol.core.result import AllocationResult, make_result
from evotol._runtime.blas_threads import single_threaded_blas


def aggregated_sensitivity(problem: ToleranceProblem, collective_groups=()) -> np.ndarray:
    """s_j (1/unit of t_j): max over poses and components of ‖B_j‖₂ / E_c.

    ``collective_groups``: groups of interval sources whose sensitivity is taken for all members
    moving together, s = max_p ‖Σ_k B_k‖ / E (e.g. the three actuated lengths of a 3-UCR, which
    then act as a platform lift): a variant that reproduces how Yao 2013's Table 2 sized lengths.

    Parameters
    ----------
    problem : ToleranceProblem
        The problem (its sensitivities at its poses and the bounds E_c of its components).
    collective_groups : sequence of str
        Source groups (names of ``problem.groups()``) whose members are taken as moving
        together; default none.

    Returns
    -------
    numpy.ndarray
        (n_sources,) s_j, per unit of t_j (1/m or 1/rad; relative to the bound, so ``s_j t_j``
        is dimensionless).

    Raises
    ------
    ValidationError
        A collective group that no source has, or one with a source that is not an interval.
    """
    s = np.zeros(problem.n_sources)
    groups = np.array(problem.groups())
    for comp, lim in problem.components:
        sc = problem.sensitivities[comp].max(axis=0) / lim
        for g in collective_groups:
            members = np.flatnonzero(groups == g)
            if members.size == 0:
                raise ValidationError("collective_groups", g, f"a source group of {problem.error_model.name}: {sorted(set(groups))}")
            if any(problem.error_model.sources[k].dim != 1 for k in members):
                raise ValidationError("collective_groups", g, "a group of interval (dim 1) sources")
            Bsum = sum(problem.blocks[comp][k][:, :, 0] for k in members)
            sc[members] = np.max(np.linalg.norm(Bsum, axis=1)) / lim
        s = np.maximum(s, sc)
    return s


def check_sensitivity(problem: ToleranceProblem) -> None:
    """The sensitivity rule's refusal that needs no work (also by :mod:`evotol.allocators.preflight`).

    Raises
    ------
    evotol.errors.ValidationError
        A problem with clearance classes.
    """
    if problem.clearances is not None:
        raise ValidationError("method", "sensitivity", "a problem without clearance classes (a clearance has no "
                                                      "linear sensitivity: use optimum, ga or nsga2)")


def sensitivity_design(problem: ToleranceProblem, measure: str | None = None, collective_groups=()) -> np.ndarray:
    """The equal-effect design of the module docstring (no budget, no repair).

    Parameters
    ----------
    measure : {"worst_case", "rss"} or None
        Stack-up of the equal shares (default: the requirement's measure; any other measure uses
        ``"rss"``).
    collective_groups : sequence of str
        Source groups taken as one collective source (:func:`aggregated_sensitivity`).

    Returns
    -------
    numpy.ndarray
        (n_sources,) the design (m or rad), clipped to the bounds; sources with no effect at
        their upper bound.

    Raises
    ------
    ValidationError
        A problem with clearance classes, locked tolerances and offsets that leave no error
        budget for the free sources, or an invalid ``collective_groups`` entry.
    """
    check_sensitivity(problem)
    measure = measure or problem.requirement.measure
    if measure not in ("worst_case", "rss"):
        measure = "rss"
    s = aggregated_sensitivity(problem, collective_groups)
    sh = problem.shape
    if not sh.plain:
        s = s * (sh.rho + np.abs(sh.kappa))
    if problem.follower.any():      # a shared variable carries its members' sensitivities
        M = problem.variable_matrix
        sv = M.T @ s if measure == "worst_case" else np.sqrt(M.T @ s ** 2)
        s = s.copy()
        s[problem.free] = sv
    free = problem.free
    t = problem.locked_values.copy()
    locked = problem.locked
    idle = free & (s <= 0)          # sources with no effect on the error: loosest tolerance
    t[idle] = problem.upper[idle]
    free = free & ~idle
    m = int(free.sum())
    if m == 0:
        return problem.full(t[problem.free][None])[0]
    offset_part = 0.0
    if np.any(sh.offset != 0):
        offset_part = max(float(np.max(np.linalg.norm(measures.mean_shift(
            problem.blocks[c], measures.IntervalShape(sh.rho, 0 * sh.kappa, sh.offset), np.zeros((1, t.size)))[0], axis=-1))) / lim
            for c, lim in problem.components)
    if measure == "worst_case":
        budget = 1 - offset_part - float(np.sum(s[locked] * t[locked]))
        share = budget / m
    else:
        budget = (1 - offset_part) ** 2 - float(np.sum((s[locked] * t[locked]) ** 2)) if offset_part else \
            1 - float(np.sum((s[locked] * t[locked]) ** 2))
        share = np.sqrt(max(budget, 0.0) / m)
    if budget <= 0:
        raise ValidationError("locked tolerances", {n: problem.locked_values[i] for i, n in enumerate(problem.names) if locked[i]},
                              "locked values and offsets that leave some error budget for the free sources")
    t[free] = np.clip(share / s[free], problem.lower[free], problem.upper[free])
    return problem.full(t[problem.free][None])[0]


@single_threaded_blas
def allocate_sensitivity(problem: ToleranceProblem, *, budget: float | None = None, measure: str | None = None,
                         collective_groups=()) -> AllocationResult:
    """Equal-effect allocation (see module docstring).

    Parameters
    ----------
    problem : evotol.core.problem.ToleranceProblem
        The problem (tolerances in SI: m or rad).
    budget : float or None
        If given (cost models' unit), best accuracy at this cost instead: the equal-effect design
        t_j ∝ 1/s_j scaled until it costs the budget (:mod:`evotol.allocators.budget`).
    measure : {"worst_case", "rss"} or None
        Stack-up the equal effects are summed in (default: the requirement's measure).
    collective_groups : sequence of str
        Source groups treated as one collective source (see :func:`aggregated_sensitivity`).

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
        A ``collective_groups`` entry that is not a group of interval sources, clearance classes
        in the problem, or locked tolerances that already exceed the requirement.

    Examples
    --------
    >>> from evotol.cost_models import PowerCost
    >>> from evotol import LinearStack, Tolerance, assembly_problem
    >>> stack = LinearStack({"x1": 1.0, "x2": -2.0, "x3": 0.5}, {"gap": 1e-4})  # gap = x1 - 2 x2 + x3 / 2
    >>> tol = {n: Tolerance(PowerCost(1.0, 1.0, scale=1e-3), lower=1e-7, upper=1e-4)
    ...        for n in stack.source_names}                                   # cost 1e-3 / t
    >>> problem = assembly_problem(stack, tol)                                # worst case <= 0.1 mm
    >>> from evotol import allocate_sensitivity
    >>> res = allocate_sensitivity(problem)                    # t_j ~ 1 / |a_j|
    >>> {n: round(t * 1e6, 2) for n, t in res.tolerances.items()}   # micrometres
    {'x1': 33.33, 'x2': 16.67, 'x3': 66.67}
    >>> res.feasible
    True
    """
    t0 = time.perf_counter()
    if budget is not None:
        budget = check_budget(problem, budget)
        s = aggregated_sensitivity(problem, collective_groups)
        family, log_p = _scaled(problem, np.where(s > 0, 1 / np.where(s > 0, s, 1.0), np.inf))
        t = spend_budget(problem, family, budget, log_p)
        return issue(make_result(problem, "sensitivity (best accuracy at budget)", t, seconds=time.perf_counter() - t0,
                                 info=budget_info(problem, t, budget), budget=budget))
    t = sensitivity_design(problem, measure, collective_groups)
    rule = f"equal effect, {measure or problem.requirement.measure} stack-up"
    if collective_groups:
        rule += f", collective groups {list(collective_groups)}"
    t, ev, repair = feasibility.hold_to_rule(problem, t)        # a rule's answer a hair outside is scaled in
    return issue(make_result(problem, "sensitivity" + (" (collective)" if collective_groups else ""), t, evaluation=ev,
                             seconds=time.perf_counter() - t0, info={"rule": rule, **repair}))
