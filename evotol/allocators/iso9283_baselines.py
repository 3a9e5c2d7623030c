"""The textbook baselines -- equal tolerances and the Lagrange closed form -- on systematic and random sources
under ISO 9283 AP and RP (issue 44 item 3, docs/iso9283.md): the study's ``equal`` and ``lagrange`` beside
``[iso9283] allocate = true``, on the problem of :func:`evotol.allocators.iso9283.allocate_iso9283`, so that its
certified optimum shows what each rule costs. Both are judged like every allocator's design
(:func:`evotol.allocators.iso9283.iso_check`): feasible only if the proven AP bound meets AP and the RP on the
fixed draws meets RP.

* **Equal tolerances** (:func:`allocate_iso9283_equal`): every variable tolerance the same value ``c`` (SI: m or
  rad, as :func:`evotol.allocators.baselines.equal_design` on the position requirement), clipped to its bounds;
  ``c`` the largest on a log grid refined by bisection for which the proven AP bound meets AP and the sampled RP
  meets its aim (1.5 % below RP, like every ISO allocator). AP and RP never decrease when ``c`` grows (the AP
  bound is a maximum of functions linear in the tolerances with non-negative weights; RP's ``E l`` is convex and
  even in each ``τ_k``), so the grid and bisection find the boundary.
* **Lagrange** (:func:`allocate_iso9283_lagrange`; Spotts 1973, Chase & Greenwood 1988, as
  :mod:`evotol.allocators.baselines`): least cost on the two single stack-ups of the equal-effect rule's effects
  (:func:`evotol.allocators.iso9283_sensitivity.source_effects`)::

      AP:  Σ_j a_j t_j = AP                 (worst case, every source with an effect on the barycentre)
      RP:  sqrt(Σ_k ρ_k² τ_k²) = RP         (root sum square, every random source)

  Stationarity ``c_j'(t_j) + λ a_j = 0`` (AP) and ``c_k'(τ_k) + 2 λ ρ_k² τ_k = 0`` (RP) gives each tolerance as
  a function of λ (bisection in log t for any convex decreasing cost model, clipped to the bounds); λ > 0 by a
  root solve in log λ so that the stack-up holds with equality. A random source in both stack-ups takes the
  smaller tolerance. The design is then scaled onto the AP/RP boundary as the equal-effect rule's
  (:func:`evotol.allocators.iso9283_sensitivity.rule_design`).

A source with no effect on either figure gets its upper bound; a systematic column that is not free keeps its
lower bound (its given value), as in the optimum.
"""
from __future__ import annotations

import numpy as np
from scipy.optimize import brentq

from evotol.allocators.iso9283 import iso_terms
from evotol.allocators.iso9283_ga import population_figures
from evotol.allocators.iso9283_sensitivity import rule_design, source_effects


def within_requirement(terms: dict, T: np.ndarray) -> np.ndarray:
    """Whether each design's proven AP bound meets AP and its sampled RP meets the aim: the check the equal
    tolerances and the polyblock (:mod:`evotol.allocators.iso9283_monotone`) search by.

    Parameters
    ----------
    terms : dict
        The problem whose AP and RP aim the designs are checked against (:func:`evotol.allocators.iso9283.iso_terms`).
    T : (n, m + K) ndarray
        The designs checked, systematic then random (SI).

    Returns
    -------
    (n,) ndarray of bool
        Grid AP bound ``<= AP (1 − 1e-9)`` and fixed-draw RP ``<=`` its aim, at every pose.
    """
    ap, rp = population_figures(terms, T)
    ok = np.ones(len(T), bool)
    if terms["AP"] is not None:
        ok &= ap.max(1) <= terms["AP"] * (1 - 1e-9)
    if terms["RP"] is not None and terms["K"]:
        ok &= rp.max(1) <= terms["rp_aim"]
    return ok


def equal_tolerances(terms: dict) -> np.ndarray:
    """The largest common tolerance ``c`` (clipped to each bound) that meets AP and RP (module docstring).

    Parameters
    ----------
    terms : dict
        The problem (:func:`evotol.allocators.iso9283.iso_terms`): which tolerances vary, their bounds, AP and
        RP's aim.

    Returns
    -------
    (m + K,) ndarray
        Systematic then random tolerances (SI); not free: lower bound. Every variable at its lower bound when
        even that misses (the judgement then says not feasible).
    """
    var, lo, hi = terms["var"], terms["lo"], terms["hi"]

    def design(c):
        return np.where(var, np.clip(np.asarray(c, float)[:, None], lo, hi), lo)

    grid = np.geomspace(lo[var].min(), hi[var].max(), 65)
    ok = within_requirement(terms, design(grid))
    if ok.all():
        return design(grid[-1:])[0]
    if not ok[0]:
        return design(grid[:1])[0]
    i = int(np.argmin(ok))                                                # first grid value that misses
    a, b = np.log(grid[i - 1]), np.log(grid[i])
    for _ in range(40):                                                   # bisection in log c
        mid = 0.5 * (a + b)
        a, b = (mid, b) if within_requirement(terms, design([np.exp(mid)]))[0] else (a, mid)
    return design([np.exp(a)])[0]


def _t_of_lambda(costs, lo, hi, g, lam: float, rss: bool) -> np.ndarray:
    """Each tolerance solving ``−c_j'(t) = λ g_j (2 t if rss else 1)`` in [lo, hi] (bisection in log t, 60 steps;
    the left side decreases with t for a convex decreasing cost model, the right side does not)."""
    a, b = np.log(lo), np.log(hi)
    for _ in range(60):
        mid = 0.5 * (a + b)
        t = np.exp(mid)
        slope = -np.array([float(cm.dcost(tj)) for cm, tj in zip(costs, t)])
        dear = slope > lam * g * (2 * t if rss else 1.0)                 # cost still falls faster: t may grow
        a, b = np.where(dear, mid, a), np.where(dear, b, mid)
    return np.exp(0.5 * (a + b))


def stack_up(costs, lo, hi, g, target: float, rss: bool) -> np.ndarray:
    """The Lagrange tolerances on one stack-up ``Σ g t = target`` (or ``sqrt(Σ g² t²)``), λ by a root solve in
    log λ; every tolerance at its upper bound when those already hold it.

    Parameters
    ----------
    costs : sequence of evotol.cost_models.base.CostModel
        Per tolerance its convex, decreasing cost model.
    lo, hi : (n,) ndarray
        Bounds (SI).
    g : (n,) ndarray
        Effect per unit tolerance (the target's unit per SI unit), > 0.
    target : float
        The stack-up's limit.
    rss : bool
        Root sum square instead of the worst-case sum.

    Returns
    -------
    (n,) ndarray
        The tolerances (SI): the lower bounds when even those miss the target.
    """
    gg = g ** 2 if rss else g

    def excess(loglam):
        t = _t_of_lambda(costs, lo, hi, gg, np.exp(loglam), rss)
        return (np.sqrt(np.sum((g * t) ** 2)) if rss else float(np.sum(g * t))) / target - 1

    if excess(-80.0) <= 0:
        return hi.copy()
    if excess(80.0) > 0:                                                  # even the lower bounds miss it
        return lo.copy()
    return _t_of_lambda(costs, lo, hi, gg, np.exp(brentq(excess, -80.0, 80.0, xtol=1e-10)), rss)


def lagrange_tolerances(terms: dict, costs) -> np.ndarray:
    """The Lagrange closed form on the AP and RP stack-ups, before scaling onto the boundary (module docstring).

    Parameters
    ----------
    terms : dict
        The problem whose two stack-ups are solved (:func:`evotol.allocators.iso9283.iso_terms`).
    costs : list of evotol.cost_models.base.CostModel or None
        Per column, systematic then random (None only where the column is not free).

    Returns
    -------
    (m + K,) ndarray
        Systematic then random tolerances (SI); no effect: upper bound; not free: lower bound.
    """
    m, K, var, lo, hi = terms["m"], terms["K"], terms["var"], terms["lo"], terms["hi"]
    a, rho = source_effects(terms)
    t = hi.copy()
    on_ap = var & (a > 1e-12 * a.max(initial=0))
    if terms["AP"] is not None and on_ap.any():
        idx = np.flatnonzero(on_ap)
        t[idx] = stack_up([costs[j] for j in idx], lo[idx], hi[idx], a[idx], terms["AP"], rss=False)
    on_rp = np.flatnonzero(rho > 0)
    if len(on_rp):
        idx = m + on_rp
        tau = stack_up([costs[j] for j in idx], lo[idx], hi[idx], rho[on_rp], terms["RP"], rss=True)
        t[idx] = np.where(on_ap[idx], np.minimum(t[idx], tau), tau)
    return np.where(var, np.clip(t, lo, hi), lo)


def allocate_iso9283_equal(robot, positions, sys_costs, sys_bounds, free, sources, rand_costs, rand_bounds, AP, RP,
                           *, n_samples: int = 10000, seed: int = 0) -> dict:
    """Equal tolerances on systematic and random sources meeting AP (proven bound) and RP (module docstring).

    Parameters
    ----------
    robot, positions, sys_costs, sys_bounds, free, sources, rand_costs, rand_bounds, AP, RP, n_samples, seed
        The problem as :func:`evotol.allocators.iso9283.allocate_iso9283` takes it (SI); ``seed`` seeds the RP
        draws as the optimum's does.

    Returns
    -------
    dict
        As :func:`evotol.allocators.iso9283_sensitivity.rule_design` (``shares``: the equal tolerances).

    Raises
    ------
    evotol.errors.ValidationError
        As :func:`evotol.allocators.iso9283.iso_terms`.
    """
    terms = iso_terms(robot, positions, sys_bounds, free, sources, rand_bounds, AP, RP, None, n_samples, seed)
    return rule_design(terms, list(sys_costs) + list(rand_costs), equal_tolerances(terms), iters=0)


def allocate_iso9283_lagrange(robot, positions, sys_costs, sys_bounds, free, sources, rand_costs, rand_bounds, AP,
                              RP, *, n_samples: int = 10000, seed: int = 0) -> dict:
    """The Lagrange closed-form tolerances, scaled onto the AP/RP boundary (module docstring).

    Parameters
    ----------
    robot, positions, sys_costs, sys_bounds, free, sources, rand_costs, rand_bounds, AP, RP, n_samples, seed
        As :func:`allocate_iso9283_equal`.

    Returns
    -------
    dict
        As :func:`evotol.allocators.iso9283_sensitivity.rule_design` (``shares``: the closed form's tolerances).

    Raises
    ------
    evotol.errors.ValidationError
        As :func:`evotol.allocators.iso9283.iso_terms`.
    """
    terms = iso_terms(robot, positions, sys_bounds, free, sources, rand_bounds, AP, RP, None, n_samples, seed)
    costs = list(sys_costs) + list(rand_costs)
    return rule_design(terms, costs, lagrange_tolerances(terms, costs))
