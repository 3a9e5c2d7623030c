"""Exact process selection: branch and bound over process choices with Lagrange-dual node bounds,
or full enumeration (conventions and the bound: :mod:`evotol.allocators.process`)."""
from __future__ import annotations

import itertools
import time
from typing import Sequence

import numpy as np
from scipy.optimize import nnls

from evotol.allocators.optimum import allocate_optimum
from evotol.allocators.process.baselines import check_some_choice_holds, cheapest_feasible_processes
from evotol.allocators.process.problem import ProcessProblem, check_no_budget
from evotol.allocators.process.result import FEAS_TOL
from evotol.allocators.process.result import ProcessResult, _result
from evotol.measures.constraints import ConstraintRows
from evotol.errors import ValidationError
from evotol.core.problem import ToleranceProblem
from evotol._runtime.blas_threads import single_threaded_blas


def _multipliers(sub: ToleranceProblem, rows: ConstraintRows, t: np.ndarray, active_tol: float = 1e-6):
    """KKT multipliers (λ on linear rows, μ on quadratic rows) of a solved subproblem, by NNLS."""
    grad = sub.dcost(t)
    ga = rows.A @ t if rows.A.shape[0] else np.zeros(0)
    gb = rows.B @ t ** 2 if rows.B.shape[0] else np.zeros(0)
    act_a = np.flatnonzero(ga >= 1 - active_tol)
    act_b = np.flatnonzero(gb >= 1 - 2 * active_tol)
    interior = (t > sub.lower * (1 + 1e-9)) & (t < sub.upper * (1 - 1e-9))
    M = np.concatenate([rows.A[act_a].T, (2 * rows.B[act_b] * t).T], axis=1)[interior]
    lam, mu = np.zeros(rows.A.shape[0]), np.zeros(rows.B.shape[0])
    if M.shape[0] and M.shape[1]:
        coef, _ = nnls(M, -grad[interior], maxiter=50 * M.shape[1])
        lam[act_a], mu[act_b] = coef[:act_a.size], coef[act_a.size:]
    elif act_a.size + act_b.size:  # every source at a bound: any positive direction is a valid multiplier
        lam[act_a], mu[act_b] = 1.0, 1.0
    return lam, mu


class _DualTables:
    """Per (scale s, source j, process p) inner minima of the Lagrangian, for node bounds."""

    def __init__(self, pp: ProcessProblem, rows: ConstraintRows, scales: np.ndarray):
        self.pp, self.rows, self.scales = pp, rows, scales
        self.tables: list[tuple[np.ndarray, np.ndarray]] = []   # (M (s, j, p), offset (s,))

    def add(self, lam: np.ndarray, mu: np.ndarray, scales: np.ndarray | None = None) -> None:
        pp, s = self.pp, (self.scales if scales is None else np.asarray(scales, dtype=float))
        w = self.rows.A.T @ lam if lam.size else np.zeros(pp.n_sources)
        v = self.rows.B.T @ mu if mu.size else np.zeros(pp.n_sources)
        P = pp.lo.shape[1]
        M = np.full((s.size, pp.n_sources, P), np.inf)
        for j, n in enumerate(pp.names):
            for k, p in enumerate(pp.processes[n]):
                W, V = s * w[j], s * v[j]
                lo, hi = np.full(s.size, p.lower), np.full(s.size, p.upper)

                def deriv(t):
                    return p.cost.dcost(t) + W + 2 * V * t

                a, b = lo.copy(), hi.copy()
                for _ in range(60):
                    mid = np.sqrt(a * b)
                    neg = deriv(mid) < 0
                    a, b = np.where(neg, mid, a), np.where(neg, b, mid)
                t = np.sqrt(a * b)
                t = np.where(deriv(lo) >= 0, lo, np.where(deriv(hi) <= 0, hi, t))
                M[:, j, k] = p.total(t) + W * t + V * t ** 2
        self.tables.append((M, s * (lam.sum() + mu.sum())))

    def bound(self, fixed: Sequence[int]) -> float:
        d = len(fixed)
        best = -np.inf
        for M, off in self.tables:
            val = -off
            if d:
                val = val + M[:, np.arange(d), np.asarray(fixed)].sum(axis=1)
            if d < M.shape[1]:
                val = val + M[:, d:, :].min(axis=2).sum(axis=1)
            best = max(best, float(np.max(val)))
        return best


@single_threaded_blas
def allocate_process_optimum(problem: ProcessProblem, *, budget: None = None, method: str = "branch_and_bound",
                             rtol: float = 1e-7, incumbent: ProcessResult | None = None) -> ProcessResult:
    """Exact minimum-cost process choice and tolerances (see the module docstring).

    Parameters
    ----------
    problem : ProcessProblem
        Process and tolerance per source (tolerances in SI: m or rad).
    budget : None
        Must be None: process selection minimises cost at the requirement (the one allocator
        shape; a budget is refused in one line).
    method : {"branch_and_bound", "enumerate"}
        Branch and bound on dual lower bounds, or every combination's convex optimum.
    rtol : float
        A node is pruned when its bound >= incumbent × (1 − rtol) (1, dimensionless).
    incumbent : ProcessResult or None
        A known feasible design whose cost starts the pruning.

    Returns
    -------
    ProcessResult
        The process of every source, its tolerance (SI), the cost (machining plus fixed costs,
        cost models' unit), the normalised error (error / requirement, 1) and how it was found,
        with the node and solve counts and the certificate of the optimum.

    Raises
    ------
    evotol.errors.ValidationError
        An unknown ``method``, a ``budget``, a ``problem`` that is not a :class:`ProcessProblem`,
        no process choice whose convex optimum the solver finds, or a requirement measure other
        than ``worst_case`` or ``rss`` (from :class:`evotol.measures.constraints.ConstraintRows`).
    evotol.errors.InfeasibleError
        No process choice can hold the requirement (every source at its finest process's lower limit misses it).

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
    >>> from evotol import allocate_process_optimum
    >>> best = allocate_process_optimum(pp)                    # exact: branch and bound
    >>> best.processes                                          # x2 needs grinding
    {'x1': 'turning', 'x2': 'grinding', 'x3': 'turning'}
    >>> best.feasible, round(best.cost, 2)
    (True, 175.68)
    """
    pp = check_no_budget(problem, budget, "allocate_process_optimum")
    if method not in ("branch_and_bound", "enumerate"):
        raise ValidationError("method", method, "'branch_and_bound' or 'enumerate'")
    t0 = time.perf_counter()
    check_some_choice_holds(pp)
    rows = ConstraintRows(pp.base)
    S = pp.n_sources
    state = {"cost": np.inf, "choice": None, "t": None, "cert": None, "solves": 0, "nodes": 0}
    lo_min = np.nanmin(pp.lo, axis=1)

    def tight_violation(fixed) -> float:
        d = len(fixed)
        t = lo_min.copy()
        if d:
            t[:d] = pp.lo[np.arange(d), np.asarray(fixed)]
        return float(rows.violation(t[None])[0])

    def solve_leaf(choice):
        sub = pp.subproblem(choice)
        state["solves"] += 1
        r = allocate_optimum(sub)
        if not r.feasible:
            return None
        cost = r.cost + pp.fixed_cost(choice)
        return cost, r.t, r.certificate, sub

    tables = None
    if method == "branch_and_bound":
        tables = _DualTables(pp, rows, np.geomspace(1e-4, 1e4, 81))
        # λ = 0: the cheapest tolerance per source, ignoring the requirement (prunes everything when
        # the requirement is loose and the leaf multipliers are all zero)
        tables.add(np.zeros(rows.A.shape[0]), np.zeros(rows.B.shape[0]), scales=[1.0])

    def offer(choice, leaf):
        cost, t, cert, sub = leaf
        if tables is not None:
            lam, mu = _multipliers(sub, rows, t)
            if lam.sum() + mu.sum() > 0:
                tables.add(lam, mu)
        if cost < state["cost"]:
            state.update(cost=cost, choice=np.array(choice), t=t, cert=cert)

    if incumbent is not None:
        ch = pp.choice_index(incumbent.processes)
        leaf = solve_leaf(ch)
        if leaf is not None:
            offer(ch, leaf)
    pruned_bounds = []
    if method == "enumerate":
        for choice in itertools.product(*[range(k) for k in pp.n_processes]):
            state["nodes"] += 1
            if tight_violation(list(choice)) > FEAS_TOL:
                continue
            leaf = solve_leaf(choice)
            if leaf is not None:
                offer(choice, leaf)
    else:
        # a first incumbent: the cheapest feasible processes (gives the first multipliers)
        if state["choice"] is None:
            ch = cheapest_feasible_processes(pp)      # InfeasibleError when no process choice can hold
            if ch is not None:
                leaf = solve_leaf(ch)
                if leaf is not None:
                    offer(ch, leaf)

        def visit(fixed):
            state["nodes"] += 1
            if tight_violation(fixed) > FEAS_TOL:
                return
            if len(fixed) == S:
                if state["choice"] is not None and tuple(state["choice"]) == tuple(fixed):
                    return
                leaf = solve_leaf(fixed)
                if leaf is not None:
                    offer(fixed, leaf)
                return
            kids = [fixed + [k] for k in range(pp.n_processes[len(fixed)])]
            bounds = [tables.bound(c) if tables.tables else -np.inf for c in kids]
            for b, c in sorted(zip(bounds, kids), key=lambda x: x[0]):
                b = tables.bound(c) if tables.tables else -np.inf   # tables may have grown
                if b >= state["cost"] * (1 - rtol):
                    pruned_bounds.append(b)
                    continue
                visit(c)

        visit([])
    if state["choice"] is None:      # every leaf's convex solve failed although a choice can hold the limit
        raise ValidationError("processes", pp.describe(), "at least one process choice whose convex optimum the solver finds")
    cert = {"leaf_gap": state["cert"].get("gap"), "leaf_kkt_residual": state["cert"].get("kkt_residual"),
            "incumbent": state["cost"], "rtol": rtol,
            "smallest_pruned_bound": float(min(pruned_bounds)) if pruned_bounds else None,
            "proof": ("every combination's convex optimum was computed" if method == "enumerate" else
                      "every unexplored node has a Lagrange-dual lower bound >= incumbent·(1 − rtol) or an infeasible tightest design")}
    return _result(pp, f"exact ({method.replace('_', ' ')})", state["choice"], state["t"], t0, n_nodes=state["nodes"],
                   n_convex_solves=state["solves"], n_combinations=pp.n_combinations, certificate=cert)
