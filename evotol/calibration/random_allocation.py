"""Allocate the random sources of a calibrated robot: least cost within what calibration leaves (issue 44 item 4).

After calibration the requirement ``E`` holds the systematic residual, the noise and the random sources
(:mod:`evotol.calibration.random_share`)::

    WC_sys + q(τ) + w(τ) ≤ E − d − s,

``WC_sys`` the worst case of ``J M δp`` over the systematic box, ``q`` the quantile of the norm of the
identification's error (noise and random sources, normal) at the plan's level, ``w`` the random sources'
worst case at the poses (largest over the poses, each), ``d, s`` the second-order allowances. The
random sources are allocated with the systematic ones **at their upper bounds** (their cheapest design):
``min Σ_k c_k(τ_k)`` subject to ``q(τ) + w(τ) ≤ E − d − s − WC_sys(upper)``. When the calibration leaves no
systematic first-order error (``WC_sys = 0``: every identifiable source identified, the UR5 example) this
is the joint optimum -- the systematic tolerances cost their least whatever ``τ`` is; otherwise it is a
sequential allocation (systematic first), stated as such.

``w`` is a maximum of functions linear in ``τ`` (convex); ``q`` is taken as ``κ_i sqrt(λ_max(C_i(τ)))`` at
each pose, ``C_i(τ) = C_0 + Σ_k τ_k² C_k`` (convex in ``τ``: the largest standard deviation of a
normal vector linear in ``τ``), with ``κ_i`` the ratio of the exact quantile (:func:`norm_quantile`) to
``sqrt(λ_max)`` at the current design, updated between three SLSQP solves (log space, analytic gradients);
the final design is checked with the exact quantile.

Parameters
----------
rb : evotol.calibration.random_budget.RandomBudget
    The budget (:func:`least_cost`).
terms : dict
    Per random source ``k``: ``covariance`` (n, 3, 3) of its unit tolerance through the identification at
    the task poses, and ``support`` (n, n_directions) of its unit tolerance at the poses (see
    :func:`evotol.calibration.random_share.unit_terms`).
"""
from __future__ import annotations

import numpy as np
from scipy.optimize import minimize

from evotol._runtime.memo import last_point
from evotol.calibration.random_budget import RandomBudget


def allocate_random(C0, cov, support, cos_delta, costs, lower, upper, budget, level, start=None, iso=None) -> dict:
    """Least-cost random tolerances with ``max_i q_i(τ) + max_i w_i(τ) ≤ budget`` (module docstring) and, with
    ``iso``, the calibrated ISO 9283 AP and the RP at the test cube's poses.

    Parameters
    ----------
    C0, cov, support, cos_delta, costs, lower, upper, budget, level
        The budget, as :class:`evotol.calibration.random_budget.RandomBudget` takes it.
    start : (K,) array_like or None
        Start (default the geometric mean of the bounds).
    iso : dict or None
        :func:`evotol.calibration.random_share.iso_terms` with ``AP_budget`` (the required AP less the
        second-order allowance, m): at each ISO pose ``max_d (s0 + τ·s_d) / cos δ + q_iso(τ) ≤ AP_budget``
        (convex, like the position constraint) and the RP on fixed draws ``≤ RP (1 − RP_MARGIN)`` (sampled,
        not certified convex; :mod:`evotol.allocators.iso9283`).

    Returns
    -------
    dict
        ``tolerances`` (K,), ``cost``, ``quantile`` and ``worst_case`` (m, the largest over the poses, exact
        quantile), ``budget``, ``active`` (the constraint binds within 0.5 %), ``success``, ``message``; with
        ``iso``, ``iso``: per ISO pose ``AP`` (bound plus exact quantile), ``AP_worst_case``, ``AP_quantile``
        and ``RP`` (on the fixed draws), ``AP_budget``, ``RP_aim`` and ``active`` per figure.

    Raises
    ------
    evotol.errors.ValidationError
        Bad bounds, or a budget (or an ISO figure) the random sources at their lower bounds already exceed.
    """
    rb = RandomBudget(C0, cov, support, cos_delta, costs, lower, upper, budget, level, iso)
    return least_cost(rb, start)


def least_cost(rb: RandomBudget, start=None) -> dict:
    """The least-cost design of a calibrated budget (module docstring): three SLSQP solves in log space, ``κ``
    updated between them, then shrunk onto the budget if ``κ`` moved.

    Parameters
    ----------
    start : (K,) array_like or None
        As :func:`allocate_random`.

    Returns
    -------
    dict
        As :func:`allocate_random`.
    """
    lo, hi, budget = rb.lo, rb.hi, rb.budget
    x = np.log(np.sqrt(lo * hi) if start is None else np.clip(start, lo, hi))
    res = None
    for _ in range(3):
        q, s = rb.task.exact(np.exp(x))
        kappa = q / np.maximum(s, 1e-300)

        def con(x, kappa=kappa):
            t = np.exp(x)
            w = rb.task.worst(t)
            s, _, _ = rb.task.lam(t)
            return (budget - w[:, None] - (kappa * s)[None, :]).ravel() / budget

        def jac(x, kappa=kappa):
            t = np.exp(x)
            _, dw = rb.task.w(t)
            s, dl, _ = rb.task.lam(t)
            dq = kappa[:, None] * dl / (2 * s[:, None])
            return -(dw[:, None, :] + dq[None, :, :]).reshape(-1, len(t)) * t / budget

        def f(x):
            t = np.exp(x)
            return rb.cost(t), np.array([float(c.dcost(v)) for c, v in zip(rb.costs, t)]) * t

        cons = [{"type": "ineq", "fun": con, "jac": jac}] + ([] if rb.iso is None else _iso_constraints(rb, np.exp(x)))
        res = minimize(f, x, jac=True, method="SLSQP", bounds=list(zip(np.log(lo), np.log(hi))),
                       constraints=cons, options={"maxiter": 200, "ftol": 1e-12})
        x = res.x
    t = np.exp(x)
    if not rb.ok(t):     # κ moved since the last solve: shrink onto the budget (every term grows with τ)
        lo_s, hi_s = 0.0, 1.0
        for _ in range(40):
            mid = (lo_s + hi_s) / 2
            lo_s, hi_s = (mid, hi_s) if rb.ok(np.maximum(t * mid, lo)) else (lo_s, mid)
        t = np.maximum(t * lo_s, lo)
    q, w = float(rb.task.exact(t)[0].max()), float(rb.task.worst(t).max())
    out = {"tolerances": t, "cost": rb.cost(t), "quantile": q, "worst_case": w,
           "budget": float(budget), "active": bool(q + w >= 0.995 * budget), "success": bool(res.success),
           "message": str(res.message)}
    if rb.iso is not None:
        out["iso"] = rb.report(t)
    return out


def _iso_constraints(rb: RandomBudget, t0) -> list:
    """SLSQP's ISO constraints at ``κ`` of ``t0``: calibrated AP (convex form) and RP on the fixed draws."""
    out = []
    if rb.AP is not None:
        q, s = rb.iso_figure.exact(t0)
        kappa = q / np.maximum(s, 1e-300)

        def fun(x):
            t = np.exp(x)
            return (rb.AP - rb.iso_figure.worst(t) - kappa * rb.iso_figure.lam(t)[0]) / rb.AP

        def jac(x):
            t = np.exp(x)
            _, dw = rb.iso_figure.w(t)
            s, dl, _ = rb.iso_figure.lam(t)
            return -(dw + kappa[:, None] * dl / (2 * s[:, None])) * t / rb.AP
        out.append({"type": "ineq", "fun": fun, "jac": jac})
    if rb.RP is not None:       # RP and its gradient from one computation at each point (last_point)
        rp_at = last_point(lambda x: rb.rp(np.exp(x)))
        out.append({"type": "ineq", "fun": lambda x: (rb.rp_aim - rp_at(x)[0]) / rb.RP,
                    "jac": lambda x: -rp_at(x)[1] * np.exp(x) / rb.RP})
    return out
