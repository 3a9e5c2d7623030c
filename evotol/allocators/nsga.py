"""Cost vs. accuracy trade-off: the whole Pareto front in one NSGA-II run (pymoo).

Objectives: total cost and the largest normalised error over the poses (error / bound, the
maximum over the constrained components; 1 = exactly at the requirement). The requirement itself
is not imposed: the front spans tolerances from the tightest to the loosest bounds. Each
generation the current front is checked exactly (lazy worst-case rows, a pymoo callback); the
returned front is re-evaluated exactly and filtered for non-dominance. The run itself is evotol's
one NSGA-II driver, :func:`evotol.allocators.nsga_driver.run_nsga2`.
"""
from __future__ import annotations

import time

import numpy as np
import pandas as pd
from pymoo.core.callback import Callback
from pymoo.core.problem import Problem

from evotol.allocators.ga import initial_population
from evotol.allocators.nsga_driver import run_nsga2  # noqa: F401  (the driver; its old import path)
from evotol.measures.constraints import ConstraintRows, constraint_rows
from evotol.measures import feasibility
from evotol.errors import ValidationError
from evotol.core.pareto import ParetoFront, non_dominated
from evotol.core.problem import ToleranceProblem
from evotol._runtime.blas_threads import single_threaded_blas
from evotol._runtime.random_state import seed_from


class _FrontProblem(Problem):
    """Variables are log(t) when ``log_scale`` (tolerance ranges spanning decades), else t."""

    def __init__(self, tp: ToleranceProblem, rows: ConstraintRows | None, log_scale: bool):
        f = tp.free
        lo, hi = (np.log(tp.lower[f]), np.log(tp.upper[f])) if log_scale else (tp.lower[f], tp.upper[f])
        super().__init__(n_var=int(f.sum()), n_obj=2, xl=lo, xu=hi)
        self.tp, self.rows, self.log_scale = tp, rows, log_scale

    def tolerances(self, X):
        return self.tp.full(np.exp(X) if self.log_scale else X)

    def _evaluate(self, X, out, *args, **kwargs):
        T = self.tolerances(X)
        err = self.rows.normalised_error(T) if self.rows is not None else self.tp.evaluate(T).violation + 1
        out["F"] = np.stack([self.tp.cost(T), err], axis=1)


class _CheckFront(Callback):
    """After every generation: check a few front members exactly (lazy worst-case rows; when
    rows were added, re-score the population), record the front."""

    def __init__(self, fp: _FrontProblem, rows: ConstraintRows | None, rng, n_check: int):
        super().__init__()
        self.fp, self.rows, self.rng, self.n_check = fp, rows, rng, n_check
        self.history: list[dict] = []

    def notify(self, algo):
        rows, fp = self.rows, self.fp
        if rows is not None and rows.measure == "worst_case":
            X = algo.opt.get("X")
            pick = self.rng.choice(len(X), size=min(self.n_check, len(X)), replace=False)
            _, added = rows.check(fp.tolerances(X[pick]))
            if added:  # re-score the population with the new rows
                F = algo.pop.get("F")
                F[:, 1] = rows.normalised_error(fp.tolerances(algo.pop.get("X")))
                algo.pop.set("F", F)
        F = algo.opt.get("F")
        self.history.append({"generation": algo.n_iter, "front_size": len(F), "min_cost": float(F[:, 0].min()),
                             "min_error": float(F[:, 1].min())})


@single_threaded_blas
def allocate_nsga2(problem: ToleranceProblem, *, budget: float | None = None, pop_size: int = 100, n_gen: int = 200,
                   seed: int = 0, rng: int | np.random.Generator | None = None, seeds=(), n_check: int = 5, progress: bool | None = None,
                   log_scale: bool | None = None) -> ParetoFront:
    """NSGA-II cost vs. normalised error (see module docstring).

    Parameters
    ----------
    problem : evotol.core.problem.ToleranceProblem
        The problem (tolerances in SI: m or rad).
    budget : None
        Accepted for the shape every allocator shares and must be None: the front spans every
        budget (read a point with ``front.table``, or use ``allocate_ga(problem, budget=...)``).
    pop_size, n_gen : int
        Population size (>= 4) and number of generations (>= 1).
    seed : int
        Seed of the run (>= 0); the run is reproducible from it.
    rng : int, numpy.random.Generator or None, optional
        As SciPy's ``rng``: an integer seed, or a Generator drawn from once for the seed of the run
        (recorded in the result); replaces ``seed`` (which keeps working, and also takes a Generator).
    seeds : sequence of mapping or array
        Designs (SI) placed in the initial population.
    n_check : int
        Front members checked exactly per generation (missed worst-case rows are added).
    progress : bool or None
        tqdm bar over generations (default: only on an interactive terminal).
    log_scale : bool or None
        Search log(t) (default: when some tolerance range spans more than two decades).

    Returns
    -------
    ParetoFront
        ``table``: the non-dominated designs by increasing cost, with ``cost`` (cost models'
        unit), ``normalised_error`` (error / requirement, 1), ``<component>_error`` (m, rad) and
        one column per source (SI); ``seconds`` and the per-generation ``history``.

    Raises
    ------
    evotol.errors.ValidationError
        A ``budget`` that is not None, or a ``pop_size``/``n_gen``/``seed`` out of range.

    Examples
    --------
    >>> from evotol.cost_models import PowerCost
    >>> from evotol import LinearStack, Tolerance, assembly_problem
    >>> stack = LinearStack({"x1": 1.0, "x2": -2.0, "x3": 0.5}, {"gap": 1e-4})  # gap = x1 - 2 x2 + x3 / 2
    >>> tol = {n: Tolerance(PowerCost(1.0, 1.0, scale=1e-3), lower=1e-7, upper=1e-4)
    ...        for n in stack.source_names}                                   # cost 1e-3 / t
    >>> problem = assembly_problem(stack, tol)                                # worst case <= 0.1 mm
    >>> from evotol import allocate_nsga2
    >>> front = allocate_nsga2(problem, pop_size=20, n_gen=10, seed=0)
    >>> list(front.table.columns[:2])
    ['cost', 'normalised_error']
    >>> bool(front.cheapest_feasible()["normalised_error"] <= 1.0)
    True
    """
    t0 = time.perf_counter()
    if budget is not None:
        raise ValidationError("budget", budget, "None for allocate_nsga2 (the front covers every budget; "
                              "allocate_ga(problem, budget=...) gives the best accuracy at one)")
    seed = seed_from(rng, seed)
    for name, v, lo in (("pop_size", pop_size, 4), ("n_gen", n_gen, 1), ("seed", seed, 0)):
        if not isinstance(v, (int, np.integer)) or v < lo:
            raise ValidationError(name, v, f"an integer >= {lo}")
    rows = constraint_rows(problem, seed=seed)
    f = problem.free
    if log_scale is None:
        log_scale = bool(np.any(problem.upper[f] / problem.lower[f] > 100))
    fp = _FrontProblem(problem, rows, log_scale)
    X0 = initial_population(problem, pop_size, seed, seeds, log_scale=log_scale)
    watch = _CheckFront(fp, rows, np.random.default_rng(seed), n_check)
    algo = run_nsga2(fp, pop_size=pop_size, n_gen=n_gen, seed=seed, sampling=X0, callback=watch, interruptible=True,
                     progress=progress, size=f"{n_gen} generations × {pop_size} designs × {problem.n_poses} poses")
    T = fp.tolerances(algo.pop.get("X"))
    ev = problem.evaluate(T, top_only=True)
    err = ev.violation + 1
    cost = problem.cost(T)
    nd = non_dominated(np.stack([cost, err], 1))
    T, err = T[nd].copy(), err[nd].copy()
    comp_err = {comp: np.max(getattr(ev, comp)[nd], axis=1) for comp, _ in problem.components}
    # members that meet the requirement by their attained error are held to the one rule of
    # evotol.measures.feasibility (proven bound <= requirement x (1 + 1e-6)); one a hair outside is scaled in
    proven = np.full(len(nd), np.nan)
    repaired = np.zeros(len(nd), dtype=bool)
    for i in np.flatnonzero(err <= 1 + feasibility.FEASIBILITY_RTOL):
        t_i, ev_i, fix = feasibility.repair_by_scaling(problem, T[i], max_miss=np.inf)
        proven[i] = feasibility.bound_ratio(problem, ev_i)
        if fix is not None and not fix.get("failed"):
            T[i], repaired[i] = t_i, True
            err[i] = max(float(ev_i.violation[0] + 1), 0.0)
            for comp, _ in problem.components:
                comp_err[comp][i] = float(np.max(getattr(ev_i, comp)[0]))
    cost = problem.cost(T)
    order = np.argsort(cost, kind="stable")
    table = pd.DataFrame({"cost": cost[order], "normalised_error": err[order], "proven_ratio": proven[order],
                          "repaired": repaired[order]})
    for comp, _ in problem.components:
        table[f"{comp}_error"] = comp_err[comp][order]
    for j, n in enumerate(problem.names):
        table[n] = T[order, j]
    feasible_rows = (table["normalised_error"] <= 1 + feasibility.FEASIBILITY_RTOL) & ~(table["proven_ratio"] > 1 + feasibility.FEASIBILITY_RTOL)
    table.loc[~feasible_rows & (table["normalised_error"] <= 1), "normalised_error"] = table["proven_ratio"]
    return ParetoFront(table.reset_index(drop=True), time.perf_counter() - t0, pd.DataFrame(watch.history),
                       rtol=feasibility.FEASIBILITY_RTOL)
