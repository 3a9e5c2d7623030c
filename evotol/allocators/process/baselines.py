"""The textbook route to process selection: the cheapest processes that can hold the requirement,
then the sensitivity rule or the Lagrange closed form on that choice.

Both rules size the tolerances on one stack with the aggregated sensitivities ``s_j = max_k
|∂y_k/∂x_j| / L_k`` (:func:`evotol.allocators.sensitivity.aggregated_sensitivity`), which for
several responses is more conservative than every response. The processes are therefore chosen
so that the rules' own stack can hold the limit at the tightest tolerances; when no process choice
allows that but some choice holds the exact limit (several responses sharing the dimensions), the
choice is made on the exact limit and a rule that cannot size it is replaced by its tightest
tolerances scaled onto the exact limit (said in the method's name). :class:`InfeasibleError`
only when no process choice holds the limit at all.

The parameters several definitions of this module share are described once, here.

Parameters
----------
pp : ProcessProblem
    The problem.
"""
from __future__ import annotations

import time

import numpy as np

from evotol.allocators.baselines import allocate_lagrange
from evotol.allocators.process.problem import ProcessProblem, check_no_budget
from evotol.allocators.process.result import FEAS_TOL
from evotol.allocators.process.result import ProcessResult, _result
from evotol.allocators.sensitivity import aggregated_sensitivity, allocate_sensitivity
from evotol.errors import InfeasibleError, ValidationError
from evotol._runtime.blas_threads import single_threaded_blas


def check_some_choice_holds(pp: ProcessProblem) -> None:
    """:class:`InfeasibleError` when even every source's finest process at its lower limit misses
    the requirement (then no process choice can hold it); names the smallest error and its pose.

    Raises
    ------
    InfeasibleError
        If no process choice can hold the requirement.
    """
    try:
        pp.base.check_feasible()
    except InfeasibleError as exc:
        raise InfeasibleError(exc.requirement, exc.smallest_error, exc.pose,
                              "no process choice can hold it: every source at its finest process's lower limit") from None


def _rule_stack(pp: ProcessProblem, T: np.ndarray) -> np.ndarray:
    """The rules' one-stack model at designs T (n, S): Σ s_j t_j (worst case) or sqrt(Σ (s_j t_j)²)."""
    s = aggregated_sensitivity(pp.base)
    if pp.requirement.measure == "worst_case":
        return T @ s
    return np.sqrt((T * s) ** 2 @ np.ones(pp.n_sources))


def cheapest_feasible_processes(pp: ProcessProblem, *, model: str = "exact") -> np.ndarray:
    """Per source the cheapest process (lowest cost at its loosest tolerance); while even the
    tightest tolerances of that choice cannot hold the requirement, move the source with the
    largest tightest-tolerance effect to the cheapest of its finer processes (smaller lower limit).

    Parameters
    ----------
    model : {"exact", "rule"}
        ``"exact"``: the problem's measure (:meth:`ProcessProblem.normalised_error`); ``"rule"``: the
        rules' one-stack model with aggregated sensitivities.

    Returns
    -------
    numpy.ndarray
        Process index per source.

    Raises
    ------
    InfeasibleError
        No process choice holds the requirement (every source at its finest process's lower
        limit misses it).
    ValidationError
        An unknown ``model``, or the greedy search ends with no choice whose tightest
        tolerances hold (with ``model="rule"``: the rules' stack).
    """
    if model not in ("exact", "rule"):
        raise ValidationError("model", model, "'exact' or 'rule'")
    check_some_choice_holds(pp)
    S = pp.n_sources
    s = aggregated_sensitivity(pp.base)

    def holds(t):
        v = pp.normalised_error(t[None])[0] if model == "exact" else _rule_stack(pp, t[None])[0]
        return v <= 1 + FEAS_TOL

    choice = np.array([int(np.argmin([float(p.total(p.upper)) for p in pp.processes[n]])) for n in pp.names])
    for _ in range(int(pp.n_processes.sum()) + 1):
        t = pp.lo[np.arange(S), choice]
        if holds(t):
            return choice
        for j in np.argsort(-s * t):
            procs = pp.processes[pp.names[j]]
            finer = [k for k, p in enumerate(procs) if p.lower < t[j]]
            if finer:
                choice[j] = min(finer, key=lambda k: float(procs[k].total(procs[k].upper)))
                break
        else:
            break
    raise ValidationError("processes", pp.describe(), "processes whose tightest tolerances hold the sensitivity rules' "
                          "one-stack model (aggregated sensitivities)")


def _onto_limit(pp: ProcessProblem, choice, t: np.ndarray) -> np.ndarray:
    """t ← clip(t / error) in the chosen ranges, repeated: a design scaled onto the exact limit."""
    idx = np.arange(pp.n_sources)
    lo, hi = pp.lo[idx, choice], pp.hi[idx, choice]
    for _ in range(60):
        ne = float(pp.normalised_error(t[None])[0])
        tn = np.clip(t / ne, lo, hi)
        if np.allclose(tn, t, rtol=1e-13, atol=0):
            break
        t = tn
    for _ in range(1000):                                   # clipping can leave it a hair outside
        if pp.normalised_error(t[None])[0] <= 1 + 1e-12:
            break
        t = np.maximum(t * (1 - 1e-9), lo)
    return t


@single_threaded_blas
def allocate_process_baselines(problem: ProcessProblem, *, budget: None = None) -> dict[str, ProcessResult]:
    """Sensitivity rule and Lagrange closed form on the cheapest processes that can hold the limit.

    Parameters
    ----------
    problem : ProcessProblem
        Process and tolerance per source (tolerances in SI: m or rad).
    budget : None
        Must be None: process selection minimises cost at the requirement (the one allocator
        shape; a budget is refused in one line).

    Returns
    -------
    dict[str, ProcessResult]
        ``{"sensitivity": ProcessResult, "lagrange": ProcessResult}``: each rule's tolerances (SI) and
        cost (cost models' unit); a rule whose design misses the limit (e.g. by clipping at a range) is
        reported ``feasible=False``.

    Raises
    ------
    InfeasibleError
        No process choice can hold the requirement.
    ValidationError
        A ``budget``, or a ``problem`` that is not a :class:`ProcessProblem`.

    Examples
    --------
    >>> from evotol.cost_models import PowerCost
    >>> from evotol import LinearStack, Tolerance, assembly_problem
    >>> stack = LinearStack({"x1": 1.0, "x2": -2.0, "x3": 0.5}, {"gap": 1e-4})  # gap = x1 - 2 x2 + x3 / 2
    >>> tol = {n: Tolerance(PowerCost(1.0, 1.0, scale=1e-3), lower=1e-7, upper=1e-4)
    ...        for n in stack.source_names}                                   # cost 1e-3 / t
    >>> problem = assembly_problem(stack, tol)                                # worst case <= 0.1 mm
    >>> from evotol import Process
    >>> turn = Process("turning", PowerCost(1.0, 1.0, scale=1e-3), lower=3e-5, upper=1e-4)
    >>> grind = Process("grinding", PowerCost(3.0, 1.0, scale=1e-3), lower=2e-6, upper=3e-5)
    >>> pp = assembly_problem(stack, processes={n: [turn, grind] for n in stack.source_names})
    >>> from evotol import allocate_process_baselines
    >>> base = allocate_process_baselines(pp)
    >>> sorted(base)
    ['lagrange', 'sensitivity']
    >>> base["sensitivity"].processes, round(base["sensitivity"].cost, 6)   # 30 + 180 + 15
    ({'x1': 'turning', 'x2': 'grinding', 'x3': 'turning'}, 225.0)
    """
    pp = check_no_budget(problem, budget, "allocate_process_baselines")
    out = {}
    t0 = time.perf_counter()
    try:
        choice, on = cheapest_feasible_processes(pp, model="rule"), "the cheapest feasible processes"
    except ValidationError:
        choice, on = cheapest_feasible_processes(pp), "the cheapest processes that hold the exact limit"
    sub = pp.subproblem(choice)
    for key, fn in (("sensitivity", allocate_sensitivity), ("lagrange", allocate_lagrange)):
        t1 = time.perf_counter()
        try:
            r = fn(sub)
            res = _result(pp, f"{r.method} on {on}", choice, r.t, t1)
        except ValidationError:     # the rule's one-stack model cannot hold the limit on any choice
            t = _onto_limit(pp, choice, sub.lower.copy())
            res = _result(pp, f"{key} rule unavailable (its one-stack model cannot hold the limit): tightest "
                              f"tolerances of {on} scaled onto the limit", choice, t, t1)
        res.seconds += t1 - t0
        out[key] = res
    return out
