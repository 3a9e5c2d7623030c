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
terms : dict
    Per random source ``k``: ``covariance`` (n, 3, 3) of its unit tolerance through the identification at
    the task poses, and ``support`` (n, n_directions) of its unit tolerance at the poses (see
    :func:`evotol.calibration.random_share.unit_terms`).
"""
from __future__ import annotations

import numpy as np
from scipy.optimize import minimize

from evotol.calibration.noise_share import norm_quantile
from evotol.errors import ValidationError


def allocate_random(C0, cov, support, cos_delta, costs, lower, upper, budget, level, start=None) -> dict:
    """Least-cost random tolerances with ``max_i q_i(τ) + max_i w_i(τ) ≤ budget`` (module docstring).

    Parameters
    ----------
    C0 : (n, 3, 3) ndarray
        The noise's covariance at the task poses (m²).
    cov : (K, n, 3, 3) ndarray
        Per random source the covariance of its unit tolerance through the identification (m² per unit²).
    support : (K, n, d) ndarray
        Per random source its support at the poses on a grid of d directions per unit tolerance (m per unit).
    cos_delta : float
        Cosine of the grid's covering angle (the worst case is the grid maximum / cos δ).
    costs : sequence of evotol.cost_models.base.CostModel
        Per random source its cost model.
    lower, upper : (K,) array_like
        Bounds of the random tolerances (SI), ``0 < lower ≤ upper``.
    budget : float
        ``E − d − s − WC_sys`` (m).
    level : float
        Probability of the noise quantile.
    start : (K,) array_like or None
        Start (default the geometric mean of the bounds).

    Returns
    -------
    dict
        ``tolerances`` (K,), ``cost``, ``quantile`` and ``worst_case`` (m, the largest over the poses, exact
        quantile), ``budget``, ``active`` (the constraint binds within 0.5 %), ``success``, ``message``.

    Raises
    ------
    evotol.errors.ValidationError
        Bad bounds, or a budget the random sources at their lower bounds already exceed.
    """
    lo, hi = np.asarray(lower, float), np.asarray(upper, float)
    if np.any(lo <= 0) or np.any(lo > hi):
        raise ValidationError("iso9283.random bounds", (lo.min(), (hi - lo).min()), "0 < lower <= upper")
    if budget <= 0:
        raise ValidationError("requirement.position", f"{budget:.3g} m left for the random sources", "a requirement above "
                              "the calibrated systematic worst case and the second-order terms")
    cov, support = np.asarray(cov, float), np.asarray(support, float)

    def w_of(t):
        h = np.einsum("k,knd->nd", t, support)
        j = h.argmax(axis=1)
        return h.max(axis=1) / cos_delta, support[:, np.arange(len(h)), j].T / cos_delta          # (n,), (n, K)

    def lam_of(t):
        C = C0 + np.einsum("k,knij->nij", t * t, cov)
        ev, V = np.linalg.eigh(C)
        v = V[:, :, -1]
        dl = 2 * t[None] * np.einsum("ni,knij,nj->nk", v, cov, v)
        return np.sqrt(np.maximum(ev[:, -1], 1e-300)), dl, C

    def exact(t):
        s, _, C = lam_of(t)
        return norm_quantile(C, level), s

    if exact(lo)[0].max() + w_of(lo)[0].max() > budget:
        raise ValidationError("iso9283.random.lower", lo.tolist(), f"random sources whose worst case and share of the "
                              f"identification stay below {budget:.3g} m, what calibration leaves for them")
    x = np.log(np.sqrt(lo * hi) if start is None else np.clip(start, lo, hi))
    res = None
    for _ in range(3):
        q, s = exact(np.exp(x))
        kappa = q / np.maximum(s, 1e-300)

        def con(x, kappa=kappa):
            t = np.exp(x)
            w, _ = w_of(t)
            s, _, _ = lam_of(t)
            return (budget - w[:, None] - (kappa * s)[None, :]).ravel() / budget

        def jac(x, kappa=kappa):
            t = np.exp(x)
            _, dw = w_of(t)
            s, dl, _ = lam_of(t)
            dq = kappa[:, None] * dl / (2 * s[:, None])
            return -(dw[:, None, :] + dq[None, :, :]).reshape(-1, len(t)) * t / budget

        def f(x):
            t = np.exp(x)
            return sum(float(c.cost(v)) for c, v in zip(costs, t)), np.array([float(c.dcost(v)) for c, v in zip(costs, t)]) * t

        res = minimize(f, x, jac=True, method="SLSQP", bounds=list(zip(np.log(lo), np.log(hi))),
                       constraints=[{"type": "ineq", "fun": con, "jac": jac}], options={"maxiter": 200, "ftol": 1e-12})
        x = res.x
    t = np.exp(x)
    q = float(exact(t)[0].max())
    w = float(w_of(t)[0].max())
    if q + w > budget:     # κ moved since the last solve: shrink onto the budget (both terms grow with τ)
        lo_s, hi_s = 0.0, 1.0
        for _ in range(40):
            mid = (lo_s + hi_s) / 2
            tm = np.maximum(t * mid, lo)
            ok = exact(tm)[0].max() + w_of(tm)[0].max() <= budget
            lo_s, hi_s = (mid, hi_s) if ok else (lo_s, mid)
        t = np.maximum(t * lo_s, lo)
        q, w = float(exact(t)[0].max()), float(w_of(t)[0].max())
    return {"tolerances": t, "cost": float(sum(c.cost(v) for c, v in zip(costs, t))), "quantile": q, "worst_case": w,
            "budget": float(budget), "active": bool(q + w >= 0.995 * budget), "success": bool(res.success),
            "message": str(res.message)}
