"""The certified optimum of a stack -- one error direction at one pose -- by a one-dimensional dual search.

A stack's requirement (a gap ``g = Σ a_j x_j`` within its limits; any problem whose every source
moves the error along one direction ``e`` at one pose) is one or two affine rows of the tolerances,
and its cost is separable::

    min Σ_j c_j(t_j)  s.t.  worst case:  r_k·t + r0_k <= 1   (k = +e, −e: the two sides of the gap),
                            RSS:         b·t² <= 1,            lo_j <= t_j <= hi_j,

with ``r_k`` the support row of the problem's own worst-case measure in direction ``±e``
(:meth:`ToleranceProblem.support_row`: ``Σ|a_j| t_j / L`` for a centred zone; an asymmetric zone
``[−minus_j t_j, plus_j t_j]`` gives each side its own coefficients and constant) and ``b`` the RSS
row (:class:`evotol.measures.constraints.ConstraintRows`). For a multiplier λ >= 0 of one row the
Lagrangian separates (Boyd & Vandenberghe, *Convex Optimization*, 2004, §5.5.5 and Example 5.2,
"water-filling"): each tolerance minimises ``c_j(t) + λ g_j(t)`` on ``[lo_j, hi_j]``, one
convex scalar problem whose derivative ``c_j'(t) + λ g_j'(t)`` is increasing, solved by safeguarded
Newton steps (bisection in ``log t`` when a step leaves the bracket) for every source at once
(vectorised over the sources that share a cost model). The row's value at that minimiser falls as
λ grows; ``scipy.optimize.brentq`` on ``log λ`` finds the λ at which the
row is active, or λ = 0 when every tolerance at its upper bound already meets it. Two rows (the two
sides of an asymmetric worst case): the row the other's optimum violates gets its multiplier by an
outer search whose every step solves the inner one (the partially maximised dual is concave, its
derivative the outer row's value minus 1, Danskin's theorem), so the KKT conditions of both hold.

Certificate: the dual value ``q(λ) = Σ_j min_t [c_j(t) + Σ_k λ_k g_jk(t)] + Σ_k λ_k (r0_k − 1)`` is a
proven lower bound on the optimum for any λ >= 0 (weak duality); ``gap = (cost − q)/cost``. The KKT
residual is the relative norm of ``c_j'(t_j) + Σ_k λ_k ∂g_k/∂t_j`` over the tolerances strictly inside
their bounds (with no active row, ``|∇c|·|t| / c`` over them, as
:func:`evotol.allocators.optimum.certificate`). The design is then held to the feasibility rule and
wrapped as every optimum is (:mod:`evotol.allocators.optimum`).

Used by :func:`evotol.allocators.optimum.allocate_optimum` for least cost at the requirement when
:func:`stack_rows` finds the structure (no shared tolerances, no clearances, one pose, one
component, one error direction); any other problem goes to the cutting planes. Costs: the number of
brentq steps (about 15 for one row, 15² for two) times a vectorised Newton solve (a few steps) over
the sources, without SLSQP's dense O(n³) steps: at 5 000 dimensions the whole optimum takes 0.5 s of
CPU (1.2 s with both sides of an asymmetric stack active), most of it the proven evaluation of the
result; SLSQP took 16-131 s at 1 000 (``benchmarks/bench_stack.py``).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.optimize import brentq

from evotol.core.problem import ToleranceProblem
from evotol.measures.constraints import ConstraintRows

#: bisections of log t that reach any tolerance to the spacing of doubles (ln(hi/lo) / 2^60); Newton's
#: steps take fewer, the cap allows these plus 40
_HALVINGS = 60


@dataclass(frozen=True)
class StackRows:
    """The rows of a stack's requirement over its free tolerances (module docstring).

    Parameters
    ----------
    rows : numpy.ndarray, (n_rows, n_free)
        Coefficients per free tolerance: ``r_k`` (worst case, 1/m) or ``b`` (RSS, 1/m²).
    const : numpy.ndarray, (n_rows,)
        Constants of the rows (the locked tolerances' part and the offsets; dimensionless).
    power : int
        1 for the worst-case rows ``r·t + r0``, 2 for the RSS row ``b·t² + b0``.
    index : numpy.ndarray, (n_free,)
        Source index of each free tolerance.
    """

    rows: np.ndarray
    const: np.ndarray
    power: int
    index: np.ndarray

    def value(self, t: np.ndarray) -> np.ndarray:
        """Row values at free tolerances t (n_free,) (dimensionless; <= 1 meets the requirement).

        Parameters
        ----------
        t : numpy.ndarray, (n_free,)
            Free tolerances (m or rad).

        Returns
        -------
        numpy.ndarray, (n_rows,)
            ``r_k·t + r0_k`` or ``b·t² + b0``.
        """
        return self.rows @ t ** self.power + self.const


def stack_rows(problem: ToleranceProblem) -> StackRows | None:
    """The exact rows of a problem whose errors lie along one direction at one pose, or None.

    Parameters
    ----------
    problem : ToleranceProblem
        A ``worst_case`` or ``rss`` problem.

    Returns
    -------
    StackRows or None
        None unless: no clearances, no shared tolerances, one pose, one constrained component, every
        free source with a cost, and (worst case) every source's error along one direction ``e``.
    """
    if problem.clearances is not None or problem.n_poses != 1 or len(problem.components) != 1:
        return None
    free = np.flatnonzero(problem.free)
    if free.size != int((~problem.locked).sum()) or free.size == 0 or np.any(problem.cost_weight[free] != 1):
        return None                                   # shared tolerances: a variable is not one source
    comp, lim = problem.components[0]
    if problem.requirement.measure == "rss":
        if problem.asymmetric:
            return None
        B = ConstraintRows(problem).B
        if B.shape[0] != 1:
            return None
        return StackRows(B[:, free], problem.locked_part(B, 2), 2, free)
    if problem.requirement.measure != "worst_case":
        return None
    M = np.concatenate([b[0] for b in problem.blocks[comp]], axis=1)      # (3, Σ dim): every error column
    _, s, vt = np.linalg.svd(M @ M.T)
    if s[0] <= 0 or s[1] > 1e-24 * s[0]:
        return None                                                       # not one direction: a robot
    e = vt[0]
    signs = (1.0, -1.0) if problem.asymmetric else (1.0,)
    rows, const = [], []
    for sign in signs:
        r, r0 = problem.support_row(comp, 0, sign * e)
        rows.append(r / lim)
        const.append((r0 + float(problem.locked_part(r[None], 1)[0])) / lim)
    R = np.array(rows)
    if len(rows) == 2 and np.allclose(R[0], R[1], rtol=0, atol=0) and const[0] == const[1]:
        R, const = R[:1], const[:1]
    return StackRows(R[:, free], np.array(const), 1, free)


class _Inner:
    """``argmin_t c_j(t) + w_j g_j(t)`` on ``[lo_j, hi_j]`` for every free tolerance, vectorised over the
    sources that share a cost model (one NumPy call per model and halving)."""

    def __init__(self, problem: ToleranceProblem, index: np.ndarray, power: int):
        self.lo, self.hi, self.power = problem.lower[index], problem.upper[index], power
        groups: dict = {}
        for k, j in enumerate(index):
            tol = problem.tolerances[problem.names[j]]
            key = (id(tol.cost), tol.width_factor)     # the same model object: a compound model's p says too little
            groups.setdefault(key, (tol, []))[1].append(k)
        self.groups = [(tol, np.array(ks)) for tol, ks in groups.values()]

    def _each(self, t: np.ndarray, order: int) -> np.ndarray:
        out = np.empty_like(t)
        for tol, ks in self.groups:
            w = tol.width_factor
            if order == 0:
                out[ks] = tol.cost_of(t[ks])
            elif order == 1:
                out[ks] = tol.dcost_of(t[ks])
            else:
                out[ks] = w * w * tol.cost.d2cost(w * t[ks])
        return out

    def cost(self, t: np.ndarray) -> np.ndarray:
        return self._each(t, 0)

    def dcost(self, t: np.ndarray) -> np.ndarray:
        return self._each(t, 1)

    def argmin(self, w: np.ndarray, start: np.ndarray | None = None) -> np.ndarray:
        """The minimisers for row weights ``w = Σ_k λ_k r_k`` (per free tolerance): Newton's method on
        the increasing slope ``c'(t) + w p t^(p−1)``, kept inside a bracket that every step narrows
        (a step leaving it is replaced by the bracket's geometric midpoint, a bisection in log t).

        Parameters
        ----------
        w : numpy.ndarray, (n_free,)
            Weight of each tolerance's row term (cost units per unit of ``g_j``).
        start : numpy.ndarray, optional
            First guess (the last λ's minimisers).

        Returns
        -------
        numpy.ndarray, (n_free,)
            The minimisers (m or rad).
        """
        p = self.power

        def slope(t):
            return self.dcost(t) + w * p * t ** (p - 1)

        a, b = self.lo.copy(), self.hi.copy()
        done = (slope(a) >= 0) | (slope(b) <= 0)          # the minimiser is a bound: nothing to iterate
        t = np.sqrt(a * b) if start is None else np.clip(start, a, b)
        for _ in range(_HALVINGS + 40):
            s = slope(t)
            neg = s < 0
            a, b = np.where(neg, t, a), np.where(neg, b, t)
            curv = self._each(t, 2) + (w * p * (p - 1) * t ** (p - 2) if p > 1 else 0.0)
            with np.errstate(divide="ignore", invalid="ignore"):
                step = s / curv
            # a Newton step below 1e-10 t leaves an error of order (1e-10)² t (1e-15 t with a finite-difference
            # curvature): take it and stop; a step that leaves the bracket is a bisection of log t instead
            last = np.isfinite(step) & (np.abs(step) <= 1e-10 * t)
            tn = t - step
            bad = ~((tn > a) & (tn < b)) | ~np.isfinite(tn)
            tn = np.where(last, np.clip(tn, self.lo, self.hi), np.where(bad, np.sqrt(a * b), tn))
            t = np.where(done, t, tn)
            done = done | last | (b - a <= 4 * np.finfo(float).eps * b)
            if done.all():
                break
        t = np.where(slope(self.lo) >= 0, self.lo, t)
        return np.where(slope(self.hi) <= 0, self.hi, t)


def _root_lambda(phi, scale: float) -> float:
    """The λ >= 0 with ``phi(λ) = 0`` for a decreasing ``phi`` (0 when ``phi(0) <= 0``): a bracket by
    factors of 4 around ``scale``, then brentq on log λ."""
    if phi(0.0) <= 0:
        return 0.0
    lo = hi = scale
    while phi(hi) > 0:
        lo, hi = hi, hi * 4.0
        if hi > scale * 1e80:
            return hi                      # every tolerance at its lower bound: the caller's feasibility check refuses
    while phi(lo) <= 0:
        lo /= 4.0
        if lo < scale * 1e-80:
            return 0.0
    x = brentq(lambda s: phi(np.exp(s)), np.log(lo), np.log(hi), xtol=1e-15, rtol=4 * np.finfo(float).eps, maxiter=200)
    return float(np.exp(x))


def dual_search(problem: ToleranceProblem, rows: StackRows) -> dict:
    """The optimum over the free tolerances of a stack, its multipliers and certificate (module docstring).

    Parameters
    ----------
    problem : ToleranceProblem
        The problem (costs and bounds of the free tolerances).
    rows : StackRows
        Its rows (:func:`stack_rows`).

    Returns
    -------
    dict
        ``t`` (free tolerances, m or rad), ``lam`` (multipliers, cost units), ``lower_bound`` (q(λ),
        cost units, the locked tolerances' cost included), ``kkt_residual`` (relative) and
        ``active_rows``.
    """
    inner = _Inner(problem, rows.index, rows.power)
    R, r0 = rows.rows, rows.const
    t_mid = np.sqrt(inner.lo * inner.hi)
    g_mid = R @ (rows.power * t_mid ** rows.power)
    scale = float(np.abs(inner.dcost(t_mid)) @ t_mid) / max(float(np.max(g_mid)), 1e-300)
    if not (np.isfinite(scale) and scale > 0):      # flat costs at the middle (a loss term's minimum): any start
        scale = 1.0

    last = [None]

    def solve(lam: np.ndarray) -> np.ndarray:
        last[0] = inner.argmin(lam @ R, last[0])
        return last[0]

    def with_row(k_free: int, lam_fixed: np.ndarray) -> np.ndarray:
        """Multipliers with row ``k_free`` active (or zero), the others fixed."""
        def phi(x):
            lam = lam_fixed.copy()
            lam[k_free] = x
            return float(rows.value(solve(lam))[k_free]) - 1.0
        lam = lam_fixed.copy()
        lam[k_free] = _root_lambda(phi, scale)
        return lam

    n_rows = R.shape[0]
    lam = with_row(0, np.zeros(n_rows))
    if n_rows == 2 and rows.value(solve(lam))[1] > 1.0 + 1e-13:
        lam = with_row(1, np.zeros(2))
        if rows.value(solve(lam))[0] > 1.0 + 1e-13:  # both sides active: the outer search on row 0's multiplier
            def phi0(x):
                return float(rows.value(solve(with_row(1, np.array([x, 0.0]))))[0]) - 1.0
            lam = with_row(1, np.array([_root_lambda(phi0, scale), 0.0]))
    t = solve(lam)
    lower = float(inner.cost(t).sum() + lam @ (rows.value(t) - 1.0))
    grad = inner.dcost(t) + (lam @ R) * rows.power * t ** (rows.power - 1)
    interior = (t > inner.lo * (1 + 1e-9)) & (t < inner.hi * (1 - 1e-9))
    if np.any(lam > 0):
        ref = np.linalg.norm(inner.dcost(t)[interior])
        kkt = float(np.linalg.norm(grad[interior]) / ref) if ref > 0 else 0.0
    else:       # no active row (a cost with a loss term has its optimum inside): |∇c|·|t| / c, as the cutting planes
        kkt = float(np.linalg.norm(grad[interior]) * np.linalg.norm(t[interior]) / max(float(inner.cost(t).sum()), 1e-300))
    return {"t": t, "lam": lam, "lower_bound": lower, "kkt_residual": kkt, "active_rows": int(np.sum(lam > 0))}
