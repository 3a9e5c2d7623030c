"""The result of a process-selection allocation: the process and tolerance chosen for every
source, its cost and how it was found (conventions: :mod:`evotol.allocators.process`)."""
from __future__ import annotations

import time
from dataclasses import dataclass, field

import numpy as np
import pandas as pd

#: relative slack of the process-selection feasibility test (normalised stack error <= 1 + FEAS_TOL):
#: what a result calls feasible, what branch and bound prunes with and what the baselines accept
FEAS_TOL = 1e-9


@dataclass
class ProcessResult:
    """A process choice and tolerances (SI), with its cost and how it was found.

    Parameters
    ----------
    method : str
        Name of the allocation method.
    processes : dict of str to str
        Source name -> chosen process name.
    tolerances : dict of str to float
        Source name -> tolerance (m or rad).
    cost : float
        Total cost, set-up costs included (cost units).
    feasible : bool
        Whether the design holds the requirement (normalised error <= 1 + ``FEAS_TOL``) and every
        tolerance is in its process's range.
    normalised_error : float
        Exact max error / bound (dimensionless; <= 1 holds).
    seconds : float
        Wall time of the allocation (s).
    n_nodes : int or None
        Branch-and-bound nodes explored, when applicable.
    n_convex_solves : int or None
        Convex subproblems solved, when applicable.
    n_combinations : int or None
        Number of process combinations of the problem, when reported.
    certificate : dict or None
        Optimality certificate of the exact method (incumbent, smallest pruned lower bound,
        ``rtol``, the leaf's gap and KKT residual, the proof's wording).
    history : list or None
        Per-generation record of the GA (best feasible cost, NaN while none), when kept.

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
    >>> best = allocate_process_optimum(pp)
    >>> print(best.table(pp, unit=1e-6, unit_name="um").round(2).to_string(index=False))
    source  process  tolerance (um)   cost
        x1  turning           30.00  33.33
        x2 grinding           27.16 110.46
        x3  turning           31.36  31.89
    """

    method: str
    processes: dict[str, str]
    tolerances: dict[str, float]
    cost: float
    feasible: bool
    normalised_error: float
    seconds: float = 0.0
    n_nodes: int | None = None
    n_convex_solves: int | None = None
    n_combinations: int | None = None
    certificate: dict | None = None
    history: list | None = field(default=None, repr=False)

    def to_dict(self) -> dict:
        """JSON-ready summary of the result (without ``history``).

        Returns
        -------
        dict
            The fields from ``method`` to ``certificate``, those that are None left out.
        """
        d = {k: getattr(self, k) for k in ("method", "processes", "tolerances", "cost", "feasible", "normalised_error",
                                            "seconds", "n_nodes", "n_convex_solves", "n_combinations", "certificate")}
        return {k: v for k, v in d.items() if v is not None}

    def table(self, problem, unit: float = 1e-3, unit_name: str = "mm") -> pd.DataFrame:
        """One row per source: chosen process, tolerance in a display unit and its cost.

        Parameters
        ----------
        problem : ProcessProblem
            The problem the result belongs to.
        unit : float
            Display unit in SI (default 1e-3: tolerances shown in mm).
        unit_name : str
            Name of the display unit, used in the column header.

        Returns
        -------
        pandas.DataFrame
            Columns ``source``, ``process``, ``tolerance (<unit_name>)`` and ``cost`` (set-up +
            process cost, cost units).

        Raises
        ------
        ValidationError
            If a process name of the result is unknown to ``problem``.
        """
        ch = problem.choice_index(self.processes)
        t = np.array([self.tolerances[n] for n in problem.names])
        return pd.DataFrame({"source": problem.names, "process": [self.processes[n] for n in problem.names],
                             f"tolerance ({unit_name})": t / unit,
                             "cost": [float(problem.processes[n][k].total(t[j])) for j, (n, k) in enumerate(zip(problem.names, ch))]})


def _result(pp, method: str, choice, t, t0: float, **kw) -> ProcessResult:
    t = np.asarray(t, dtype=float)
    ne = float(pp.normalised_error(t)[0])
    ok = bool(ne <= 1 + FEAS_TOL and pp.in_ranges(choice, t)[0])
    return ProcessResult(method, pp.choice_names(choice), dict(zip(pp.names, t.tolist())), float(pp.cost(choice, t)[0]),
                         ok, ne, seconds=time.perf_counter() - t0, **kw)
