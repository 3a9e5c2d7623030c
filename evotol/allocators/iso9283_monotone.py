"""A bracket of the least cost of systematic and random sources under ISO 9283 AP and RP by polyblocks (issue 44
item 3, docs/iso9283.md): the study's ``monotone`` beside ``[iso9283] allocate = true``, on the problem of
:func:`evotol.allocators.iso9283.allocate_iso9283`, so that the bracket stands beside the certified optimum.

The polyblock algorithm (Tuy 2000, :func:`evotol.allocators.monotone.polyblock_search`) runs in ``x = log (t, τ)``
over the variable systematic columns and the random sources. A design is feasible by the check the equal
tolerances search by (:func:`evotol.allocators.iso9283_baselines.within_requirement`): the proven AP bound (grid
maximum of ``h(u; t, τ)`` over 600 directions / cos δ) ``<= AP`` and ``E l + 3 std l`` on the optimum's fixed draws
``<=`` its aim (1.5 % below RP). The polyblock needs that check to be lost only when a tolerance grows:

* **AP**: for each grid direction ``h`` is ``[|D J|, D J C + |D J| H] @ (t, τ)``, linear with non-negative weights
  (measured on the UR5 case: the smallest weight is 0), so the bound, a maximum of such functions, never
  decreases when a tolerance grows: proven;
* **RP** on fixed draws: ``E l`` never decreases (convex and even in each ``τ_k``), but ``3 std l`` can: on the UR5
  case of ``tests/test_iso9283_monotone.py`` (random designs, one ``τ`` swept over its bounds at a time) the
  sampled RP fell up to 1.3–2.0 % below its value at a smaller ``τ`` (lost motions and encoder counts alike:
  ``E l`` grows, ``std l`` shrinks). RP is therefore **not** monotone. The cuts and the box reduction then
  remove only designs outside the normal set ``G*`` (designs every smaller design of which meets RP, i.e.
  RP's monotone envelope meets the aim), so the **lower bound is proven for the least cost over G***; a design
  that meets the sampled RP only where it dips below the envelope may cost less than it. The upper bound is the
  cost of a design that meets the check itself (feasible as every ISO allocator's design is judged).

The first vertex is the reduced upper corner (:func:`evotol.allocators.monotone.upper_reduction`). The search
stops at ``rel_gap``, at ``max_seconds``, at ``max_evaluations`` or before a cut proposing more than
:data:`MAX_NEW_VERTICES` new vertices (the polyblock without that cut still holds every feasible design, so the
lower bound stands). The incumbent (the first upper bound) is the cheapest the check accepts of the Lagrange closed form's and the
equal-effect rule's designs (:func:`evotol.allocators.iso9283_baselines.lagrange_tolerances`,
:func:`evotol.allocators.iso9283_sensitivity.equal_effect_shares`, scaled onto the boundary) and the equal
tolerances (:func:`evotol.allocators.iso9283_baselines.equal_tolerances`). The
bracket is a bracket: the design is called optimal only where ``gap <= rel_gap``.
"""
from __future__ import annotations

import numpy as np

from evotol.allocators.iso9283 import iso_terms
from evotol.allocators.iso9283_baselines import equal_tolerances, lagrange_tolerances, within_requirement
from evotol.allocators.iso9283_ga import design_cost
from evotol.allocators.iso9283_sensitivity import equal_effect_shares, rule_design
from evotol.allocators.monotone import MonotoneProblem, polyblock_search
from evotol.errors import ValidationError

#: the search stops before a cut proposing more new vertices (one cut's dominance check grows with their number
#: times the vertices kept; on the 54-variable example one cut of 1 947 vertices, 105 000 proposed, took 16 s)
MAX_NEW_VERTICES = 20000


def iso_monotone_problem(terms: dict, costs) -> tuple[MonotoneProblem, callable]:
    """The ISO allocation as a monotone problem in the log of its variable tolerances (module docstring).

    Parameters
    ----------
    terms : dict
        The problem whose bounds, check and cost are wrapped (:func:`evotol.allocators.iso9283.iso_terms`).
    costs : list of evotol.cost_models.base.CostModel or None
        Per column, systematic then random (None: never priced).

    Returns
    -------
    problem : evotol.allocators.monotone.MonotoneProblem
        Bounds, the check, the cost and the per-variable costs.
    design : callable
        ``design(X) -> (k, m + K)``: log variables to tolerances (SI), the other columns at their lower bounds.
    """
    var, lo, hi = terms["var"], terms["lo"], terms["hi"]
    idx = np.flatnonzero(var)

    def design(X):
        T = np.repeat(lo[None], len(X), 0)
        T[:, var] = np.exp(X)
        return T

    def var_costs(X):
        T = design(X)
        return np.stack([np.zeros(len(T)) if costs[j] is None else np.asarray(costs[j].cost(T[:, j]), float)
                         for j in idx], 1)

    return MonotoneProblem(np.log(lo[var]), np.log(hi[var]), feasible=lambda X: within_requirement(terms, design(X)),
                           cost=lambda X: design_cost(costs, design(np.atleast_2d(X))), var_costs=var_costs), design


def allocate_iso9283_monotone(robot, positions, sys_costs, sys_bounds, free, sources, rand_costs, rand_bounds, AP, RP,
                              *, n_samples: int = 10000, seed: int = 0, max_seconds: float = 10.0,
                              rel_gap: float = 1e-2, max_evaluations: int = 20000, batch: int = 16) -> dict:
    """The polyblock bracket of the least cost meeting AP (proven bound) and RP (module docstring).

    Parameters
    ----------
    robot, positions, sys_costs, sys_bounds, free, sources, rand_costs, rand_bounds, AP, RP, n_samples, seed
        As :func:`evotol.allocators.iso9283_baselines.allocate_iso9283_equal`.
    max_seconds : float
        Wall time of the polyblock search (s), checked once per round and after every cut.
    rel_gap : float
        As :func:`evotol.allocators.monotone.polyblock`.
    max_evaluations : int
        Stop after about this many designs checked (a budget that does not depend on the machine).
    batch : int
        Cheapest vertices projected per round (:func:`evotol.allocators.monotone.polyblock_search`).

    Returns
    -------
    dict
        As :func:`evotol.allocators.iso9283_sensitivity.rule_design` (``cost`` the bracket's upper bound), and
        ``lower_bound`` (cost units; proven for the normal set of the module docstring), ``gap`` (relative to
        ``cost``), ``rounds``, ``vertices``, ``evaluations``, ``converged`` (``gap <= rel_gap``), ``stop`` (what ended
        the search, :func:`evotol.allocators.monotone.polyblock_search`), ``incumbent``
        (the rule whose design started the upper bound, or None) and ``improved`` (whether the polyblock found a
        cheaper design than it).

    Raises
    ------
    evotol.errors.ValidationError
        ``max_seconds`` or ``rel_gap`` not positive, ``max_evaluations`` below 1; as
        :func:`evotol.allocators.iso9283.iso_terms`.
    """
    for field, value, ok in (("max_seconds", max_seconds, max_seconds > 0), ("rel_gap", rel_gap, rel_gap > 0),
                             ("max_evaluations", max_evaluations, max_evaluations >= 1), ("batch", batch, batch >= 1)):
        if not ok:
            raise ValidationError(f"monotone.{field}", value, "a positive number")
    terms = iso_terms(robot, positions, sys_bounds, free, sources, rand_bounds, AP, RP, None, n_samples, seed)
    costs = list(sys_costs) + list(rand_costs)
    mp, design = iso_monotone_problem(terms, costs)
    scaled = {k: rule_design(terms, costs, shares) for k, shares in
              (("lagrange", lagrange_tolerances(terms, costs)), ("sensitivity", equal_effect_shares(terms)))}
    starts = {**{k: np.concatenate([r["systematic"], r["random"]]) for k, r in scaled.items()},
              "equal": equal_tolerances(terms)}
    # the rules' designs sit on the boundary to rounding (scaled to AP (1 − 1e-9), the check's own limit): 1e-6 inside
    starts = {k: np.where(terms["var"], np.maximum(t * (1 - 1e-6), terms["lo"]), t) for k, t in starts.items()}
    held = {k: t for k, t in starts.items() if within_requirement(terms, t[None])[0]}
    incumbent = min(held, key=lambda k: design_cost(costs, held[k][None])[0], default=None)
    ub = np.inf if incumbent is None else float(design_cost(costs, held[incumbent][None])[0])
    res = polyblock_search(mp, upper_bound=ub, spent=len(starts), rel_gap=rel_gap, max_evaluations=max_evaluations,
                           batch=batch, max_seconds=max_seconds, max_new_vertices=MAX_NEW_VERTICES, reduce_upper=True)
    t = held.get(incumbent) if res["x"] is None else design(res["x"][None])[0]
    if t is None:                   # nothing found that holds: every tolerance at its lower bound, judged as it is
        t = terms["lo"].copy()
    out = rule_design(terms, costs, t, iters=0)
    return {**out, "lower_bound": res["lower_bound"], "gap": res["gap"], "rounds": res["rounds"],
            "vertices": res["vertices"], "evaluations": res["evaluations"], "converged": res["converged"], "stop": res["stop"],
            "incumbent": incumbent, "improved": res["x"] is not None}
