"""Branch and bound over unit directions: the largest norm of the consistent error twists of one
decoupled block (Deng 2012 eqs. III.26-III.27), max_|u|=1 h(u) with h the support function solved
per direction by :mod:`evotol.robots.clearance.support`, patches bounded by :mod:`evotol.robots.clearance.patches`
(method in :mod:`evotol.robots.clearance.maxerror`). Settings come in one
:class:`~evotol.robots.clearance.options.EngineOptions`; the work done is returned with the result.

The parameters several definitions of this module share are described once, here.

Parameters
----------
case : (n,) int ndarray
    Case of each problem.
u : (n, k) ndarray
    Directions.
mu : (n, m) ndarray
    Dual points.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from evotol.robots.clearance.certificate import true_dual
from evotol.robots.clearance.options import DEFAULT, EngineOptions
from evotol.robots.clearance.patches import children, initial_patches, interpolated_bound, normalise, patch_bound
from evotol.robots.clearance.support import solve_support


@dataclass
class NormMaximum:
    """max ||Ct sigma|| of every case: attained value, certified bound, attaining scaled screws,
    and the work done (support problems solved, Newton iterations summed over problems).

    Parameters
    ----------
    lower : (K,) ndarray
        Attained norm per case (units of the target: m or rad).
    upper : (K,) ndarray
        Certified upper bound per case, same units.
    sigma : (K, R) ndarray
        Scaled screws (dimensionless, in the unit cones) attaining ``lower``.
    n_newton : int, optional
        Newton iterations summed over the problems (default 0).
    """

    lower: np.ndarray      # (K,) attained norm
    upper: np.ndarray      # (K,) certified bound
    sigma: np.ndarray      # (K, R) attaining scaled screws
    n_solves: int = 0
    n_newton: int = 0


class SupportEvaluator:
    """Support values for (case, direction) pairs; keeps the best attained point of each case.

    ``exact`` solves the convex problem (certified upper value + feasible primal point);
    ``cheap`` only evaluates the dual objective at a given ``mu`` -- still a certified upper
    bound of the support value (weak duality), at the cost of one matrix-vector product.

    Parameters
    ----------
    Ct : (K, k, R) ndarray
        Scaled target rows of each case (m or rad per unit scaled screw).
    Bt : (K, R, m) ndarray
        Scaled loop-equation maps.
    gi : (K, m, m) ndarray
        ``pinv(Bt^T Bt)`` of each case.
    nd : int
        Number of disk cones (rows ``0 .. 2 nd - 1`` in pairs; intervals after).
    tol_solve : float
        Default relative precision of each support solve.
    groups : tuple or None, optional
        Block sparsity of ``Bt`` (:attr:`evotol.robots.clearance.model.PoseMaps.groups`); None: dense.
    """

    def __init__(self, Ct, Bt, gi, nd, tol_solve, groups=None, options: EngineOptions = DEFAULT):
        self.Ct, self.Bt, self.gi, self.nd, self.groups, self.options = Ct, Bt, gi, nd, groups, options
        K, k, R = Ct.shape
        self.best = np.zeros(K)
        self.sigma = np.zeros((K, R))
        self.mu = np.zeros((K, Bt.shape[-1]))
        self.tol_solve = tol_solve
        self.n_solves = 0
        self.n_newton = 0
        self.n_cheap = 0

    def exact(self, case, u, mu0=None, scale=None, rtol=None, stop_below=None):
        """Solve the support problems of cases ``case`` in directions ``u``; record improved points.

        Parameters
        ----------
        case : (n,) int ndarray
            Case of each problem (repeats allowed).
        u : (n, k) ndarray
            Unit directions.
        mu0 : (n, m) ndarray or None, optional
            Warm-start dual points; the barrier then starts at their certified gap.
        scale : (n,) ndarray or None, optional
            Value scale: the absolute gap target is ``rtol * scale`` (None: 0, relative only).
        rtol : float or None, optional
            Relative gap target (None: ``tol_solve``).
        stop_below : (n,) ndarray or None, optional
            Stop a problem once its certified upper bound is below this value.

        Returns
        -------
        upper : (n,) ndarray
            Certified upper values of the support function.
        mu : (n, m) ndarray
            Final dual points (warm starts).
        """
        Ct, Bt = self.Ct[case], self.Bt[case]          # gathered once (the largest copies of a solve)
        a = np.einsum("kqr,kq->kr", Ct, u)
        rtol = self.tol_solve if rtol is None else rtol
        tol = 0.0 if scale is None else rtol * scale
        gap0 = None
        if mu0 is not None:
            # start the barrier at the certified gap of the warm start: f(mu0) - u^T x_best
            f0 = true_dual(a + (Bt @ mu0[..., None])[..., 0], self.nd)
            lo = np.einsum("kq,kq->k", u, np.einsum("kqr,kr->kq", Ct, self.sigma[case]))
            gap0 = np.maximum(f0 - np.maximum(lo, 0.0), np.maximum(tol, rtol * f0))
        res = solve_support(a, Bt, self.nd, tol=tol, rtol=rtol, mu0=mu0, gap0=gap0, gram_inv=self.gi[case],
                            groups=self.groups, stop_below=stop_below, options=self.options)
        self.n_solves += len(case)
        self.n_newton += res.newton
        norms = np.linalg.norm(np.einsum("kqr,kr->kq", Ct, res.sigma), axis=-1)
        order = np.argsort(norms)          # last write wins -> the largest per case
        c_sorted = case[order]
        better = norms[order] > self.best[c_sorted]
        cs, idx = c_sorted[better], order[better]
        self.best[cs] = norms[idx]
        self.sigma[cs] = res.sigma[idx]
        self.mu[cs] = res.mu[idx]
        return res.upper, res.mu

    def cheap(self, case, u, mu):
        """Dual objective at given dual points: a certified upper bound without solving.

        Returns
        -------
        (n,) ndarray
            ``f(mu) = sum_c ||y_c||`` with ``y = Ct^T u + Bt mu`` (upper bounds of ``h(u)``).
        """
        self.n_cheap += len(case)
        return true_dual(self.dual_vectors(case, u, mu), self.nd)

    def dual_vectors(self, case, u, mu):
        """``y = D C^T u + D B mu`` (K, R): the cone-wise vectors whose norms sum to the dual bound.

        Returns
        -------
        (n, R) ndarray
            The vectors ``y``.
        """
        return np.einsum("kqr,kq->kr", self.Ct[case], u) + (self.Bt[case] @ mu[..., None])[..., 0]

    def polish(self, n_iter: int = 2, rtol: float | None = None, cases=None):
        """Local ascent from the best attained point: ``u <- x / ||x||``, ``x <- argmax u^T x``; monotone
        (``||x_new|| >= u^T x_new = h(u) >= u^T x_old = ||x_old||``). Tightens the attained value.

        Parameters
        ----------
        n_iter : int, optional
            Ascent steps (default 2).
        rtol : float or None, optional
            Relative precision of the solves (None: ``options.polish_rtol``).
        cases : (n,) int ndarray or None, optional
            Cases to polish (None: all).
        """
        cases = np.arange(len(self.best)) if cases is None else cases
        rtol = self.options.polish_rtol if rtol is None else rtol
        for _ in range(n_iter):
            x = np.einsum("kqr,kr->kq", self.Ct[cases], self.sigma[cases])
            nrm = np.linalg.norm(x, axis=-1)
            ok = nrm > 0
            if not ok.any():
                break
            c = cases[ok]
            self.exact(c, x[ok] / nrm[ok, None], mu0=self.mu[c], scale=nrm[ok], rtol=rtol)


def maximise_norm(Ct, Bt, gi, nd, *, tol=1e-3, tol_solve=1e-5, max_rounds=40, groups=None,
                  options: EngineOptions = DEFAULT) -> NormMaximum:
    """max ||Ct sigma|| over feasible scaled screws for every case, with a certified bound.

    Parameters
    ----------
    Ct : ndarray, shape (K, k, R)
        Scaled target rows of each case (k in 1..3 error components).
    Bt : ndarray, shape (K, R, m)
        Scaled loop-equation maps; ``gi``: their ``pinv(Bt^T Bt)`` (K, m, m).
    gi : ndarray, shape (K, m, m)
        ``pinv(Bt^T Bt)`` of each case.
    nd : int
        Number of disk cones (rows 0 .. 2 nd - 1 in pairs; intervals after).
    tol : float
        Relative gap between the attained value and the certified bound (default 1e-3).
    tol_solve : float
        Relative precision of the support solves at the initial vertices (default 1e-5).
    max_rounds : int
        Most patch-splitting rounds (default 40); patches still alive then enter the upper
        bound with their patch bounds.
    groups : tuple or None
        Block sparsity of ``Bt`` (:attr:`evotol.robots.clearance.model.PoseMaps.groups`); None: dense.
    options : EngineOptions
        The engine's settings (:mod:`evotol.robots.clearance.options`).

    Returns
    -------
    NormMaximum
        Per case the attained norm, the certified bound (units of ``Ct``: m or rad) and the
        attaining scaled screws.
    """
    K, k, R = Ct.shape
    m = Bt.shape[-1]
    ev = SupportEvaluator(Ct, Bt, gi, nd, tol_solve, groups, options)
    cases = np.arange(K)
    tol_bb = 0.5 * tol
    if k == 1:
        up, _ = ev.exact(cases, np.ones((K, 1)), rtol=1e-9)
        return NormMaximum(ev.best.copy(), np.maximum(up, ev.best), ev.sigma, ev.n_solves, ev.n_newton)
    verts, tri, sign = initial_patches(k, options)
    nv, T = len(verts), len(tri)
    up, mu = ev.exact(np.repeat(cases, nv), np.tile(verts, (K, 1)))
    up, mu = up.reshape(K, nv), mu.reshape(K, nv, m)
    ev.polish(rtol=options.polish_rtol0)
    best_before = ev.best.copy()
    pc = np.repeat(cases, T)                                       # patch -> case
    PU = np.tile(verts[tri] * sign[..., None], (K, 1, 1))         # (P, q, k)
    PH = up[:, tri].reshape(K * T, -1)                             # (P, q) certified upper values
    PM = (mu[:, tri] * sign[None, :, :, None]).reshape(K * T, tri.shape[1], m)
    interp = options.interpolate and m
    n_sub = options.interpolate_arc if k == 2 else options.interpolate
    legacy = options.patch_bound == "legacy"
    if interp:
        PY = ev.dual_vectors(np.repeat(pc, tri.shape[1]), PU.reshape(-1, k), PM.reshape(-1, m)).reshape(PU.shape[:2] + (R,))
    pruned = np.zeros(K)
    q = PU.shape[1]
    for _ in range(max_rounds):
        bound = patch_bound(PU, PH, legacy)
        if interp:        # the finer (costlier) bound only where the vertex bound does not prune
            loose = np.nonzero(bound > ev.best[pc] * (1 + tol_bb))[0]
            bound[loose] = np.minimum(bound[loose], interpolated_bound(PU[loose], PY[loose], nd, n_sub))
        keep = bound > ev.best[pc] * (1 + tol_bb)
        np.maximum.at(pruned, pc[~keep], bound[~keep])
        pc, PU, PH, PM = pc[keep], PU[keep], PH[keep], PM[keep]
        if interp:
            PY = PY[keep]
        if not pc.size:
            break
        if q == 2:
            mids = normalise(PU[:, 0] + PU[:, 1])[:, None]
            mmu = ((PM[:, 0] + PM[:, 1]) / 2)[:, None]
        else:
            mids = normalise(np.stack([PU[:, 0] + PU[:, 1], PU[:, 1] + PU[:, 2], PU[:, 2] + PU[:, 0]], 1))
            mmu = np.stack([PM[:, 0] + PM[:, 1], PM[:, 1] + PM[:, 2], PM[:, 2] + PM[:, 0]], 1) / 2
        e = mids.shape[1]
        key = np.concatenate([np.repeat(pc, e)[:, None].astype(float), np.round(mids.reshape(-1, k), 12)], 1)
        _, first, back = np.unique(key, axis=0, return_index=True, return_inverse=True)
        back = back.ravel()
        uc = np.repeat(pc, e)[first]
        uu = mids.reshape(-1, k)[first]
        um = mmu.reshape(len(pc) * e, m)[first]
        hm = ev.cheap(uc, uu, um)
        need = np.nonzero(hm > ev.best[uc] * (1 + tol_bb))[0]
        if need.size:
            sc = np.maximum(ev.best[uc[need]], 1e-300)
            he, me = ev.exact(uc[need], uu[need], mu0=um[need], scale=sc, rtol=tol_bb / 4,
                              stop_below=sc * (1 - options.stop_below))
            hm[need] = np.minimum(hm[need], he)
            um[need] = me
        if interp:
            ym = ev.dual_vectors(uc, uu, um)[back].reshape(len(pc), e, R)
        hm = hm[back].reshape(len(pc), e)
        mm = um[back].reshape(len(pc), e, m)
        PU, PH, PM = children(PU, mids), children(PH, hm), children(PM, mm)
        if interp:
            PY = children(PY, ym)
        pc = np.tile(pc, 2 if q == 2 else 4)
    alive = np.zeros(K)
    if pc.size:
        ab = patch_bound(PU, PH, legacy)
        if interp:
            ab = np.minimum(ab, interpolated_bound(PU, PY, nd, n_sub))   # the few still alive
        np.maximum.at(alive, pc, ab)
    changed = np.nonzero(ev.best > best_before)[0]
    ev.polish(n_iter=1, cases=np.arange(K))         # final tightening of the attained value
    if changed.size:
        ev.polish(n_iter=1, cases=changed)
    upper = np.maximum.reduce([pruned, alive, ev.best])
    return NormMaximum(ev.best.copy(), upper, ev.sigma, ev.n_solves, ev.n_newton)
