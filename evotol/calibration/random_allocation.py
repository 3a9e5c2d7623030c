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

from evotol.allocators.iso9283 import RP_MARGIN
from evotol.calibration.noise_share import norm_quantile
from evotol.errors import ValidationError
from evotol.measures.iso9283.budget import rp_with_gradient


def allocate_random(C0, cov, support, cos_delta, costs, lower, upper, budget, level, start=None, iso=None) -> dict:
    """Least-cost random tolerances with ``max_i q_i(τ) + max_i w_i(τ) ≤ budget`` (module docstring) and, with
    ``iso``, the calibrated ISO 9283 AP and the RP at the test cube's poses.

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
    lo, hi = np.asarray(lower, float), np.asarray(upper, float)
    if np.any(lo <= 0) or np.any(lo > hi):
        raise ValidationError("iso9283.random bounds", (lo.min(), (hi - lo).min()), "0 < lower <= upper")
    if budget <= 0:
        raise ValidationError("requirement.position", f"{budget:.3g} m left for the random sources", "a requirement above "
                              "the calibrated systematic worst case and the second-order terms")
    cov, support = np.asarray(cov, float), np.asarray(support, float)

    def w_of(t, s0=0.0, sup=support, cd=cos_delta):
        h = s0 + np.einsum("k,knd->nd", t, sup)
        j = h.argmax(axis=1)
        return h.max(axis=1) / cd, sup[:, np.arange(len(h)), j].T / cd          # (n,), (n, K)

    def lam_of(t, C0=C0, cov=cov):
        C = C0 + np.einsum("k,knij->nij", t * t, cov)
        ev, V = np.linalg.eigh(C)
        v = V[:, :, -1]
        dl = 2 * t[None] * np.einsum("ni,knij,nj->nk", v, cov, v)
        return np.sqrt(np.maximum(ev[:, -1], 1e-300)), dl, C

    def exact(t, C0=C0, cov=cov):
        s, _, C = lam_of(t, C0, cov)
        return norm_quantile(C, level), s

    I = _IsoParts(iso, w_of, lam_of, exact) if iso is not None else None
    if exact(lo)[0].max() + w_of(lo)[0].max() > budget:
        raise ValidationError("iso9283.random.lower", lo.tolist(), f"random sources whose worst case and share of the "
                              f"identification stay below {budget:.3g} m, what calibration leaves for them")
    if I is not None:
        I.check_lower(lo)
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

        cons = [{"type": "ineq", "fun": con, "jac": jac}] + ([] if I is None else I.constraints(np.exp(x)))
        res = minimize(f, x, jac=True, method="SLSQP", bounds=list(zip(np.log(lo), np.log(hi))),
                       constraints=cons, options={"maxiter": 200, "ftol": 1e-12})
        x = res.x
    t = np.exp(x)

    def ok(t):
        return exact(t)[0].max() + w_of(t)[0].max() <= budget and (I is None or I.ok(t))

    if not ok(t):     # κ moved since the last solve: shrink onto the budget (every term grows with τ)
        lo_s, hi_s = 0.0, 1.0
        for _ in range(40):
            mid = (lo_s + hi_s) / 2
            lo_s, hi_s = (mid, hi_s) if ok(np.maximum(t * mid, lo)) else (lo_s, mid)
        t = np.maximum(t * lo_s, lo)
    q, w = float(exact(t)[0].max()), float(w_of(t)[0].max())
    out = {"tolerances": t, "cost": float(sum(c.cost(v) for c, v in zip(costs, t))), "quantile": q, "worst_case": w,
           "budget": float(budget), "active": bool(q + w >= 0.995 * budget), "success": bool(res.success),
           "message": str(res.message)}
    if I is not None:
        out["iso"] = I.report(t)
    return out


class _IsoParts:
    """The ISO 9283 constraints of :func:`allocate_random` (its ``iso`` parameter): calibrated AP and RP per pose."""

    def __init__(self, iso, w_of, lam_of, exact):
        self.iso, self.AP, self.RP = iso, iso.get("AP_budget"), iso.get("RP")
        self.rp_aim = None if self.RP is None else self.RP * (1 - RP_MARGIN)
        self.w = lambda t: w_of(t, iso["s0"], np.asarray(iso["support"], float), iso["cos_delta"])     # noqa: E731
        self.lam = lambda t: lam_of(t, iso["C0"], np.asarray(iso["cov"], float))                      # noqa: E731
        self.exact = lambda t: exact(t, iso["C0"], np.asarray(iso["cov"], float))                     # noqa: E731

    def ap(self, t):
        return self.w(t)[0] + self.exact(t)[0]                          # (p,): proven bound + exact quantile

    def rp(self, t):
        return rp_with_gradient(self.iso["E"], t)

    def check_lower(self, lo):
        if self.AP is not None and self.ap(lo).max() > self.AP:
            raise ValidationError("requirement.iso9283.AP", self.iso["AP"], f"more than {self.ap(lo).max():.3g} m plus the "
                                  "second-order allowance: the calibrated AP with every random source at its lower bound")
        if self.RP is not None and self.rp(lo)[0].max() > self.rp_aim:
            raise ValidationError("requirement.iso9283.RP", self.RP, f"more than {self.rp(lo)[0].max() / (1 - RP_MARGIN):.3g} m, "
                                  "the RP of the random sources at their lower bounds")

    def constraints(self, t0):
        out = []
        if self.AP is not None:
            q, s = self.exact(t0)
            kappa = q / np.maximum(s, 1e-300)

            def fun(x):
                t = np.exp(x)
                return (self.AP - self.w(t)[0] - kappa * self.lam(t)[0]) / self.AP

            def jac(x):
                t = np.exp(x)
                _, dw = self.w(t)
                s, dl, _ = self.lam(t)
                return -(dw + kappa[:, None] * dl / (2 * s[:, None])) * t / self.AP
            out.append({"type": "ineq", "fun": fun, "jac": jac})
        if self.RP is not None:
            out.append({"type": "ineq", "fun": lambda x: (self.rp_aim - self.rp(np.exp(x))[0]) / self.RP,
                        "jac": lambda x: -self.rp(np.exp(x))[1] * np.exp(x) / self.RP})
        return out

    def ok(self, t):
        return (self.AP is None or self.ap(t).max() <= self.AP) and (self.RP is None or self.rp(t)[0].max() <= self.rp_aim)

    def report(self, t):
        w, q = self.w(t)[0], self.exact(t)[0]
        rp = self.rp(t)[0]
        return {"AP": (w + q).tolist(), "AP_worst_case": w.tolist(), "AP_quantile": q.tolist(), "RP": rp.tolist(),
                "AP_budget": self.AP, "RP_aim": self.rp_aim,
                "proven": "AP: the systematic residual and the lost motion's offset, a proven bound (grid / cos δ, convex in "
                          "the tolerances), plus the exact quantile of the fit's error (normal: noise and random sources "
                          "through the identification) at the plan's level, less the second-order allowance of the task "
                          "poses; RP: sampled on fixed draws (not convex in general), aimed 1.5 % below the requirement",
                "active": {"AP": self.AP is not None and bool((w + q).max() >= 0.995 * self.AP),
                           "RP": self.RP is not None and bool(rp.max() >= 0.995 * self.rp_aim)}}
