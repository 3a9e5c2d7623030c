"""Allocate systematic and random sources at once to meet ISO 9283 AP and RP (issue 44, docs/iso9283.md).

Minimise ``Σ_i c_i(t_i) + Σ_k c_k(τ_k)`` over the free systematic tolerances ``t`` and the random
sources' tolerances ``τ`` (log-space SLSQP, analytic gradients) subject to, at every ISO pose,

* ``AP(t, τ) ≤ AP_req cos δ``: the worst-case barycentre error ``max_{|u|=1} h(u; t, τ)``
  (:func:`evotol.measures.iso9283.figures.ap_worst_case`), aimed at ``cos δ`` (δ the covering angle of
  the direction grid, 0.4 % for 600 directions) below the requirement so that the proven bound meets it. For each direction ``u``, ``h`` is linear in
  ``(t, τ)`` (the box's centre and half-widths are), so AP is a maximum of linear functions: **convex**
  in the tolerances, and the final design's AP is re-checked by the proven bound;
* ``RP(τ) ≤ RP_req``: ``E l + 3 std l`` on ``n_samples`` fixed draws (common random numbers, a smooth
  sample-average approximation). ``E l`` is convex in ``τ`` (an average of norms of linear functions);
  ``std l`` is not in general, so the RP constraint is **not** certified convex: what is proven is the
  convex bound ``RP ≤ E l + 3 sqrt(E l²)`` (``std ≤`` root mean square), which the result states
  beside the sampled RP; the sampled RP is aimed :data:`RP_MARGIN` below the requirement and
  re-estimated on fresh draws;
* the orientation figures (ISO 9283 §7.2), where required: ``AP_a ≤ limit`` (the worst case
  ``|r·c| + Σ_i |r_i| h_i`` of one linear function over the box, exact and convex) and ``RP_a ≤ limit``
  (``3 sqrt(Σ_k τ_k² w_k)``, exact for the linearised random sources, a weighted norm: convex), per angle
  a, b, c about the base axes: **certified**.

Parameters
----------
robot : evotol.robots.mechanism.model.error_model.MechanismModel
    The mechanism (a description, serial or closed-loop).
positions : (p, 3) array_like
    The ISO poses (m).
sys_costs : list of evotol.cost_models.base.CostModel or None
    Per column of the model its cost model; None for a given (fixed) source, never priced.
sys_bounds : (2, n_columns) array_like
    Lower and upper bounds of the systematic tolerances (SI); a column not free keeps its lower.
free : (n_columns,) array_like of bool
    Which systematic tolerances the allocation may change.
sources : sequence of evotol.robots.mechanism.model.random_sources.RandomSource
    The random sources.
rand_costs : list of evotol.cost_models.base.CostModel
    Per random source its cost model.
rand_bounds : (2, n_random) array_like
    Lower and upper bounds of the random tolerances (SI).
AP, RP : float or None
    Required figures (m); None: no such constraint.
n_samples : int
    Fixed cycle draws for RP.
seed : int
    Seed of the draws.
orientation : dict or None
    Orientation figures required (ISO 9283 §7.2, rad): keys ``APa``, ``APb``, ``APc`` (worst case of
    ``|ā − a_c|`` over the tolerance box, exact: ``|r·c| + Σ |r_i| h_i``, convex) and ``RPa``, ``RPb``,
    ``RPc`` (``3 sqrt(Σ_k τ_k² w_k)``, exact for the linearised random sources, convex: a weighted norm);
    a, b, c the rotations about the base x, y, z (:func:`evotol.measures.iso9283.predict_orientation`).
"""
from __future__ import annotations

import numpy as np
from scipy.optimize import minimize

from evotol._runtime.memo import last_point
from evotol.errors import ValidationError
from evotol.measures.iso9283.budget import (joints_and_maps, lost_motion_parts, orientation_variance_weights,
                                           rp_unit_errors, rp_with_gradient)
from evotol.measures.iso9283.figures import ap_worst_case, rp_from_errors, worst_direction
from evotol.measures.linear.directions import directions_for
from evotol.robots.mechanism.model.random_sources import column_loading, unit_draws

#: the sampled RP is aimed this share below the requirement: about 3 standard errors of the estimate
#: ``E l + 3 std l`` on 10 000 draws (0.4-0.6 % between two seeds on the UR5 example)
RP_MARGIN = 0.015


def allocate_iso9283(robot, positions, sys_costs, sys_bounds, free, sources, rand_costs, rand_bounds, AP, RP,
                     x0=None, n_samples: int = 10000, seed: int = 0, maxiter: int = 200, orientation=None) -> dict:
    """Least-cost tolerances meeting AP (worst case) and RP at every pose (module docstring).

    Parameters
    ----------
    x0 : (n_columns + n_random,) array_like or None
        Start (SI); None: the geometric mean of the bounds.
    maxiter : int
        SLSQP iterations.

    Returns
    -------
    dict
        ``systematic`` (n_columns,) and ``random`` (n_random,) tolerances (SI), ``cost``, ``AP``
        and ``AP_bound`` (p,), ``RP`` (p,) on the draws and ``RP_fresh`` on fresh draws,
        ``RP_convex_bound`` (p,), ``active`` (which constraints bind), ``success``, ``message``; with
        ``orientation``, ``orientation``: per key its ``limit``, per pose ``value`` (rad) and ``active``.

    Raises
    ------
    evotol.errors.ValidationError
        Bounds with lower > upper or not positive, or neither AP nor RP.
    """
    terms = iso_terms(robot, positions, sys_bounds, free, sources, rand_bounds, AP, RP, orientation, n_samples, seed)
    lo, hi, var, m, K, J, C, H, E = (terms[k] for k in ("lo", "hi", "var", "m", "K", "J", "C", "H", "E"))
    S, loadings = terms["S"], terms["loadings"]
    costs = list(sys_costs) + list(rand_costs)

    def full(x):
        t = lo.copy()
        t[var] = np.exp(x)
        return t

    def cost(x):            # a given (fixed) source has no cost model: never priced
        t = full(x)
        c = sum(float(cm.cost(ti)) for cm, ti in zip(costs, t) if cm is not None)
        g = np.array([0.0 if cm is None else float(cm.dcost(ti)) for cm, ti in zip(costs, t)]) * t
        return c, g[var]

    def ap_parts(t):
        ts, tr = t[:m], t[m:]
        out, grads = [], []
        for i in range(len(J)):
            c, h = C[i] @ tr, ts + H[i] @ tr
            u = worst_direction(J[i], c, h)                  # the maximising direction; gradient by the envelope theorem
            a = u @ J[i]                                                     # (m,)
            g = np.concatenate([np.abs(a), a @ C[i] + np.abs(a) @ H[i]]) * t
            out.append(a @ c + np.abs(a) @ h)
            grads.append(g[var])
        return np.array(out), np.array(grads)

    def rp_parts(t):
        rp, grad = rp_with_gradient(E, t[m:])
        g = np.zeros((len(J), m + K))
        g[:, m:] = grad * t[m:]
        return rp, g[:, var]

    # SLSQP asks a constraint's value and then its jacobian at the same point: each is computed once
    ap_at, rp_at = last_point(lambda x: ap_parts(full(x))), last_point(lambda x: rp_parts(full(x)))
    cons = []
    # aim at AP cos δ: the proven bound (grid maximum / cos δ <= attained / cos δ) then meets AP
    ap_aim = None if AP is None else AP * np.cos(terms["delta"])
    if AP is not None:
        cons.append({"type": "ineq", "fun": lambda x: (ap_aim - ap_at(x)[0]) / AP, "jac": lambda x: -ap_at(x)[1] / AP})
    rp_aim = terms["rp_aim"]
    if RP is not None and K:
        cons.append({"type": "ineq", "fun": lambda x: (rp_aim - rp_at(x)[0]) / RP, "jac": lambda x: -rp_at(x)[1] / RP})
    R = S[:, 3:]                                                              # orientation rows (p, 3, m)
    Wv = orientation_variance_weights(R, loadings, sources) if K else np.zeros((len(J), 3, 0))

    def angle_parts(t, key):                  # APa..RPc at every pose, and its gradient in log space
        ts, tr, r = t[:m], t[m:], R[:, "abc".index(key[2])]
        g = np.zeros((len(J), m + K))
        if key.startswith("AP"):
            c = np.einsum("pm,pmk,k->p", r, C, tr)
            val = np.abs(c) + np.einsum("pm,pm->p", np.abs(r), ts[None] + H @ tr)
            g[:, :m] = np.abs(r)
            g[:, m:] = np.sign(c)[:, None] * np.einsum("pm,pmk->pk", r, C) + np.einsum("pm,pmk->pk", np.abs(r), H)
        else:
            w = Wv[:, "abc".index(key[2])]
            val = 3 * np.sqrt(np.maximum(w @ (tr * tr), 1e-300))
            g[:, m:] = 9 * w * tr / val[:, None]
        return val, (g * t)[:, var]

    ori = {k: float(v) for k, v in (orientation or {}).items() if v is not None}
    for key, L in ori.items():          # aimed 1e-6 below: the exact figure then meets the limit, not rounds onto it
        at = last_point(lambda x, k=key: angle_parts(full(x), k))
        cons.append({"type": "ineq", "fun": lambda x, at=at, L=L: (L * (1 - 1e-6) - at(x)[0]) / L,
                     "jac": lambda x, at=at, L=L: -at(x)[1] / L})
    start = np.sqrt(lo * hi) if x0 is None else np.clip(np.asarray(x0, float), lo, hi)
    res = minimize(lambda x: cost(x), np.log(start[var]), jac=True, method="SLSQP", constraints=cons,
                   bounds=list(zip(np.log(lo[var]), np.log(hi[var]))), options={"maxiter": maxiter, "ftol": 1e-10})
    t = full(res.x)
    chk = iso_check(terms, t)
    ap_val, rp_val, feasible = chk["ap"], chk["RP"], chk["feasible"]
    orient = {k: {"limit": L, "value": angle_parts(t, k)[0].tolist()} for k, L in ori.items()}
    for o in orient.values():
        o["active"] = bool(max(o["value"]) >= o["limit"] * (1 - 1e-3))
        feasible = feasible and max(o["value"]) <= o["limit"] * (1 + 1e-6)
    return {**({"orientation": orient} if ori else {}), "systematic": t[:m], "random": t[m:], "cost": cost(res.x)[0], "AP": ap_val[:, 0], "AP_bound": ap_val[:, 1],
            "RP": rp_val, "RP_fresh": chk["RP_fresh"], "RP_convex_bound": chk["RP_convex_bound"], "feasible": bool(feasible),
            "active": {"AP": AP is not None and bool(ap_val[:, 0].max() >= ap_aim * (1 - 1e-3)),
                       "RP": RP is not None and bool(rp_val.max() >= rp_aim * (1 - 1e-3))},
            "success": bool(res.success), "message": str(res.message)}



def iso_terms(robot, positions, sys_bounds, free, sources, rand_bounds, AP, RP, orientation=None,
              n_samples: int = 10000, seed: int = 0) -> dict:
    """The parts of the ISO 9283 constraints shared by every allocator (module docstring), checked.

    Returns
    -------
    dict
        ``lo``, ``hi`` (bounds of systematic then random tolerances, SI), ``var`` (which are variables),
        ``m``, ``K`` (numbers of columns and random sources), ``S`` (p, 6, m) the first-order map,
        ``J`` its position rows, ``C``, ``H`` (p, m, K) the lost motion's box per unit tolerance,
        ``E`` (p, n, 3, K) the fixed RP draws, ``loadings``, ``delta`` (the covering angle of the AP
        direction grid, rad), ``AP``, ``RP``, ``rp_aim`` (m), ``sources``, ``n_samples``, ``seed``.

    Raises
    ------
    evotol.errors.ValidationError
        Bounds with lower > upper or not positive, or neither AP, RP nor an orientation figure.
    """
    rb = np.asarray(rand_bounds, float).reshape(2, -1)
    lo = np.concatenate([np.asarray(sys_bounds, float)[0], rb[0]])
    hi = np.concatenate([np.asarray(sys_bounds, float)[1], rb[1]])
    if np.any(lo <= 0) or np.any(lo > hi):
        raise ValidationError("iso9283 allocation bounds", (lo.min(), (hi - lo).min()), "0 < lower <= upper")
    if AP is None and RP is None and not orientation:
        raise ValidationError("iso9283 requirement", None, "AP, RP or an orientation figure to allocate for")
    free = np.asarray(free, bool)
    m, K = len(free), len(sources)
    _, S = joints_and_maps(robot, positions)
    J = S[:, :3]
    loadings = column_loading(robot, sources)
    C, H = lost_motion_parts(robot, S, sources, loadings)
    E = rp_unit_errors(robot, S, sources, n_samples, seed) if K else np.zeros((len(J), n_samples, 3, 0))   # (p, n, 3, K)
    return {"lo": lo, "hi": hi, "var": np.concatenate([free, np.ones(K, bool)]), "m": m, "K": K, "S": S, "J": J,
            "C": C, "H": H, "E": E, "loadings": loadings, "delta": directions_for(J, 600, full_sphere=True)[1],
            "AP": AP, "RP": RP, "rp_aim": None if RP is None else RP * (1 - RP_MARGIN), "sources": list(sources),
            "n_samples": n_samples, "seed": seed}


def iso_check(terms: dict, t) -> dict:
    """The exact first-order AP and RP of one design, as every allocator's final design is judged.

    AP: the attained worst case and its proven bound (grid / cos δ) at each pose
    (:func:`evotol.measures.iso9283.figures.ap_worst_case`); RP: ``E l + 3 std l`` on the fixed draws of
    :func:`iso_terms` and on fresh draws; feasible if the bound meets AP and the fixed-draw RP meets RP.

    Parameters
    ----------
    terms : dict
        :func:`iso_terms`.
    t : (m + K,) array_like
        Systematic then random tolerances (SI).

    Returns
    -------
    dict
        ``ap`` (p, 2) attained and bound, ``RP``, ``RP_fresh``, ``RP_convex_bound`` (p,), all m, and ``feasible``.
    """
    t = np.asarray(t, float)
    m, J, C, H, E, AP, RP = (terms[k] for k in ("m", "J", "C", "H", "E", "AP", "RP"))
    ap_val = np.array([ap_worst_case(J[i:i + 1], C[i] @ t[m:], t[:m] + H[i] @ t[m:]) for i in range(len(J))])[:, :, 0]
    rp_val = rp_with_gradient(E, t[m:])[0]
    fresh = unit_draws(terms["sources"], terms["n_samples"], np.random.default_rng(terms["seed"] + 1))
    rp_fresh = rp_from_errors(sum((tk * np.einsum("pim,nm->pni", J, d @ G.T) for G, d, tk in zip(terms["loadings"], fresh, t[m:])),
                                  np.zeros((len(J), terms["n_samples"], 3))))
    l2 = np.sqrt(np.mean(np.sum((E @ t[m:]) ** 2, axis=-1), axis=1))
    bound = np.linalg.norm(E @ t[m:], axis=-1).mean(1) + 3 * l2
    feasible = (AP is None or ap_val[:, 1].max() <= AP * (1 + 1e-6)) and (RP is None or rp_val.max() <= RP * (1 + 1e-6))
    return {"ap": ap_val, "RP": rp_val, "RP_fresh": rp_fresh, "RP_convex_bound": bound, "feasible": bool(feasible)}
