"""The textbook route to process selection: the cheapest processes that can hold the requirement,
then the sensitivity rule or the Lagrange closed form on that choice."""
from __future__ import annotations

import time

import numpy as np

from evotol.allocators.baselines import allocate_lagrange
from evotol.allocators.process.problem import FEAS_TOL, ProcessProblem, ProcessResult, _result
from evotol.allocators.sensitivity import allocate_sensitivity
from evotol.constraints import ConstraintRows
from evotol.errors import ValidationError
from evotol.threads import single_threaded_blas


def cheapest_feasible_processes(pp: ProcessProblem, rows: ConstraintRows | None = None) -> np.ndarray:
    """Per source the cheapest process (lowest cost at its loosest tolerance); while even the
    tightest tolerances of that choice cannot hold the requirement, move the source with the
    largest tightest-tolerance effect to its next finer process (smaller lower limit)."""
    rows = rows or ConstraintRows(pp.base)
    S = pp.n_sources
    choice = np.array([int(np.argmin([float(p.total(p.upper)) for p in pp.processes[n]])) for n in pp.names])
    sens = np.max(np.concatenate([rows.A, np.sqrt(rows.B)], axis=0), axis=0) if rows.n_rows else np.ones(S)
    for _ in range(int(pp.n_processes.sum())):
        t = pp.lo[np.arange(S), choice]
        if rows.violation(t[None])[0] <= FEAS_TOL:
            return choice
        order = np.argsort(-sens * t)
        for j in order:
            finer = [k for k, p in enumerate(pp.processes[pp.names[j]]) if p.lower < t[j]]
            if finer:
                # the cheapest (at its own loosest tolerance) of the processes that go finer
                choice[j] = min(finer, key=lambda k: float(pp.processes[pp.names[j]][k].total(pp.processes[pp.names[j]][k].upper)))
                break
        else:
            break
    raise ValidationError("processes", pp.describe(), "processes fine enough to hold the requirement")


@single_threaded_blas
def allocate_process_baselines(pp: ProcessProblem) -> dict[str, ProcessResult]:
    """Sensitivity rule and Lagrange closed form on the cheapest feasible processes.

    Parameters
    ----------
    pp : ProcessProblem
        Process and tolerance per source (tolerances in SI: m or rad).

    Returns
    -------
    dict[str, ProcessResult]
        ``"sensitivity"`` and ``"lagrange"``: each rule's tolerances (SI) on the cheapest process
        of every source that can hold the requirement, with their cost (cost models' unit).

    Raises
    ------
    evotol.errors.ValidationError
        No process combination fine enough to hold the requirement.
    """
    out = {}
    t0 = time.perf_counter()
    choice = cheapest_feasible_processes(pp)
    sub = pp.subproblem(choice)
    for key, fn in (("sensitivity", allocate_sensitivity), ("lagrange", allocate_lagrange)):
        t1 = time.perf_counter()
        r = fn(sub)
        res = _result(pp, f"{r.method} on the cheapest feasible processes", choice, r.t, t1)
        res.seconds += t1 - t0
        out[key] = res
    return out
