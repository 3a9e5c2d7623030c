"""The cost–accuracy trade-off under a repeatability requirement: an NSGA-II front of cost against ISO 9283 AP on
systematic and random sources together (issue 44 item 3, docs/iso9283.md).

A design is ``x = log (t, τ)``: the free systematic tolerances ``t`` and the random sources' ``τ``. pymoo's NSGA-II
(:func:`evotol.allocators.nsga_driver.run_nsga2`) minimises the two objectives

* cost ``Σ_i c_i(t_i) + Σ_k c_k(τ_k)`` (cost models' unit), and
* AP, its proven first-order worst-case bound ``max_poses max_d h(u_d; t, τ) / cos δ`` (m; the 600-direction grid of
  :func:`evotol.allocators.iso9283.allocate_iso9283`, δ its covering angle),

subject to RP ``E l + 3 std l ≤ RP (1 − RP_MARGIN)`` on the optimum's fixed draws at every pose. The whole
population is evaluated at once (:func:`evotol.allocators.iso9283_ga.population_figures`). RP is positively
homogeneous of degree 1 in ``τ``, so every design is first moved under the RP aim (``τ ← min(1, r_RP) τ``, clipped
to the bounds).

Every point of the final front is re-judged by :func:`evotol.allocators.iso9283.iso_check` (the optimum's check:
the attained worst case and its proven bound, RP on the fixed and on fresh draws) and kept only if its RP meets RP;
dominated points left after the re-judging are dropped, so the front kept is monotone (more cost, less AP).

**The exact frontier.** For a given AP level ``A`` the least cost with the proven bound ``≤ A`` and the same RP aim
is :func:`evotol.allocators.iso9283.allocate_iso9283` (AP convex in the tolerances: certified; RP sampled, as that
module says). It is solved at ``n_levels`` levels spanning the kept front's AP range (geometric), each warm-started
from the previous, and each point's gap is its cost over the frontier interpolated linearly in (log AP, log cost),
minus 1. The optimum aims its *attained* AP at ``A cos δ``, a front point only its bound at ``A``: a point may lie
below the frontier by that margin (at most about 0.4 % in AP), never by more.
"""
from __future__ import annotations

import numpy as np
from pymoo.core.repair import Repair
from scipy.stats import qmc

from evotol._runtime.blas_threads import single_threaded_blas
from evotol.allocators.iso9283 import allocate_iso9283, iso_check, iso_terms
from evotol.allocators.iso9283_ga import LogDesignProblem, design_cost, population_figures
from evotol.allocators.nsga_driver import run_nsga2
from evotol.errors import ValidationError


class _FrontProblem(LogDesignProblem):
    """Cost and the proven AP bound of a population (module docstring); one RP constraint."""

    def __init__(self, terms, costs):
        self.rp_constrained = terms["RP"] is not None and terms["K"] > 0
        super().__init__(terms, costs, n_obj=2, n_ieq_constr=int(self.rp_constrained))

    def _evaluate(self, X, out, *args, **kwargs):
        T = self.full(X)
        ap, rp = population_figures(self.terms, T)
        out["F"] = np.column_stack([design_cost(self.costs, T), ap.max(1)])
        if self.rp_constrained:
            out["G"] = (rp.max(1) / self.terms["rp_aim"] - 1)[:, None]


class _UnderRP(Repair):
    """``τ ← min(1, RP_aim / RP) τ`` (RP is homogeneous of degree 1 in τ), then the random sources that do not enter
    AP (no lost motion) raised towards the RP aim, ``τ_F ← s τ_F`` with ``s ← s RP_aim / RP`` (from below: ``RP/s``
    does not increase with ``s``, so the steps stay under the aim): cheaper at the same AP; clipped to the bounds."""

    def _do(self, problem, X, **kwargs):
        if not problem.rp_constrained:
            return X
        terms, m = problem.terms, problem.terms["m"]
        aim, lo, hi = terms["rp_aim"] * (1 - 1e-9), terms["lo"][m:], terms["hi"][m:]
        T = problem.full(X)
        r = np.minimum(1.0, aim / population_figures(terms, T)[1].max(1))
        T[:, m:] = np.clip(T[:, m:] * r[:, None], lo, hi)
        ap_free = ~(np.abs(terms["C"]).sum((0, 1)) + np.abs(terms["H"]).sum((0, 1)) > 0)      # (K,)
        for _ in range(3 if ap_free.any() else 0):
            s = np.maximum(1.0, aim / population_figures(terms, T)[1].max(1))
            T[:, m:][:, ap_free] = np.clip(T[:, m:][:, ap_free] * s[:, None], lo[ap_free], hi[ap_free])
        return np.log(T[:, terms["var"]])


def exact_frontier(robot, positions, sys_costs, sys_bounds, free, sources, rand_costs, rand_bounds, RP, levels, x0,
                   n_samples: int, seed: int) -> list[dict]:
    """The certified optimum (:func:`evotol.allocators.iso9283.allocate_iso9283`) at each AP level, warm-started.

    Parameters
    ----------
    robot, positions, sys_costs, sys_bounds, free, sources, rand_costs, rand_bounds, RP
        As :func:`evotol.allocators.iso9283.allocate_iso9283` (SI).
    levels : (L,) array_like
        AP levels (m), solved from the largest (cheapest) down, each from the previous solution.
    x0 : (m + K,) array_like
        Start of the first solve (SI).
    n_samples, seed : int
        The RP draws (the front's).

    Returns
    -------
    list of dict
        Per level, ascending: ``AP`` (the level, m), ``cost``, ``AP_bound`` and ``AP_attained`` (largest over the
        poses, m), ``RP`` (largest, m), ``feasible``, ``success``, ``tolerances`` (SI).
    """
    out, x = [], np.asarray(x0, float)
    for A in sorted(np.asarray(levels, float), reverse=True):
        al = allocate_iso9283(robot, positions, sys_costs, sys_bounds, free, sources, rand_costs, rand_bounds, float(A),
                              RP, x0=x, n_samples=n_samples, seed=seed)
        x = np.concatenate([al["systematic"], al["random"]])
        out.append({"AP": float(A), "cost": float(al["cost"]), "AP_bound": float(al["AP_bound"].max()),
                    "AP_attained": float(al["AP"].max()), "RP": float(al["RP"].max()), "feasible": bool(al["feasible"]),
                    "success": bool(al["success"]), "tolerances": x})
    return out[::-1]


def frontier_gap(cost, ap, frontier: list[dict]) -> np.ndarray:
    """``cost / F(AP) − 1`` with ``F`` the frontier interpolated linearly in (log AP, log cost) between its feasible
    levels (module docstring); NaN outside their range.

    Parameters
    ----------
    cost, ap : (n,) array_like
        Points' cost and proven AP bound (m).
    frontier : list of dict
        :func:`exact_frontier`.

    Returns
    -------
    (n,) ndarray
    """
    ok = [f for f in frontier if f["feasible"]]
    ap = np.asarray(ap, float)
    if not ok:
        return np.full(len(ap), np.nan)
    la, lc = np.log([f["AP"] for f in ok]), np.log([f["cost"] for f in ok])
    inside = (np.log(ap) >= la[0] - 1e-12) & (np.log(ap) <= la[-1] + 1e-12)
    F = np.exp(np.interp(np.log(ap), la, lc))
    return np.where(inside, np.asarray(cost, float) / F - 1, np.nan)


@single_threaded_blas
def allocate_iso9283_front(robot, positions, sys_costs, sys_bounds, free, sources, rand_costs, rand_bounds, AP, RP, *,
                           pop_size: int = 40, n_gen: int = 40, seed: int = 0, n_samples: int = 10000,
                           draw_seed: int | None = None, n_levels: int = 6) -> dict:
    """NSGA-II front of cost against the proven AP bound, every point holding RP, judged against the exact frontier
    (module docstring).

    Parameters
    ----------
    robot, positions, sys_costs, sys_bounds, free, sources, rand_costs, rand_bounds, RP, n_samples
        As :func:`evotol.allocators.iso9283.allocate_iso9283` (SI; RP draws).
    AP : float or None
        The AP requirement (m): not a constraint of the front, only stated beside it.
    pop_size, n_gen, draw_seed
        As :func:`evotol.allocators.iso9283_ga.allocate_iso9283_ga`.
    seed : int
        Seed of NSGA-II and its initial Latin hypercube.
    n_levels : int
        AP levels of the exact frontier (at least 2).

    Returns
    -------
    dict
        ``points`` (ascending cost): ``cost``, ``AP_bound`` and ``AP_attained`` (largest over the poses, m), ``RP`` and
        ``RP_fresh`` (largest, m), ``systematic`` (m,) and ``random`` (K,) tolerances (SI), ``gap`` (None outside the frontier's levels);
        ``exact_frontier`` (:func:`exact_frontier`), ``judged`` (front points re-judged), ``kept``,
        ``evaluations``.

    Raises
    ------
    evotol.errors.ValidationError
        ``pop_size`` < 4, ``n_gen`` < 1 or ``n_levels`` < 2, and as :func:`evotol.allocators.iso9283.iso_terms`.
    """
    if int(pop_size) < 4 or int(n_gen) < 1 or int(n_levels) < 2:
        raise ValidationError("nsga2 (iso9283)", {"pop_size": pop_size, "n_gen": n_gen, "n_levels": n_levels},
                              "pop_size >= 4, n_gen >= 1 and n_levels >= 2")
    draw_seed = seed if draw_seed is None else draw_seed
    terms = iso_terms(robot, positions, sys_bounds, free, sources, rand_bounds, AP, RP, None, n_samples, draw_seed)
    costs = list(sys_costs) + list(rand_costs)
    prob = _FrontProblem(terms, costs)
    X0 = qmc.scale(qmc.LatinHypercube(d=prob.n_var, seed=seed).random(int(pop_size)), prob.xl, prob.xu)
    algo = run_nsga2(prob, pop_size=int(pop_size), n_gen=int(n_gen), seed=seed, sampling=X0, repair=_UnderRP(), progress=None,
                     size=f"ISO front, {int(n_gen)} generations × {int(pop_size)} designs")     # a bar on a terminal
    X = algo.opt.get("X")
    if prob.rp_constrained:
        X = X[algo.opt.get("G")[:, 0] <= 0]
    judge = {**terms, "AP": None}               # the front states AP; only RP decides whether a point is kept
    points = []
    for t in prob.full(X):
        chk = iso_check(judge, t)
        if chk["feasible"]:
            points.append({"cost": float(design_cost(costs, t[None])[0]), "AP_bound": float(chk["ap"][:, 1].max()),
                           "AP_attained": float(chk["ap"][:, 0].max()), "RP": float(chk["RP"].max()),
                           "RP_fresh": float(chk["RP_fresh"].max()), "systematic": t[:terms["m"]], "random": t[terms["m"]:]})
    points.sort(key=lambda p: (p["cost"], p["AP_bound"]))
    kept = []
    for p in points:                            # monotone: each dearer point must have a smaller AP
        if not kept or p["AP_bound"] < kept[-1]["AP_bound"]:
            kept.append(p)
    frontier = []
    if kept:
        a = np.array([p["AP_bound"] for p in kept])
        levels = np.geomspace(a.min(), a.max(), int(n_levels)) if a.max() > a.min() else a[:1]
        frontier = exact_frontier(robot, positions, sys_costs, sys_bounds, free, sources, rand_costs, rand_bounds, RP,
                                  levels, np.concatenate([kept[0]["systematic"], kept[0]["random"]]), n_samples, draw_seed)
        for p, g in zip(kept, frontier_gap([p["cost"] for p in kept], a, frontier)):
            p["gap"] = None if np.isnan(g) else float(g)
    return {"points": kept, "exact_frontier": frontier, "judged": len(X), "kept": len(kept),
            "evaluations": int(algo.evaluator.n_eval)}
