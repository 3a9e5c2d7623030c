"""Single-objective genetic algorithm on pymoo with the penalty fitness of Yao et al. 2013 (eq. 15).

Fitness (eq. 15)::

    f(t) = Σ c_j(t_j)            if the accuracy requirement holds,
    f(t) = Σ c_j(t_j) + k        otherwise (k: a large constant, default 10× the
                                 cost of the tightest design).

Two operator sets:

* ``operators="pymoo"`` (default): binary tournament, SBX crossover, polynomial mutation,
  (μ+λ) fitness survival – pymoo's well-tested defaults;
* ``operators="paper"``: roulette-wheel selection (probability ∝ 1/f), elitism (the ``n_elite``
  best parents pass unchanged, the rest of the generation are offspring), crossover
  g = λ g1 + (1 − λ) g2 with λ ~ U(0, 1) (as printed in Sec. 4, step 5, under the name Wright's
  heuristic crossover), and uniform mutation (a gene is redrawn uniformly inside its bounds:
  the printed rule, "a random number in [a, b] is added", would push genes out of bounds).

``repair=True`` (default) scales every design onto the boundary of the requirement (the error is
positively homogeneous in t, so t ← t / (error/bound) is exact when no bound clips), which turns
the penalty search into a search along the feasible boundary; ``repair=False`` is the paper's GA.

The whole population is evaluated in one vectorised call. Worst-case rows are generated lazily
(:mod:`evotol.measures.constraints`): each generation the best designs are checked exactly and any missed
row is added; the returned design is judged by the exact evaluation.
Runs are reproducible from ``seed``; Ctrl-C stops the run and returns the best design so far.
"""
from __future__ import annotations

import json
import time
from pathlib import Path

import numpy as np
import pandas as pd
from pymoo.algorithms.soo.nonconvex.ga import GA, FitnessSurvival
from pymoo.core.crossover import Crossover
from pymoo.core.mutation import Mutation
from pymoo.core.problem import Problem
from pymoo.core.repair import Repair
from pymoo.core.selection import Selection
from pymoo.core.survival import Survival
from pymoo.operators.crossover.sbx import SBX
from pymoo.operators.mutation.pm import PM
from pymoo.operators.selection.tournament import TournamentSelection, compare
from pymoo.termination import get_termination
from scipy.stats import qmc

from evotol._runtime.atomic_files import write_text
from evotol.allocators.budget import check_budget, cheapest_design
from evotol.measures.constraints import ConstraintRows, ExactRows, constraint_rows
from evotol.errors import ValidationError
from evotol.core.problem import ToleranceProblem
from evotol._runtime.progress import progress_bar
from evotol.core.quality_loss import has_quality_loss
from evotol.core.plausibility import issue
from evotol.measures import feasibility
from evotol.core.result import AllocationResult, make_result
from evotol._runtime.blas_threads import single_threaded_blas
from evotol._runtime.random_state import seed_from


# --- the paper's operators --------------------------------------------------------------------------
class RouletteSelection(Selection):
    """Roulette-wheel selection for minimisation: probability ∝ 1/f (f > 0).

    Parameters
    ----------
    **kwargs
        Passed to pymoo's ``Selection``.
    """

    def _do(self, problem, pop, n_select, n_parents, random_state=None, **kwargs):
        rng = random_state if random_state is not None else np.random.default_rng()
        F = pop.get("F")[:, 0]
        w = 1.0 / np.maximum(F - min(F.min(), 0.0) + 1e-12, 1e-12)
        return rng.choice(len(pop), size=(n_select, n_parents), p=w / w.sum())


class BlendCrossover(Crossover):
    """g = λ g1 + (1 − λ) g2 and its mirror, λ ~ U(0, 1) per mating (Yao 2013 Sec. 4 step 5).

    Parameters
    ----------
    prob : float
        Probability that a mating is crossed over (else the parents are copied).
    **kwargs
        Passed to pymoo's ``Crossover``.
    """

    def __init__(self, prob: float = 0.9, **kwargs):
        super().__init__(2, 2, prob=prob, **kwargs)

    def _do(self, problem, X, random_state=None, **kwargs):
        rng = random_state if random_state is not None else np.random.default_rng()
        lam = rng.random((X.shape[1], 1))
        return np.stack([lam * X[0] + (1 - lam) * X[1], (1 - lam) * X[0] + lam * X[1]])


class UniformMutation(Mutation):
    """Each gene is redrawn uniformly inside its bounds with probability ``prob_var``.

    Parameters
    ----------
    prob_var : float or None
        Per-gene mutation probability; None: 1 / n_var.
    **kwargs
        Passed to pymoo's ``Mutation``.
    """

    def __init__(self, prob_var: float | None = None, **kwargs):
        super().__init__(prob=1.0, **kwargs)
        self.p_var = prob_var

    def _do(self, problem, X, random_state=None, **kwargs):
        rng = random_state if random_state is not None else np.random.default_rng()
        p = self.p_var if self.p_var is not None else 1.0 / problem.n_var
        mask = rng.random(X.shape) < p
        new = problem.xl + rng.random(X.shape) * (problem.xu - problem.xl)
        return np.where(mask, new, X)


class EliteSurvival(Survival):
    """The ``n_elite`` best parents survive unchanged; the offspring fill the rest (generational).

    Parameters
    ----------
    n_elite : int
        Number of best parents kept.
    """

    def __init__(self, n_elite: int = 2):
        super().__init__(filter_infeasible=False)
        self.n_elite = int(n_elite)

    def _do(self, problem, pop, n_survive=None, algorithm=None, **kwargs):
        n_off = len(algorithm.off) if algorithm is not None and algorithm.off is not None else 0
        if n_off == 0 or n_off >= len(pop):
            S = np.argsort(pop.get("F")[:, 0])
            return pop[S[:n_survive]]
        parents, offspring = pop[:len(pop) - n_off], pop[len(pop) - n_off:]
        elite = np.argsort(parents.get("F")[:, 0])[:self.n_elite]
        rest = np.argsort(offspring.get("F")[:, 0])[:n_survive - len(elite)]
        from pymoo.core.population import Population
        return Population.merge(parents[elite], offspring[rest])


# --- pymoo problem and repair ---------------------------------------------------------------------
class _BoundaryRepair(Repair):
    def __init__(self, rows: ConstraintRows):
        super().__init__()
        self.rows = rows

    def _do(self, problem, X, **kwargs):
        P = self.rows.problem
        T = P.full(X)
        if has_quality_loss(P):   # cost + loss is not monotone: pull in infeasible designs only
            out = self.rows.normalised_error(T) > 1
            if out.any():
                T[out] = boundary_scale(self.rows, T[out])
        else:
            T = boundary_scale(self.rows, T)
        return T[:, P.free]


def boundary_scale(rows: ConstraintRows, T: np.ndarray, iters: int = 20) -> np.ndarray:
    """t ← clip(t / error) on the free tolerances, a few fixed-point steps (exact without clipping).

    Designs still outside afterwards (locked sources, clipping) are shrunk by bisection
    (:meth:`ConstraintRows.scale_to_boundary`); with :class:`ExactRows`,
    :meth:`ExactRows.boundary_scale` does the work.

    Parameters
    ----------
    rows : ConstraintRows or ExactRows
        The requirement's rows (the error is judged on them).
    T : numpy.ndarray, (n, n_sources)
        Designs (m or rad).
    iters : int
        Fixed-point steps at most (ignored with :class:`ExactRows`).

    Returns
    -------
    numpy.ndarray
        (n, n_sources) designs (m or rad) scaled onto the boundary of the requirement as the
        rows judge it (normalised error 1 where no bound clips), clipped to the bounds.
    """
    if isinstance(rows, ExactRows):     # no rows: a few exact evaluations of the engine
        return rows.boundary_scale(T)
    P = rows.problem
    f = P.free
    T = T.copy()
    active = np.arange(T.shape[0])
    for _ in range(iters):
        ne = rows.normalised_error(T[active])
        Tn = P.full(np.clip(T[active][:, f] / ne[:, None], P.lower[f], P.upper[f]))
        moved = np.any(np.abs(Tn - T[active]) > 1e-12 * np.abs(T[active]), axis=1) & (np.abs(ne - 1) > 1e-12)
        T[active] = Tn
        active = active[moved]
        if active.size == 0:
            break
    ne = rows.normalised_error(T)
    over = ne > 1 + 1e-10   # round-off of t/ne is not a violation
    if over.any():  # locked sources / clipping: shrink by bisection on those left outside
        T[over] = rows.scale_to_boundary(T[over], iters=30)
    return T


class _GAProblem(Problem):
    def __init__(self, tp: ToleranceProblem, rows: ConstraintRows | None, penalty: float, budget: float | None,
                 n_check: int):
        f = tp.free
        super().__init__(n_var=int(f.sum()), n_obj=1, xl=tp.lower[f], xu=tp.upper[f])
        self.tp, self.rows, self.penalty, self.budget, self.n_check = tp, rows, penalty, budget, n_check
        self.best = None  # (fitness, design, exact violation)

    def _violation(self, T):
        if self.rows is not None:
            return self.rows.violation(T)
        return self.tp.evaluate(T).violation

    def _evaluate(self, X, out, *args, **kwargs):
        T = self.tp.full(X)
        cost = self.tp.cost(T)
        viol = self._violation(T)
        if self.budget is None:
            fit = cost + self.penalty * (viol > 1e-9)
            order = np.argsort(fit)[: self.n_check]
            if self.rows is not None and self.rows.measure == "worst_case":
                exact, added = self.rows.check(T[order])
                if added:
                    viol = self.rows.violation(T)
                    fit = cost + self.penalty * (viol > 1e-9)
                ok = order[exact <= 1e-9]
            else:
                ok = order[viol[order] <= 1e-9]
            if ok.size:
                i = ok[np.argmin(cost[ok])]
                if self.best is None or cost[i] < self.best[0]:
                    self.best = (float(cost[i]), T[i].copy())
        else:
            err = viol + 1
            fit = err + self.penalty * (cost > self.budget)
            ok = np.flatnonzero(cost <= self.budget)
            if ok.size:
                i = ok[np.argmin(err[ok])]
                if self.best is None or err[i] < self.best[0]:
                    self.best = (float(err[i]), T[i].copy())
        out["F"] = fit[:, None]


def initial_population(tp: ToleranceProblem, pop_size: int, seed: int, seeds=(), log_scale: bool = False) -> np.ndarray:
    """Latin hypercube over the bounds (scipy.stats.qmc), with the given seed designs first.
    With ``log_scale`` the hypercube and the returned variables are log(t).

    Parameters
    ----------
    tp : ToleranceProblem
        The problem (bounds of the free variables).
    pop_size : int
        Number of designs.
    seed : int
        Seed of the Latin hypercube.
    seeds : sequence of mapping or array_like
        Designs (m or rad; anything ``tp.as_array`` takes) placed first, clipped to the bounds;
        at most ``pop_size`` are used.
    log_scale : bool
        Whether the variables are log(t).

    Returns
    -------
    numpy.ndarray
        (pop_size, n_free) free variables: t (m or rad) or log(t).
    """
    f = tp.free
    lo, hi = (np.log(tp.lower[f]), np.log(tp.upper[f])) if log_scale else (tp.lower[f], tp.upper[f])
    X = qmc.scale(qmc.LatinHypercube(d=int(f.sum()), seed=seed).random(pop_size), lo, hi)
    S = [tp.as_array(s)[f] for s in seeds]
    for i, s in enumerate(S[:pop_size]):
        s = np.clip(s, tp.lower[f], tp.upper[f])
        X[i] = np.log(s) if log_scale else s
    return X


@single_threaded_blas
def check_ga_options(*, operators: str = "pymoo", pop_size: int = 100, n_gen: int = 200, seed: int = 0) -> None:
    """The GA's settings checked before any work (also by :mod:`evotol.allocators.preflight`).

    Parameters
    ----------
    operators : str
        ``"pymoo"`` or ``"paper"``.
    pop_size, n_gen, seed : int
        Population size (>= 4), generations (>= 1), seed (>= 0).

    Raises
    ------
    evotol.errors.ValidationError
        An unknown ``operators`` or a count out of range.
    """
    if operators not in ("pymoo", "paper"):
        raise ValidationError("operators", operators, "'pymoo' or 'paper'")
    for name, v, lo in (("pop_size", pop_size, 4), ("n_gen", n_gen, 1), ("seed", seed, 0)):
        if not isinstance(v, (int, np.integer)) or v < lo:
            raise ValidationError(name, v, f"an integer >= {lo}")


def allocate_ga(problem: ToleranceProblem, *, pop_size: int = 100, n_gen: int = 200, seed: int = 0, rng: int | np.random.Generator | None = None,
                operators: str = "pymoo", repair: bool | None = None, penalty: float | None = None,
                seeds=None, seed_with_baselines: bool = True, budget: float | None = None,
                n_elite: int = 2, n_check: int = 1, progress: bool | None = None,
                checkpoint: str | Path | None = None, checkpoint_every: int = 20, refine: bool | dict = False) -> AllocationResult:
    """GA allocation: least cost under the requirement (Yao et al. 2013 eq. 15; module docstring).

    Parameters
    ----------
    problem : evotol.core.problem.ToleranceProblem
        The problem (tolerances in SI: m or rad).
    pop_size, n_gen : int
        Population size (>= 4) and number of generations (>= 1).
    seed : int
        Seed of the run (>= 0); the run is reproducible from it.
    rng : int, numpy.random.Generator or None, optional
        As SciPy's ``rng``: an integer seed, or a Generator drawn from once for the seed of the run
        (recorded in the result); replaces ``seed`` (which keeps working, and also takes a Generator).
    operators : {"pymoo", "paper"}
        pymoo's tournament/SBX/polynomial mutation, or the paper's roulette/elitism/Wright
        crossover/uniform mutation.
    repair : bool or None
        Scale every design onto the boundary of the requirement (default: with ``"pymoo"``
        operators, no budget and a worst-case or RSS measure); ``False`` is the paper's GA.
    penalty : float or None
        Constant k of eq. 15 added to an infeasible design's fitness, in the cost models' unit
        (default: 10× the cost of the tightest design; 10 in budget mode, on the normalised error).
    seeds : sequence of mapping or array, or None
        Designs (SI) placed in the initial population; by default the sensitivity, Lagrange and
        equal-tolerance baselines (``seed_with_baselines``).
    seed_with_baselines : bool
        Whether the default seeds are used.
    budget : float or None
        If given (cost models' unit), minimise the (normalised) error subject to cost <= budget
        instead.
    n_elite : int
        Parents passed unchanged per generation (``"paper"`` operators).
    n_check : int
        Best designs checked exactly per generation (missed worst-case rows are added).
    progress : bool or None
        tqdm bar over generations (default: only on an interactive terminal).
    checkpoint : str or Path or None
        JSON file updated every ``checkpoint_every`` generations with the best design.
    checkpoint_every : int
        Generations between checkpoints.
    refine : bool or dict
        Final check over the whole workspace (``True`` or options of
        :func:`evotol.allocators.workspace_refinement.hold_on_workspace`): the best design is scaled until it holds at
        the worst poses found between and beyond the problem's poses; reported in
        ``result.info["refinement"]``.

    Returns
    -------
    evotol.core.result.AllocationResult
        The best design (tolerances in SI), its cost (cost models' unit), its errors (m, rad),
        the per-generation history and the feasibility repair applied (:mod:`evotol.measures.feasibility`).

    Raises
    ------
    evotol.errors.ValidationError
        An unknown ``operators``, a ``pop_size``/``n_gen``/``seed`` out of range, a budget below
        the cost of the cheapest design, or ``repair=True`` with the ``mc_quantile`` measure.
    evotol.errors.InfeasibleError
        Without a budget: even every free tolerance at its lower bound misses the requirement.

    Examples
    --------
    >>> from evotol.cost_models import PowerCost
    >>> from evotol import LinearStack, Tolerance, assembly_problem
    >>> stack = LinearStack({"x1": 1.0, "x2": -2.0, "x3": 0.5}, {"gap": 1e-4})  # gap = x1 - 2 x2 + x3 / 2
    >>> tol = {n: Tolerance(PowerCost(1.0, 1.0, scale=1e-3), lower=1e-7, upper=1e-4)
    ...        for n in stack.source_names}                                   # cost 1e-3 / t
    >>> problem = assembly_problem(stack, tol)                                # worst case <= 0.1 mm
    >>> from evotol import allocate_ga, allocate_optimum
    >>> ga = allocate_ga(problem, pop_size=20, n_gen=20, seed=0)
    >>> ga.feasible, ga.cost <= 1.01 * allocate_optimum(problem).cost
    (True, True)
    """
    t0 = time.perf_counter()
    seed = seed_from(rng, seed)
    check_ga_options(operators=operators, pop_size=pop_size, n_gen=n_gen, seed=seed)
    if refine and budget is None:
        from evotol.allocators.workspace_refinement import check_refinable
        check_refinable(problem)        # a calibrated problem: refused before the generations run
    if budget is not None:           # below the cheapest design: no answer (issue 15)
        budget = check_budget(problem, budget)
    measure = problem.requirement.measure
    if budget is None:
        problem.check_feasible()
    rows = constraint_rows(problem, seed=seed)
    if repair is None:
        repair = operators == "pymoo" and budget is None and rows is not None
    if repair and rows is None:
        raise ValidationError("repair", True, "the worst_case or rss measure (mc_quantile has no boundary scaling)")
    if penalty is None:
        penalty = 10.0 * float(problem.cost(problem.full(problem.lower[problem.free][None]))[0]) if budget is None else 10.0
    if seeds is None:
        seeds = []
        if seed_with_baselines and budget is None:
            from evotol.allocators.baselines import equal_design, lagrange_design
            from evotol.allocators.sensitivity import sensitivity_design
            for fn in (sensitivity_design, lagrange_design, lambda p: equal_design(p, rows)):
                try:
                    seeds.append(fn(problem))
                except Exception:  # a baseline that does not apply (e.g. all bounds) is just skipped
                    pass
        elif seed_with_baselines:        # budget mode: the cheapest design always fits the budget
            seeds.append(cheapest_design(problem))
    gp = _GAProblem(problem, rows, penalty, budget, n_check)
    X0 = initial_population(problem, pop_size, seed, seeds)
    if operators == "pymoo":
        algo = GA(pop_size=pop_size, sampling=X0, selection=TournamentSelection(func_comp=_binary_tournament),
                  crossover=SBX(prob=0.9, eta=15), mutation=PM(eta=20), survival=FitnessSurvival(),
                  repair=_BoundaryRepair(rows) if repair else None, eliminate_duplicates=True)
    else:
        algo = GA(pop_size=pop_size, sampling=X0, selection=RouletteSelection(), crossover=BlendCrossover(prob=0.9),
                  mutation=UniformMutation(), survival=EliteSurvival(n_elite),
                  repair=_BoundaryRepair(rows) if repair else None, eliminate_duplicates=False)
    algo.setup(gp, termination=get_termination("n_gen", n_gen), seed=seed, verbose=False)
    hist = []
    interrupted = False
    bar = progress_bar(n_gen, "GA", "gen", progress, size=f"{n_gen} generations × {pop_size} designs × {problem.n_poses} poses")
    try:
        while algo.has_next():
            algo.next()
            F = algo.pop.get("F")[:, 0]
            hist.append({"generation": algo.n_gen - 1, "best_fitness": float(F.min()), "mean_fitness": float(F.mean()),
                         "best_feasible": gp.best[0] if gp.best else np.nan, "evaluations": algo.evaluator.n_eval})
            bar.update(1)
            if gp.best:
                bar.set_postfix(best=f"{gp.best[0]:.5g}")
            if rows is not None and len(hist) % 20 == 0:
                rows.prune(problem.full(algo.pop.get("X")), keep_ratio=0.9)
            if checkpoint and len(hist) % checkpoint_every == 0:
                _write_checkpoint(checkpoint, problem, gp, hist)
    except KeyboardInterrupt:
        interrupted = True
    finally:
        bar.close()
    if checkpoint:
        _write_checkpoint(checkpoint, problem, gp, hist)
    if gp.best is None:
        best = problem.full(algo.pop.get("X")[np.argmin(algo.pop.get("F")[:, 0])][None])[0]
    else:
        best = gp.best[1]
    history = pd.DataFrame(hist)
    refinement = None
    if refine and budget is None:
        from evotol.allocators.workspace_refinement import hold_on_workspace

        best, refinement = hold_on_workspace(problem, best, **({} if refine is True else dict(refine)))
    name = "GA" if budget is None else "GA (best accuracy at budget)"
    ev, fix = None, {}
    if budget is None:      # the last generation's best, held to the one rule whatever its miss (a search method)
        best, ev, fix = feasibility.hold_to_rule(problem, best, max_miss=np.inf)
    return issue(make_result(problem, name, best, evaluation=ev, history=history, seconds=time.perf_counter() - t0,
                             budget=budget,
                             info={"operators": operators, "repair": bool(repair), "pop_size": pop_size, "n_gen": n_gen,
                                   "seed": seed, "penalty": penalty, "interrupted": interrupted,
                                   "initial_best": float(history["best_fitness"].iloc[0]) if len(history) else np.nan,
                                   **({"budget": budget} if budget is not None else {}),
                                   **({"refinement": refinement} if refinement else {}), **fix}))


def _binary_tournament(pop, P, random_state=None, **kwargs):
    F = pop.get("F")[:, 0]
    S = np.empty(P.shape[0], dtype=int)
    for i, (a, b) in enumerate(P):
        S[i] = compare(a, F[a], b, F[b], method="smaller_is_better", return_random_if_equal=True,
                       random_state=random_state)
    return S[:, None]


def _write_checkpoint(path, problem, gp, hist):
    data = {"generation": len(hist), "history": hist,
            "best": dict(zip(problem.names, gp.best[1].tolist())) if gp.best else None,
            "best_value": gp.best[0] if gp.best else None}
    write_text(path, json.dumps(data, indent=1, default=float))     # atomic: a kill keeps the last checkpoint
