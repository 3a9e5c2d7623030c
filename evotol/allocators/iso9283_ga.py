"""The genetic algorithm on systematic and random sources together under ISO 9283 AP and RP (issue 44 item 3,
docs/iso9283.md).

A design is ``x = log (t, τ)``: the free systematic tolerances ``t`` and the random sources' ``τ``. pymoo's GA
(tournament, SBX, polynomial mutation in log space; pymoo's feasibility-first comparison) minimises
``Σ_i c_i(t_i) + Σ_k c_k(τ_k)`` subject to the constraints of :func:`evotol.allocators.iso9283.allocate_iso9283`,
evaluated for the whole population at once:

* AP, as its proven bound: ``max_d h(u_d; t, τ) / cos δ ≤ AP`` on the same 600-direction grid. ``h`` is linear
  in ``(t, τ)`` for each direction, so the grid values of a population are one product with the matrix
  ``[|D J|, D J C + |D J| H]`` per pose;
* RP: ``E l + 3 std l`` on the same fixed draws, ``≤ RP (1 − RP_MARGIN)``.

Every design is first moved onto the boundary of the requirement (AP is positively homogeneous of degree 1 in
``(t, τ)`` and non-decreasing in each tolerance, RP in ``τ``: ``t ← r_AP t``, ``τ ← min(r_AP, r_RP) τ`` meets
both where no bound clips; a few such steps). The best design is judged by :func:`iso_check`, the evaluation of
the optimum, and called feasible only if that holds. Orientation figures are not handled (refused).

Parameters
----------
terms : dict
    :func:`evotol.allocators.iso9283.iso_terms` (the functions below add cached matrices to it).
T : (n, m + K) ndarray
    Designs: systematic then random tolerances (SI).
"""
from __future__ import annotations

import numpy as np
from pymoo.algorithms.soo.nonconvex.ga import GA
from pymoo.core.problem import Problem
from pymoo.core.repair import Repair
from pymoo.optimize import minimize
from scipy.stats import qmc

from evotol._runtime.blas_threads import single_threaded_blas
from evotol.allocators.iso9283 import iso_check, iso_terms
from evotol.errors import ValidationError
from evotol.measures.linear.directions import directions_for


def population_figures(terms: dict, T: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The proven AP bound and the fixed-draw RP of many designs, per pose.

    Returns
    -------
    ap_bound, rp : (n, p) ndarray
        Grid maximum of ``h_K`` / cos δ, and ``E l + 3 std l`` (m).
    """
    L, m = _grid_maps(terms), terms["m"]
    ap = (L.reshape(-1, L.shape[2]) @ T.T).reshape(L.shape[0], L.shape[1], -1).max(1).T / np.cos(terms["delta"])
    if "draws_by_axis" not in terms:        # (p, 3, n, K): one BLAS product per pose below
        terms["draws_by_axis"] = np.ascontiguousarray(terms["E"].transpose(0, 2, 1, 3))
    Et = terms["draws_by_axis"]
    p, _, n, K = Et.shape
    rp = np.empty((len(T), p))
    for i in range(p):
        X = (Et[i].reshape(-1, K) @ T[:, m:].T).reshape(3, n, -1)
        l = np.sqrt(X[0] ** 2 + X[1] ** 2 + X[2] ** 2)                # (n, designs)
        mean = l.mean(0)
        rp[:, i] = mean + 3 * np.sqrt(np.maximum((l * l).sum(0) - n * mean ** 2, 0) / (n - 1))
    return ap, rp


def _grid_maps(terms):
    if "grid_maps" not in terms:            # [|D J|, D J C + |D J| H] per pose: h on the grid is L @ (t, τ)
        D = directions_for(terms["J"], 600, full_sphere=True)[0]
        A = np.einsum("dk,pkm->pdm", D, terms["J"])
        terms["grid_maps"] = np.concatenate([np.abs(A), A @ terms["C"] + np.abs(A) @ terms["H"]], axis=2)
    return terms["grid_maps"]


def _violation(terms, ap, rp):
    """Normalised violation per design (0: both hold)."""
    v = np.zeros(len(ap))
    if terms["AP"] is not None:
        v += np.maximum(ap.max(1) / terms["AP"] - 1, 0)
    if terms["RP"] is not None and terms["K"]:
        v += np.maximum(rp.max(1) / terms["rp_aim"] - 1, 0)
    return v


def scale_to_boundary(terms: dict, T: np.ndarray, iters: int = 3) -> np.ndarray:
    """``t ← r_AP t``, ``τ ← min(r_AP, r_RP) τ`` clipped to the bounds, a few steps (module docstring).

    Parameters
    ----------
    iters : int
        Steps.

    Returns
    -------
    (n, m + K) ndarray
        Designs on (or, where bounds clip, inside or still outside) the boundary of AP and RP (SI).
    """
    lo, hi, var, m = terms["lo"], terms["hi"], terms["var"], terms["m"]
    T = T.copy()
    for _ in range(iters):
        ap, rp = population_figures(terms, T)
        r_ap = np.ones(len(T)) if terms["AP"] is None else terms["AP"] * (1 - 1e-9) / ap.max(1)
        r_rp = r_ap if terms["RP"] is None or not terms["K"] else np.minimum(r_ap, terms["rp_aim"] / rp.max(1))
        S = np.concatenate([np.repeat(r_ap[:, None], m, 1), np.repeat(r_rp[:, None], terms["K"], 1)], axis=1)
        T = np.where(var, np.clip(T * S, lo, hi), lo)
    return T


class LogDesignProblem(Problem):
    """pymoo's problem over ``x = log (t, τ)`` of the free tolerances (module docstring): least cost, one constraint
    (AP and RP's normalised violation); :mod:`evotol.allocators.iso9283_front` changes the objectives.

    Parameters
    ----------
    terms, costs
        As :func:`population_figures` and :func:`design_cost`.
    n_obj, n_ieq_constr : int
        Objectives and inequality constraints.
    """

    def __init__(self, terms, costs, n_obj: int = 1, n_ieq_constr: int = 1):
        v = terms["var"]
        super().__init__(n_var=int(v.sum()), n_obj=n_obj, n_ieq_constr=n_ieq_constr, xl=np.log(terms["lo"][v]),
                         xu=np.log(terms["hi"][v]))
        self.terms, self.costs = terms, costs

    def full(self, X):
        """Designs from decision vectors: the free columns ``exp(X)``, the others at their lower bounds.

        Parameters
        ----------
        X : (n, n_var) ndarray
            Log tolerances of the free columns.

        Returns
        -------
        (n, m + K) ndarray
            Systematic then random tolerances (SI).
        """
        T = np.repeat(self.terms["lo"][None], len(X), 0)
        T[:, self.terms["var"]] = np.exp(X)
        return T

    def _evaluate(self, X, out, *args, **kwargs):
        T = self.full(X)
        out["F"] = design_cost(self.costs, T)[:, None]
        out["G"] = _violation(self.terms, *population_figures(self.terms, T))[:, None]


class _OntoBoundary(Repair):
    def _do(self, problem, X, **kwargs):
        return np.log(scale_to_boundary(problem.terms, problem.full(X))[:, problem.terms["var"]])


def design_cost(costs, T) -> np.ndarray:
    """``Σ c_j(t_j)`` of each design (cost models' unit); a column without a cost model is not priced.

    Parameters
    ----------
    costs : list of evotol.cost_models.base.CostModel or None
        Per column (systematic then random).

    Returns
    -------
    (n,) ndarray
    """
    return sum((np.asarray(cm.cost(T[:, j]), float) for j, cm in enumerate(costs) if cm is not None), np.zeros(len(T)))


def run_ga(prob, pop_size: int, n_gen: int, seed: int, repair=None) -> tuple[np.ndarray, int]:
    """pymoo's GA from a Latin hypercube of ``pop_size`` designs (seeded), feasibility first: its best design.

    Parameters
    ----------
    prob : pymoo.core.problem.Problem
        One objective, one inequality constraint (``G <= 0``), bounds ``xl``, ``xu``.
    pop_size, n_gen, seed : int
        Population, generations, and the seed of the start and of the GA.
    repair : pymoo.core.repair.Repair or None
        Applied to every offspring.

    Returns
    -------
    tuple
        ``(X (n_var,) ndarray, evaluations)``: the best feasible design, else the least violating of the last
        population.
    """
    X0 = qmc.scale(qmc.LatinHypercube(d=prob.n_var, seed=seed).random(int(pop_size)), prob.xl, prob.xu)
    algorithm = GA(pop_size=int(pop_size), sampling=X0, eliminate_duplicates=True,
                   **({"repair": repair} if repair is not None else {}))
    res = minimize(prob, algorithm, ("n_gen", int(n_gen)), seed=seed, verbose=False)
    X = res.X if res.X is not None else res.pop.get("X")[np.argmin(res.pop.get("G")[:, 0])]
    return np.atleast_2d(X)[0], int(res.algorithm.evaluator.n_eval)


@single_threaded_blas
def allocate_iso9283_ga(robot, positions, sys_costs, sys_bounds, free, sources, rand_costs, rand_bounds, AP, RP, *,
                        pop_size: int = 40, n_gen: int = 40, seed: int = 0, n_samples: int = 10000,
                        draw_seed: int | None = None) -> dict:
    """The GA's least-cost tolerances meeting AP (proven bound) and RP at every pose (module docstring).

    Parameters
    ----------
    robot, positions, sys_costs, sys_bounds, free, sources, rand_costs, rand_bounds, AP, RP, n_samples
        As :func:`evotol.allocators.iso9283.allocate_iso9283` (SI; RP draws).
    pop_size, n_gen : int
        Population and generations (at least 4 and 1).
    seed : int
        Seed of the GA and its initial Latin hypercube.
    draw_seed : int or None
        Seed of the RP draws (the optimum's with the same seed); None: ``seed``.

    Returns
    -------
    dict
        ``systematic`` (m,), ``random`` (K,) tolerances (SI), ``cost``, ``AP`` and ``AP_bound`` (p,),
        ``RP``, ``RP_fresh`` (p,), all m, ``feasible`` (:func:`evotol.allocators.iso9283.iso_check`),
        ``evaluations``.

    Raises
    ------
    evotol.errors.ValidationError
        ``pop_size`` < 4 or ``n_gen`` < 1, and as :func:`evotol.allocators.iso9283.iso_terms`.
    """
    if int(pop_size) < 4 or int(n_gen) < 1:
        raise ValidationError("ga (iso9283)", {"pop_size": pop_size, "n_gen": n_gen}, "pop_size >= 4 and n_gen >= 1")
    terms = iso_terms(robot, positions, sys_bounds, free, sources, rand_bounds, AP, RP, None, n_samples,
                      seed if draw_seed is None else draw_seed)
    costs = list(sys_costs) + list(rand_costs)
    prob = LogDesignProblem(terms, costs)
    X, n_eval = run_ga(prob, pop_size, n_gen, seed, repair=_OntoBoundary())
    t = prob.full(X[None])[0]
    chk = iso_check(terms, t)
    return {"systematic": t[:terms["m"]], "random": t[terms["m"]:], "cost": float(design_cost(costs, t[None])[0]),
            "AP": chk["ap"][:, 0], "AP_bound": chk["ap"][:, 1], "RP": chk["RP"], "RP_fresh": chk["RP_fresh"],
            "feasible": chk["feasible"], "evaluations": n_eval}
