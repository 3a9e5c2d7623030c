"""NSGA-II beyond the levels: the factors' continuous ranges searched by pymoo (issue "beyond the levels"),
run by evotol's one NSGA-II driver (:func:`evotol.allocators.nsga_driver.run_nsga2`).

The parameters several definitions of this module share are described once, here.

Parameters
----------
factors : sequence of Factor
    The design variables; their continuous ``[low, high]`` ranges (log-scaled where ``log``)
    are searched, levels are ignored.
evaluator : callable
    Picklable ``DataFrame -> DataFrame`` computing the objective columns (and optionally
    ``feasible`` and the ``constraint`` column) of a whole population, as for
    :func:`~evotol.design.evaluation.evaluate`.
objectives : sequence of Objective
    The objective columns and their senses.
constraint : str, optional
    Column of the evaluator output that must be <= 0 for a feasible entry.
scheduler : str, optional
    Address of a Dask scheduler (``"tcp://host:8786"``) to run the chunks on.
"""
from __future__ import annotations

import math
import time
from dataclasses import dataclass
from typing import Sequence

import numpy as np
import pandas as pd
from pymoo.core.problem import Problem

from evotol.design.evaluation import Evaluator, _evaluate_chunk, evaluate
from evotol.design.factors import FEASIBLE, SOURCE, Factor, _check_factors, from_unit
from evotol.allocators.nsga_driver import run_nsga2
from evotol.errors import EvotolError, ValidationError
from evotol.core.pareto import ParetoFront, knee_points, non_dominated


@dataclass(frozen=True)
class Objective:
    """An objective column and whether it is minimised (``sense=+1``) or maximised (``-1``).

    Parameters
    ----------
    column : str
        Name of the evaluator's output column (its unit is the one the name says).
    sense : int, default 1
        +1 to minimise, -1 to maximise.
    log : bool, default False
        Compare and normalise in log10 (values spanning decades), e.g. for the knee points.

    Raises
    ------
    ValidationError
        ``sense`` is not +1 or -1.
    """

    column: str
    sense: int = 1
    log: bool = False     # compare/normalise in log10 (values spanning decades)

    def __post_init__(self):
        if self.sense not in (1, -1):
            raise ValidationError(f"Objective({self.column!r}).sense", self.sense, "+1 (minimise) or -1 (maximise)")



class DesignProblem(Problem):
    """The factors in [0, 1] (:meth:`Factor.to_unit`) as a pymoo problem; one evaluator call per
    generation. Defined at module level so that it pickles (to worker processes and Dask).

    F: the objectives times their ``sense`` (pymoo minimises); G: <= 0 for a feasible entry
    (``feasible`` and, when given, the ``constraint`` column <= 0). ``seen`` keeps every
    evaluated entry (inputs + evaluator output): the archive the Pareto front is taken from.

    Parameters
    ----------
    workers : int, default 1
        Local processes; above 1 (or with ``scheduler``) a generation is split into one chunk
        per worker and run by :func:`~evotol.design.evaluation.evaluate`, else it runs in this
        process.
    """

    def __init__(self, factors: Sequence[Factor], evaluator: Evaluator, objectives: Sequence[Objective], *,
                 constraint: str | None = None, workers: int = 1, scheduler=None):
        super().__init__(n_var=len(factors), n_obj=len(objectives), n_ieq_constr=1, xl=0.0, xu=1.0)
        self.factors, self.evaluator, self.objectives = tuple(factors), evaluator, tuple(objectives)
        self.constraint, self.workers, self.scheduler = constraint, workers, scheduler
        self.seen: list[pd.DataFrame] = []

    def to_frame(self, U: np.ndarray) -> pd.DataFrame:
        """The entries of a population: unit coordinates mapped by :meth:`Factor.to_unit`.

        Parameters
        ----------
        U : (n, n_factors) ndarray
            Decision variables in [0, 1], one row per individual, one column per factor.

        Returns
        -------
        pandas.DataFrame
            ``n`` rows, one column per factor (column units).
        """
        return pd.DataFrame({f.name: f.to_unit(U[:, j]) for j, f in enumerate(self.factors)})

    def _evaluate(self, U, out, *args, **kwargs):
        X = self.to_frame(U)
        if self.workers > 1 or self.scheduler is not None:
            Y = evaluate(X, self.evaluator, workers=self.workers, scheduler=self.scheduler, progress=False,
                         chunk_size=max(1, math.ceil(len(X) / max(self.workers, 1))))
            Y = Y.drop(columns=list(X.columns))
        else:
            Y = _evaluate_chunk(self.evaluator, X)
        # a batch whose every entry failed brings no objective column back: its entries are
        # infeasible (ranked by G below), their objectives NaN
        wanted = [o.column for o in self.objectives] + ([self.constraint] if self.constraint is not None else [])
        Y = Y.assign(**{c: np.nan for c in wanted if c not in Y.columns})
        self.seen.append(pd.concat([X, Y], axis=1))
        F = np.column_stack([o.sense * Y[o.column].to_numpy(dtype=float) for o in self.objectives])
        bad = ~Y[FEASIBLE].to_numpy(bool)
        F[bad] = 0.0     # ranked by the constraint violation below, never by F
        G = np.where(bad, 1.0, -1.0)
        if self.constraint is not None:     # a failed entry keeps G = 1 (its constraint value is NaN)
            G = np.where(bad, 1.0, np.maximum(G, Y[self.constraint].to_numpy(dtype=float)))
        out["F"], out["G"] = F, G[:, None]


def nsga2(factors: Sequence[Factor], evaluator: Evaluator, objectives: Sequence[Objective], *,
          pop_size: int = 64, n_gen: int = 40, seed: int = 0, constraint: str | None = None,
          initial: pd.DataFrame | None = None, progress: bool = False, workers: int = 1,
          scheduler: str | None = None) -> ParetoFront:
    """NSGA-II (pymoo) on the factors' continuous ranges; returns the final Pareto entries.

    Decision variables are the factors in [0, 1] mapped by :meth:`Factor.to_unit` (log-uniform
    where ``log``: a tolerance from 1e-4 to 1e-1 mm is searched per decade, not per mm). Each
    generation's whole population is one evaluator call (``workers`` > 1 or ``scheduler``: split
    into one chunk per worker, run by :func:`evaluate`). ``constraint`` is a column of the
    evaluator output that must be <= 0 for a feasible entry (besides ``feasible``). ``initial``
    seeds the population with known entries (e.g. the best grid entries).

    Returns the :class:`evotol.core.pareto.ParetoFront` of the non-dominated feasible entries: its
    ``table`` has ``source = "NSGA-II"`` and a boolean ``knee`` column (:func:`knee_points`), sorted
    by the first objective; ``objectives`` are the study's (column, sense, log).

    Parameters
    ----------
    pop_size : int, default 64
        Population size.
    n_gen : int, default 40
        Number of generations.
    seed : int, default 0
        Seed of NSGA-II and of the random individuals that complete an ``initial`` population.
    initial : pandas.DataFrame, optional
        Known entries (one column per factor name, column units) seeding the population; the
        first ``pop_size`` are used (clipped to the ranges), random individuals fill the rest.
    progress : bool or None, default False
        The progress display over generations, as every NSGA-II run of evotol's
        (:func:`~evotol.allocators.nsga_driver.run_nsga2`): None a bar on a terminal only, True
        also periodic lines off a terminal, False nothing.
    workers : int, default 1
        Local processes; above 1 (or with ``scheduler``) each generation is split into one
        chunk per worker.

    Returns
    -------
    ParetoFront
        Its ``table``: the non-dominated feasible entries among every entry evaluated (inputs,
        evaluator output, ``source``, ``knee``), duplicates of the factor values dropped;
        ``table.attrs["evotol"]`` records the factors, ``design = "NSGA-II"``, ``pop_size``,
        ``n_gen``, ``seed`` and ``n_evaluations``; ``seconds`` is the wall time (s).

    Raises
    ------
    ValidationError
        ``factors`` is empty, holds a non-Factor or has duplicate or reserved names, or
        ``objectives`` is empty.
    EvotolError
        No evaluated entry is feasible.
    """
    t0 = time.perf_counter()
    factors = _check_factors(factors)
    objectives = tuple(objectives)
    if not objectives:
        raise ValidationError("objectives", objectives, "at least one Objective")
    problem = DesignProblem(factors, evaluator, objectives, constraint=constraint, workers=workers,
                            scheduler=scheduler)
    sampling = None
    if initial is not None and len(initial):
        U0 = np.column_stack([from_unit(f, initial[f.name].to_numpy(float)) for f in factors])
        rng = np.random.default_rng(seed)
        fill = rng.random((max(0, pop_size - len(U0)), len(factors)))
        sampling = np.vstack([U0[:pop_size], fill])
    run_nsga2(problem, pop_size=pop_size, n_gen=n_gen, seed=seed, sampling=sampling, progress=progress,
              size=f"{n_gen} generations × {pop_size} entries")
    seen = problem.seen
    allx = pd.concat(seen, ignore_index=True)
    ok = allx[allx[FEASIBLE]].reset_index(drop=True)
    if constraint is not None:
        ok = ok[ok[constraint] <= 0].reset_index(drop=True)
    if ok.empty:
        raise EvotolError("NSGA-II found no feasible entry")
    F = np.column_stack([o.sense * ok[o.column].to_numpy(float) for o in objectives])
    front = non_dominated(F)
    # every entry NSGA-II evaluated is a candidate: the archive's front is never worse than the
    # final population's
    pareto = ok.iloc[front].drop_duplicates(subset=[f.name for f in factors]).reset_index(drop=True)
    Fp = np.column_stack([o.sense * pareto[o.column].to_numpy(float) for o in objectives])
    knee = np.zeros(len(pareto), bool)
    knee[knee_points(Fp, [o.log for o in objectives])] = True
    pareto[SOURCE] = "NSGA-II"
    pareto["knee"] = knee
    pareto = pareto.sort_values(objectives[0].column, ascending=objectives[0].sense > 0).reset_index(drop=True)
    pareto.attrs["evotol"] = {"factors": [f.to_dict() for f in factors], "design": "NSGA-II",
                              "pop_size": pop_size, "n_gen": n_gen, "seed": seed,
                              "n_evaluations": int(len(allx))}
    return ParetoFront(pareto, time.perf_counter() - t0, objective=objectives[-1].column, limit=np.inf,
                       objectives=tuple((o.column, int(o.sense), bool(o.log)) for o in objectives))

