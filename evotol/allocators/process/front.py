"""NSGA-II fronts of process selection: cost vs. normalised error or vs. miss probability, on the
GA's encoding (:mod:`evotol.allocators.process.ga`)."""
from __future__ import annotations

import numpy as np
import pandas as pd
from pymoo.core.problem import Problem

from evotol.allocators.nsga_driver import run_nsga2
from evotol.allocators.process.ga import _decode
from evotol.allocators.process.problem import check_no_budget, ProcessProblem
from evotol.errors import ValidationError
from evotol.core.pareto import ParetoFront
from evotol._runtime.blas_threads import single_threaded_blas
from evotol._runtime.random_state import seed_from


class _ProcessFrontProblem(Problem):
    """Two objectives on the GA's encoding: cost and either the normalised worst-case/RSS error
    (``objective="error"``) or the miss probability 1 − yield (``objective="yield"``, see
    :meth:`ProcessProblem.assembly_yield`)."""

    def __init__(self, pp: ProcessProblem, objective: str, yield_model=None):
        super().__init__(n_var=pp.n_sources, n_obj=2, xl=np.zeros(pp.n_sources), xu=pp.n_processes - 1e-9)
        self.pp, self.objective, self.yield_model = pp, objective, yield_model

    def second(self, T) -> np.ndarray:
        if self.objective == "yield":
            return 1.0 - self.pp.assembly_yield(T, self.yield_model)
        return self.pp.normalised_error(T)

    def _evaluate(self, X, out, *args, **kwargs):
        k, T, _, _ = _decode(self.pp, X)
        out["F"] = np.column_stack([self.pp.cost(k, T), self.second(T)])


#: second objective of a process front beside cost: the normalised stack error ("error") or the
#: assembly yield ("yield")
FRONT_OBJECTIVES = ("error", "yield")


#: miss probability of a 3σ design, 2Φ(−3): the default feasibility limit of a yield front
THREE_SIGMA_MISS = 0.0026997960632601866


@single_threaded_blas
def process_front(problem: ProcessProblem, *, budget: None = None, seed: int = 0, rng: int | np.random.Generator | None = None, objective: str = "error",
                  pop_size: int = 60, n_gen: int = 100, distribution="normal",
                  max_miss: float = THREE_SIGMA_MISS) -> ParetoFront:
    """NSGA-II front (:func:`evotol.allocators.nsga_driver.run_nsga2`) of cost vs. a second objective.

    Parameters
    ----------
    problem : ProcessProblem
        The process-selection problem.
    budget : None
        Must be None: process selection minimises cost at the requirement (the one allocator
        shape; a budget is refused in one line).
    seed : int
        Seed of pymoo's random generator.
    rng : int, numpy.random.Generator or None, optional
        As SciPy's ``rng``: an integer seed, or a Generator drawn from once for the seed of the run
        (recorded in the result); replaces ``seed`` (which keeps working, and also takes a Generator).
    objective : {"error", "yield"}
        ``"error"``: the normalised error (max error / bound, the problem's measure);
        ``"yield"``: the miss probability 1 − yield of the first-order statistical model
        (``distribution`` per source, default normal with t = 3σ; :meth:`ProcessProblem.assembly_yield`).
    pop_size, n_gen : int
        NSGA-II population and generations.
    distribution : str or evotol.measures.statistical.distributions.Distribution
        Distribution of every source for ``objective="yield"``.
    max_miss : float
        For ``objective="yield"``: the miss probability a feasible design may have
        (:meth:`ParetoFront.cheapest_feasible`); default 2Φ(−3) = 0.27 % (yield of a 3σ design).

    Returns
    -------
    ParetoFront
        ``table``: one row per front member sorted by cost (cost, the objective's column --
        ``normalised_error``, or ``miss_probability`` and ``yield`` --, per source
        ``<name>_process`` and ``<name>_t`` in m).

    Raises
    ------
    ValidationError
        An unknown ``objective``, a ``budget``, or a ``problem`` that is not a
        :class:`ProcessProblem`.

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
    >>> from evotol import process_front
    >>> front = process_front(pp, pop_size=20, n_gen=10, seed=0)
    >>> list(front.table.columns)                              # doctest: +NORMALIZE_WHITESPACE
    ['cost', 'normalised_error', 'x1_process', 'x1_t', 'x2_process', 'x2_t',
     'x3_process', 'x3_t']
    """
    import time

    pp = check_no_budget(problem, budget, "process_front")
    seed = seed_from(rng, seed)

    if objective not in FRONT_OBJECTIVES:
        raise ValidationError("objective", objective, f"one of {FRONT_OBJECTIVES}")
    t0 = time.perf_counter()
    model = pp.yield_model(distribution) if objective == "yield" else None
    prob = _ProcessFrontProblem(pp, objective, model)
    algo = run_nsga2(prob, pop_size=pop_size, n_gen=n_gen, seed=seed)
    X, F = algo.opt.get("X"), algo.opt.get("F")
    k, T, _, _ = _decode(pp, np.atleast_2d(X))
    df = pd.DataFrame({"cost": F[:, 0]})
    if objective == "yield":
        df["miss_probability"] = F[:, 1]
        df["yield"] = 1.0 - F[:, 1]
    else:
        df["normalised_error"] = F[:, 1]
    for j, n in enumerate(pp.names):
        df[f"{n}_process"] = [pp.processes[n][i].name for i in k[:, j]]
        df[f"{n}_t"] = T[:, j]
    if objective == "yield":
        return ParetoFront(df.sort_values("cost", ignore_index=True), time.perf_counter() - t0,
                           objective="miss_probability", limit=float(max_miss))
    return ParetoFront(df.sort_values("cost", ignore_index=True), time.perf_counter() - t0)
