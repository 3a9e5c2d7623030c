"""GA over process choices and tolerances: one real gene per source (process index + log-position
in its range), a boundary repair, pymoo's GA (encoding: :mod:`evotol.allocators.process`)."""
from __future__ import annotations

import time

import numpy as np
from pymoo.core.callback import Callback
from pymoo.core.problem import Problem
from pymoo.core.repair import Repair

from evotol.allocators.process.problem import check_no_budget, ProcessProblem
from evotol.allocators.process.result import ProcessResult, _result
from evotol.measures.constraints import ConstraintRows
from evotol.errors import ValidationError
from evotol._runtime.blas_threads import single_threaded_blas
from evotol._runtime.random_state import seed_from


def _decode(pp: ProcessProblem, X: np.ndarray):
    k = np.clip(np.floor(X).astype(int), 0, pp.n_processes - 1)
    u = np.clip(X - k, 0.0, 1.0)
    idx = np.arange(pp.n_sources)
    lo, hi = pp.lo[idx, k], pp.hi[idx, k]
    return k, lo * (hi / lo) ** u, lo, hi


def _encode(k, T, lo, hi):
    span = np.log(hi / lo)
    u = np.where(span > 0, np.log(np.clip(T, lo, hi) / lo) / np.where(span > 0, span, 1.0), 0.0)
    return k + np.clip(u, 0.0, 1 - 1e-12)


def _repair(pp, rows, X, iters: int = 25):
    k, T, lo, hi = _decode(pp, X)
    for _ in range(iters):
        ne = rows.normalised_error(T)
        if pp.loss_coefficients.any():   # cost + loss is not monotone: only pull infeasible designs in
            ne = np.maximum(ne, 1.0)
        Tn = np.clip(T / ne[:, None], lo, hi)
        if np.allclose(Tn, T, rtol=1e-13, atol=0):
            break
        T = Tn
    return _encode(k, T, lo, hi)


class _ProcessRepair(Repair):
    """Scale every design's tolerances onto the constraint (see :func:`_repair`)."""

    def __init__(self, pp: ProcessProblem, rows: ConstraintRows):
        super().__init__()
        self.pp, self.rows = pp, rows

    def _do(self, problem, X, **kwargs):
        return _repair(self.pp, self.rows, X)


class _ProcessGAProblem(Problem):
    """One gene per source (process index + position in its range): cost, one constraint max error/bound − 1."""

    def __init__(self, pp: ProcessProblem):
        super().__init__(n_var=pp.n_sources, n_obj=1, n_ieq_constr=1, xl=np.zeros(pp.n_sources),
                         xu=pp.n_processes - 1e-9)
        self.pp = pp

    def _evaluate(self, X, out, *args, **kwargs):
        k, T, _, _ = _decode(self.pp, X)
        out["F"] = self.pp.cost(k, T)[:, None]
        out["G"] = (self.pp.normalised_error(T) - 1)[:, None]


class _History(Callback):
    """Best feasible cost after every generation (NaN before the first feasible design)."""

    def __init__(self):
        super().__init__()
        self.costs: list[float] = []

    def notify(self, algorithm):
        opt = algorithm.opt
        self.costs.append(float(opt.get("F")[0, 0]) if opt.get("CV")[0, 0] <= 0 else float("nan"))


@single_threaded_blas
def allocate_process_ga(problem: ProcessProblem, *, budget: None = None, seed: int = 0, rng: int | np.random.Generator | None = None, pop_size: int = 60,
                        n_gen: int = 100, repair: bool = True) -> ProcessResult:
    """pymoo GA over process choices and tolerances (encoding and repair: module docstring).

    Parameters
    ----------
    problem : ProcessProblem
        Process and tolerance per source (tolerances in SI: m or rad).
    budget : None
        Must be None: process selection minimises cost at the requirement (the one allocator
        shape; a budget is refused in one line).
    pop_size, n_gen : int
        Population size and number of generations.
    seed : int
        Seed of the run; the run is reproducible from it.
    rng : int, numpy.random.Generator or None, optional
        As SciPy's ``rng``: an integer seed, or a Generator drawn from once for the seed of the run
        (recorded in the result); replaces ``seed`` (which keeps working, and also takes a Generator).
    repair : bool
        Scale the tolerances of every design onto the requirement's boundary.

    Returns
    -------
    ProcessResult
        The process of every source, its tolerance (SI), the cost (machining plus fixed costs,
        cost models' unit), the normalised error (error / requirement, 1) and how it was found,
        with the best cost per generation (``history``).

    Raises
    ------
    evotol.errors.ValidationError
        The GA found no feasible design (raise ``n_gen`` / ``pop_size``), a ``budget``, a
        ``problem`` that is not a :class:`ProcessProblem`, or a requirement measure other than
        ``worst_case`` or ``rss`` (from :class:`evotol.measures.constraints.ConstraintRows`).

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
    >>> from evotol import allocate_process_ga, allocate_process_optimum
    >>> ga = allocate_process_ga(pp, pop_size=20, n_gen=10, seed=0)
    >>> ga.feasible, ga.cost >= allocate_process_optimum(pp).cost * (1 - 1e-9)
    (True, True)
    """
    from pymoo.algorithms.soo.nonconvex.ga import GA
    from pymoo.optimize import minimize

    pp = check_no_budget(problem, budget, "allocate_process_ga")
    seed = seed_from(rng, seed)

    t0 = time.perf_counter()
    rows = ConstraintRows(pp.base)
    hist = _History()
    alg = GA(pop_size=pop_size, repair=_ProcessRepair(pp, rows) if repair else None, eliminate_duplicates=True)
    res = minimize(_ProcessGAProblem(pp), alg, ("n_gen", n_gen), seed=seed, verbose=False, callback=hist)
    if res.X is None:
        raise ValidationError("processes", pp.describe(), "a feasible design found by the GA (raise n_gen / pop_size)")
    k, T, _, _ = _decode(pp, np.atleast_2d(res.X))
    return _result(pp, "GA (pymoo, one gene per source)", k[0], T[0], t0, history=hist.costs)
