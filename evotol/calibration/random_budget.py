"""What calibration leaves for the random sources, as functions of their tolerances ``τ`` (issue 44 item 4,
docs/iso9283.md): the constraints every allocator of the calibrated budget is judged by.

After calibration the requirement ``E`` holds the systematic residual, the noise and the random sources
(:mod:`evotol.calibration.random_share`); at each task pose ``i``::

    q_i(τ) + w_i(τ) ≤ budget = E − d − s − WC_sys,

``q_i`` the exact quantile of the norm of the identification's error (normal: noise and random sources, covariance
``C_i(τ) = C_0 + Σ_k τ_k² C_k``) at the plan's level, ``w_i`` the random sources' worst case (largest over a grid
of directions / cos δ: a proven bound, linear in ``τ`` per direction). With an ISO 9283 target, at each ISO pose
the calibrated AP (the lost motion's offset and the systematic residual, proven bound, plus the fit's quantile)
meets ``AP_budget`` and the RP on fixed draws meets ``RP (1 − RP_MARGIN)``.

Every term is non-decreasing in each ``τ_k``: ``w`` has non-negative weights; a larger covariance (in the
positive semi-definite order) gives a larger quantile of the norm of a centred normal vector (Anderson's
theorem); RP on fixed draws is taken as non-decreasing, as in :mod:`evotol.allocators.iso9283`. So a design can be
moved onto the boundary along a ray (:meth:`RandomBudget.onto_boundary`).

Parameters
----------
t : (K,) ndarray
    Random tolerances (SI: rad, m).
"""
from __future__ import annotations

import numpy as np

from evotol.allocators.iso9283 import RP_MARGIN
from evotol.calibration.noise_share import norm_quantile, norm_within
from evotol.errors import ValidationError
from evotol.measures.iso9283.budget import rp_value, rp_with_gradient


class Figure:
    """One calibrated figure's two parts as functions of ``τ``, per pose: the worst case ``w_i`` (``s_0`` plus the
    sources' support on a grid of directions, / cos δ: a proven bound) and the fit's error, normal with
    covariance ``C_0 + Σ_k τ_k² C_k``. The budget's position figure at the task poses and the calibrated AP at
    the ISO poses are both of this form.

    Parameters
    ----------
    s0 : float or (n, d) ndarray
        The fixed part of the support (m).
    support : (K, n, d) ndarray
        Per random source its support per unit tolerance (m per unit).
    cos_delta : float
        Cosine of the grid's covering angle.
    C0 : (n, 3, 3) ndarray
        The noise's covariance (m²).
    cov : (K, n, 3, 3) ndarray
        Per random source the covariance of its unit tolerance through the identification (m² per unit²).
    level : float
        Probability of the quantile.
    """

    def __init__(self, s0, support, cos_delta, C0, cov, level):
        self.s0, self.support, self.cos_delta = s0, np.asarray(support, float), cos_delta
        self.C0, self.cov, self.level = C0, np.asarray(cov, float), level

    def w(self, t):
        """Worst case per pose (m) and its gradient at the maximising direction (m per unit).

        Returns
        -------
        tuple of ndarray
            ``(n,)`` and ``(n, K)``.
        """
        h = self._support(t)
        j = h.argmax(axis=1)
        return h.max(axis=1) / self.cos_delta, self.support[:, np.arange(len(h)), j].T / self.cos_delta

    def worst(self, t):
        """Worst case per pose (m): :meth:`w`'s value, without its gradient (the checks' and reports' need).

        Returns
        -------
        (n,) ndarray
        """
        return self._support(t).max(axis=1) / self.cos_delta

    def _support(self, t):
        """``s_0 + Σ_k τ_k support_k`` per pose and grid direction (m)."""
        return self.s0 + np.einsum("k,knd->nd", t, self.support)

    def lam(self, t):
        """``sqrt(λ_max(C_i(τ)))`` per pose (m), its gradient, and ``C_i(τ)``.

        Returns
        -------
        tuple of ndarray
            ``(n,)``, ``(n, K)``, ``(n, 3, 3)``.
        """
        C = self.covariance(t)
        ev, V = np.linalg.eigh(C)
        v = V[:, :, -1]
        dl = 2 * t[None] * np.einsum("ni,knij,nj->nk", v, self.cov, v)
        return np.sqrt(np.maximum(ev[:, -1], 1e-300)), dl, C

    def exact(self, t):
        """The exact quantile of the fit's error per pose and ``sqrt(λ_max)`` (m).

        Returns
        -------
        tuple of ndarray
            Two ``(n,)`` arrays.
        """
        s, _, C = self.lam(t)
        return norm_quantile(C, self.level), s

    def within(self, t, limits) -> bool:
        """Whether the exact quantile of the fit's error is at most ``limits`` at every pose (m): the check
        :meth:`exact` would give against them, by one evaluation of the distribution per pose
        (:func:`evotol.calibration.noise_share.norm_within`).

        Parameters
        ----------
        limits : float or (n,) array_like
            Per pose the largest quantile allowed (m).

        Returns
        -------
        bool
        """
        return norm_within(self.covariance(t), self.level, limits)

    def covariance(self, t):
        """The fit's error covariance per pose, ``C_0 + Σ_k τ_k² C_k`` (m²).

        Returns
        -------
        (n, 3, 3) ndarray
        """
        t = np.asarray(t, float)
        return self.C0 + np.einsum("k,knij->nij", t * t, self.cov)


class RandomBudget:
    """The calibrated budget of the random sources (module docstring): figures, feasibility and cost of a design.

    Parameters
    ----------
    C0, cov, support, cos_delta
        The task poses' noise covariance (m²), per source its unit covariance through the identification and its
        support on the direction grid, and the grid's cosine: the position :class:`Figure` (with ``s0 = 0``).
    costs : sequence of evotol.cost_models.base.CostModel
        Per random source its cost model.
    lower, upper : (K,) array_like
        Bounds of the random tolerances (SI), ``0 < lower ≤ upper``.
    budget : float
        ``E − d − s − WC_sys`` (m).
    level : float
        Probability of the noise quantile.
    iso : dict or None
        :func:`evotol.calibration.random_share.iso_terms` with ``AP_budget`` (m), or None.

    Raises
    ------
    evotol.errors.ValidationError
        Bad bounds, or a budget (or an ISO figure) the random sources at their lower bounds already exceed.
    """

    def __init__(self, C0, cov, support, cos_delta, costs, lower, upper, budget, level, iso=None):
        self.lo, self.hi = np.asarray(lower, float), np.asarray(upper, float)
        if np.any(self.lo <= 0) or np.any(self.lo > self.hi):
            raise ValidationError("iso9283.random bounds", (self.lo.min(), (self.hi - self.lo).min()), "0 < lower <= upper")
        if budget <= 0:
            raise ValidationError("requirement.position", f"{budget:.3g} m left for the random sources", "a requirement "
                                  "above the calibrated systematic worst case and the second-order terms")
        self.task = Figure(0.0, support, cos_delta, C0, cov, level)          # the position figure at the task poses
        self.costs, self.budget, self.level = list(costs), float(budget), level
        self.iso = iso
        self.AP = None if iso is None else iso.get("AP_budget")
        self.RP = None if iso is None else iso.get("RP")
        self.rp_aim = None if self.RP is None else self.RP * (1 - RP_MARGIN)
        self.iso_figure = None if iso is None else Figure(iso["s0"], iso["support"], iso["cos_delta"], iso["C0"],
                                                          iso["cov"], level)    # the calibrated AP at P1-P5
        if self.position(self.lo) > self.budget:
            raise ValidationError("iso9283.random.lower", self.lo.tolist(), f"random sources whose worst case and share "
                                  f"of the identification stay below {self.budget:.3g} m, what calibration leaves for them")
        if iso is not None:
            self._check_iso_lower()

    # -- the position budget at the task poses
    def position(self, t) -> float:
        """``max_i q_i(τ) + max_i w_i(τ)`` (m), what the budget bounds.

        Returns
        -------
        float
        """
        return float(self.task.exact(t)[0].max() + self.task.worst(t).max())

    # -- the ISO 9283 figures at the test cube's poses
    def ap(self, t):
        """Calibrated AP per ISO pose (m): proven bound plus exact quantile.

        Returns
        -------
        (p,) ndarray
        """
        return self.iso_figure.worst(t) + self.iso_figure.exact(t)[0]

    def rp(self, t):
        """RP per ISO pose on the fixed draws (m) and its gradient.

        Returns
        -------
        tuple of ndarray
            ``(p,)`` and ``(p, K)``.
        """
        return rp_with_gradient(self.iso["E"], t)

    def rp_value(self, t):
        """RP per ISO pose on the fixed draws (m), without its gradient (the checks' path).

        Returns
        -------
        (p,) ndarray
        """
        return rp_value(self.iso["E"], t)

    def _check_iso_lower(self):
        lo = self.lo
        if self.AP is not None and self.ap(lo).max() > self.AP:
            raise ValidationError("requirement.iso9283.AP", self.iso["AP"], f"more than {self.ap(lo).max():.3g} m plus the "
                                  "second-order allowance: the calibrated AP with every random source at its lower bound")
        if self.RP is not None and self.rp_value(lo).max() > self.rp_aim:
            raise ValidationError("requirement.iso9283.RP", self.RP, f"more than {self.rp_value(lo).max() / (1 - RP_MARGIN):.3g} m, "
                                  "the RP of the random sources at their lower bounds")

    def iso_ok(self, t) -> bool:
        """The ISO figures (if any) hold at ``τ``.

        Returns
        -------
        bool
        """
        if self.iso is None:
            return True
        if self.AP is not None and not self.iso_figure.within(t, self.AP - self.iso_figure.worst(t)):
            return False                # AP_i = w_i + q_i <= AP at every ISO pose
        return self.RP is None or self.rp_value(t).max() <= self.rp_aim

    # -- what every allocator is judged by
    def ok(self, t) -> bool:
        """The design holds the budget (exact quantile) and the ISO figures.

        Returns
        -------
        bool
        """
        # max q_i + max w_i <= budget: every q_i within budget - max w_i (no quantile solved)
        return self.task.within(t, self.budget - self.task.worst(t).max()) and self.iso_ok(t)

    def cost(self, t) -> float:
        """``Σ_k c_k(τ_k)`` (cost units).

        Returns
        -------
        float
        """
        return float(sum(c.cost(v) for c, v in zip(self.costs, t)))

    def onto_boundary(self, t) -> np.ndarray:
        """The design ``clip(s τ, lower, upper)`` with the largest common factor ``s`` that holds the budget (40-step
        bisection in log s, to 1e-11 of the factor's range; every term is non-decreasing along the ray). Every tolerance at its lower bound when
        even that misses (judged not feasible by :meth:`ok`); at its upper bound when that holds.

        Returns
        -------
        (K,) ndarray
        """
        t = np.asarray(t, float)
        a, b = np.log((self.lo / t).min()), np.log((self.hi / t).max())
        at = lambda ls: np.clip(np.exp(ls) * t, self.lo, self.hi)        # noqa: E731
        if self.ok(at(b)):
            return at(b)
        if not self.ok(at(a)):
            return at(a)
        for _ in range(40):
            mid = 0.5 * (a + b)
            a, b = (mid, b) if self.ok(at(mid)) else (a, mid)
        return at(a)

    def report(self, t) -> dict:
        """The ISO figures of a design (SI) and what is proven (the block's ``iso``).

        Returns
        -------
        dict
            ``AP``, ``AP_worst_case``, ``AP_quantile``, ``RP`` per pose, ``AP_budget``, ``RP_aim``, ``proven``,
            ``active``.
        """
        w, q = self.iso_figure.worst(t), self.iso_figure.exact(t)[0]
        rp = self.rp_value(t)
        return {"AP": (w + q).tolist(), "AP_worst_case": w.tolist(), "AP_quantile": q.tolist(), "RP": rp.tolist(),
                "AP_budget": self.AP, "RP_aim": self.rp_aim,
                "proven": "AP: the systematic residual and the lost motion's offset, a proven bound (grid / cos δ, convex in "
                          "the tolerances), plus the exact quantile of the fit's error (normal: noise and random sources "
                          "through the identification) at the plan's level, less the second-order allowance of the task "
                          "poses; RP: sampled on fixed draws (not convex in general), aimed 1.5 % below the requirement",
                "active": {"AP": self.AP is not None and bool((w + q).max() >= 0.995 * self.AP),
                           "RP": self.RP is not None and bool(rp.max() >= 0.995 * self.rp_aim)}}
