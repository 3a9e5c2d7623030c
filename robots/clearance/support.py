"""Support function of the set of consistent end-effector errors, with a primal-dual certificate.

For one direction ``w`` the largest error component ``h(w) = max w^T C s`` over the screws ``s``
that satisfy the clearance bounds and the loop equations ``B^T s = 0`` is a small convex
problem. In scaled screws ``sigma_c = s_c / Delta_c`` (one unit disk or unit interval per cone)::

    primal   h(w) = max  a^T sigma   s.t.  ||sigma_c|| <= 1,  Bt^T sigma = 0        (a = D C^T w, Bt = D B)
    dual     h(w) = min_mu  f(mu) = sum_c || a_c + Bt_c mu ||                        (mu in R^m)

(``D`` = diag of the bounds). Weak duality makes **every** ``mu`` a certified upper bound
``f(mu) >= h(w)`` and every feasible ``sigma`` a lower bound attained by an explicit set of
screws. The dual is a sum of Euclidean norms in ``m`` variables (``m`` = number of loop
equations: 3 per block for the 5-bar, 18 or 30 for the IRSBot-2). We minimise its smoothing
``f_eps(mu) = sum_c sqrt(||a_c + Bt_c mu||^2 + eps^2)`` by damped Newton steps while ``eps``
shrinks (path following); the gradient of ``f_eps`` is ``Bt^T sigma`` with
``sigma_c = y_c / sqrt(||y_c||^2 + eps^2)``, strictly inside the unit cones, so at the smoothed
optimum ``sigma`` is primal feasible and the duality gap is at most ``n_cones * eps``. Any
remaining loop residual is projected out and ``sigma`` is scaled back into the cones before the
lower bound is computed. Everything is batched over problems (poses x directions x bound sets).

With no loop equation (``m = 0``, an open serial chain) the support function is closed form:
``h(w) = sum_c ||a_c||`` (Minkowski sum of the joints' sets).

This module drives the path following (:func:`solve_support`); the certificate's bounds
(dual value, feasible screws) are :mod:`evotol.robots.clearance.certificate`, one Newton iteration is
:mod:`evotol.robots.clearance.newton_kernel` (compiled) or :mod:`evotol.robots.clearance.newton_numpy`.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from evotol.errors import ValidationError
from evotol.robots.clearance import newton_kernel
from evotol.robots.clearance.certificate import _gram_pinv, _project, _project_free, recover_primal, true_dual
from evotol.robots.clearance.newton_numpy import _barrier_terms, _numpy_iteration, _numpy_predictor
from evotol.robots.clearance.options import DEFAULT, EngineOptions

#: predictor scales tried by ``EngineOptions(predictor="legacy")``
_PRED_LEGACY = np.array([1.0, 0.75, 0.5, 0.25, 0.0])


@dataclass
class SupportResult:
    """Certified result of a batch of support-function problems (:func:`solve_support`).

    Values are in the units of ``a`` (the scaled problem: m or rad for a target row scaled by the
    bounds).

    Parameters
    ----------
    upper : (K,) ndarray
        Certified upper bound ``f(mu) >= h(w)`` per problem.
    lower : (K,) ndarray
        ``a^T sigma`` of the feasible ``sigma`` (``<= h(w)``) per problem.
    sigma : (K, R) ndarray
        Feasible scaled screws (``||sigma_c|| <= 1``, loop residual about 1e-13), dimensionless.
    mu : (K, m) ndarray
        Dual points attaining ``upper`` (warm starts).
    iterations : int
        Newton iterations of the batch (the longest problem's count).
    newton : int, optional
        Newton iterations summed over the problems (the work done; default 0).
    """

    upper: np.ndarray   # (K,) certified upper bound f(mu) >= h(w)
    lower: np.ndarray   # (K,) a^T sigma of the feasible sigma (<= h(w))
    sigma: np.ndarray   # (K, R) feasible scaled screws (||sigma_c|| <= 1, loop residual ~ 1e-13)
    mu: np.ndarray      # (K, m) dual variables (warm starts)
    iterations: int
    newton: int = 0     # Newton iterations summed over the problems (the work done)


def _merge_groups(groups):
    """Merge row groups whose columns are a subset of another group's (fewer, larger blocks)."""
    groups = [(np.asarray(d, int), np.asarray(i, int), np.asarray(c, int)) for d, i, c in groups]
    merged = True
    while merged and len(groups) > 1:
        merged = False
        for a_ in range(len(groups)):
            for b_ in range(len(groups)):
                if a_ != b_ and set(groups[a_][2]) <= set(groups[b_][2]):
                    d = np.concatenate([groups[b_][0], groups[a_][0]])
                    i = np.concatenate([groups[b_][1], groups[a_][1]])
                    groups[b_] = (d, i, groups[b_][2])
                    del groups[a_]
                    merged = True
                    break
            if merged:
                break
    return tuple(groups)


def solve_support(a: np.ndarray, B: np.ndarray, nd: int, *, tol: np.ndarray | float, mu0: np.ndarray | None = None,
                  gap0: np.ndarray | float | None = None, max_iter: int = 100, gram_inv: np.ndarray | None = None,
                  growth: float | None = None, rtol: float = 0.0, groups=None, stop_below=None,
                  kernel: bool | None = None, options: EngineOptions = DEFAULT) -> SupportResult:
    """Solve the batched support-function problems (see module docstring).

    a: (K, R) scaled linear terms; B: (K, R, m) scaled loop maps (rows: ``nd`` disks as pairs,
    then intervals); tol: absolute duality-gap target per problem (K,) or scalar; mu0: warm
    start (K, m); rtol: also stop when the gap is below ``rtol * upper``; gap0: barrier gap to start the path from (default 10 % of f(mu0));
    gram_inv: optional precomputed ``pinv(B^T B)`` (K, m, m); groups: optional block sparsity
    of B (:attr:`evotol.robots.clearance.model.PoseMaps.groups`): the Newton systems are then
    assembled group by group; stop_below: (K,) stop as soon as the certified upper bound is below
    this value (enough for a branch-and-bound vertex far from the maximum); kernel: run each
    Newton iteration compiled (:mod:`evotol.robots.clearance.newton_kernel`, default when numba is
    available) or with batched NumPy (``False``; the reference, equal to round-off). A problem
    whose Hessian is exactly singular takes no step in the compiled iteration (its decrement is
    reported as 0, so the path moves on) where NumPy falls back to a pseudo-inverse. options: the
    engine's settings (:class:`evotol.robots.clearance.options.EngineOptions`: centring threshold,
    ``growth``, predictor, ``kernel``); the arguments ``growth`` and ``kernel`` override them.

    Method: the dual ``min_mu sum_c ||y_c||`` (``y = a + B mu``) is written as the SOCP
    ``min sum_c t_c, ||y_c|| <= t_c`` and solved by a primal log-barrier path-following method:
    minimising ``tau sum t_c - sum log(t_c^2 - ||y_c||^2)`` over ``t`` gives in closed form
    ``t_c = (1 + sqrt(1 + tau^2 ||y_c||^2)) / tau``; the reduced function of ``mu`` is
    self-concordant, so damped Newton steps ``mu += d / (1 + lambda)`` converge without a line
    search. On the central path ``sigma_c = y_c / t_c`` is strictly feasible for the primal and
    the duality gap is ``2 n_cones / tau``; ``tau`` grows by ``growth`` each time the Newton
    decrement is small. The certificate (upper, lower) is evaluated exactly at each centring.

    Parameters
    ----------
    a : (K, R) array_like
        Scaled linear terms ``a = D C^T w``.
    B : (K, R, m) ndarray
        Scaled loop maps ``D B`` (rows: ``nd`` disks as pairs, then intervals).
    tol : float or (K,) ndarray
        Absolute duality-gap target per problem (units of ``a``).
    mu0 : (K, m) ndarray or None, optional
        Warm start (None: the least-squares point).
    gap0 : float or (K,) ndarray or None, optional
        Barrier gap to start the path from (None: 10 % of ``f(mu0)``).
    max_iter : int, optional
        Most Newton iterations of the batch (default 100).
    growth : float or None, optional
        Factor of ``tau`` at each centring (None: ``options.growth``).
    rtol : float, optional
        Also stop when the gap is below ``rtol * upper`` (default 0).
    groups : tuple or None, optional
        Block sparsity of ``B`` (:attr:`evotol.robots.clearance.model.PoseMaps.groups`); None: dense.
    stop_below : float or (K,) ndarray or None, optional
        Stop a problem once its certified upper bound is below this value.
    kernel : bool or None, optional
        Compiled (True) or NumPy (False) Newton iteration; None: ``options.kernel``.

    Returns
    -------
    SupportResult
        Per problem the certified ``upper`` and attained ``lower`` values, the feasible scaled
        screws and the dual points. With ``m = 0`` the closed form (``lower = upper``).

    Raises
    ------
    ValidationError
        The compiled iteration required (``kernel=True``, or ``options.kernel=True``) but numba
        not available.
    """
    a = np.asarray(a, float)
    K, R = a.shape
    m = B.shape[-1]
    growth = options.growth if growth is None else float(growth)
    tol = np.broadcast_to(np.asarray(tol, float), (K,)).copy()
    if stop_below is not None:
        stop_below = np.broadcast_to(np.asarray(stop_below, float), (K,))
    n_cones = nd + (R - 2 * nd)
    if m == 0:
        sigma, lower = recover_primal(a, a, B, nd, np.zeros(K))
        return SupportResult(true_dual(a, nd), lower, sigma, np.zeros((K, 0)), 0)
    if gram_inv is None:
        gram_inv = _gram_pinv(B)
    if mu0 is None:       # least-squares start: minimises sum_c |y_c|^2, a good guess for sum_c |y_c|
        mu = -(gram_inv @ (np.swapaxes(B, 1, 2) @ a[..., None]))[..., 0]
    else:
        mu = np.array(mu0, float)
    Y = a + (B @ mu[..., None])[..., 0]
    upper = true_dual(Y, nd)
    g0 = 0.1 * upper if gap0 is None else np.broadcast_to(np.asarray(gap0, float), (K,))
    floor = 1e-13 * np.maximum(upper, 1e-200)        # relative precision floor (no tau overflow)
    target = np.maximum(np.maximum(tol, rtol * upper), floor)
    tau = np.minimum(2.0 * n_cones / np.maximum(g0, floor), 4.0 * n_cones / target)
    sigma = np.zeros((K, R))
    lower = np.full(K, -np.inf)
    lower[upper <= 1e-300] = 0.0                      # all-zero problem: sigma = 0 is optimal
    best_mu = mu.copy()
    if not groups:
        groups = ((np.arange(nd), np.arange(2 * nd, R), np.arange(m)),)
    groups = _merge_groups(groups)
    # permute the cones so that every group's disks and intervals are contiguous (views, no copies)
    dperm = np.concatenate([g[0] for g in groups] + [np.setdiff1d(np.arange(nd), np.concatenate([g[0] for g in groups]))]).astype(int)
    iperm = np.concatenate([g[1] for g in groups] + [np.setdiff1d(np.arange(2 * nd, R), np.concatenate([g[1] for g in groups]))]).astype(int)
    perm = np.concatenate([np.stack([2 * dperm, 2 * dperm + 1], 1).ravel(), iperm]).astype(int)
    inv = np.empty_like(perm)
    inv[perm] = np.arange(R)
    if np.array_equal(perm, np.arange(R)):     # cones already grouped (the IRSBot-2, the 5-bar): no copies
        a, B, Y = np.ascontiguousarray(a), np.ascontiguousarray(B), np.ascontiguousarray(Y)
    else:
        a, B, Y = np.take(a, perm, axis=1), np.take(B, perm, axis=1), np.take(Y, perm, axis=1)   # (C-contiguous copies)
    grows, d0, i0 = [], 0, 2 * nd
    for dcone, irows, cols in groups:
        dn, inn = len(dcone), len(irows)
        grows.append((slice(2 * d0, 2 * d0 + 2 * dn), slice(i0, i0 + inn), np.asarray(cols, int), slice(d0, d0 + dn)))
        d0, i0 = d0 + dn, i0 + inn
    kernel = options.kernel if kernel is None else kernel
    use_kernel = (kernel is None or bool(kernel)) and newton_kernel._kernel() is not None
    if kernel and not use_kernel:
        raise ValidationError("kernel", kernel, "False or None: numba is not available (see evotol.robots.clearance.newton_kernel)")
    if use_kernel:
        # the kernels read B, a and pinv(B^T B) of the original problems through ``idx`` (no copies
        # when the working set shrinks) and each group's block of B from one contiguous array
        kgroups = newton_kernel.group_arrays(grows, nd)
        GB = newton_kernel.group_blocks(B, grows)
        gB = None
    else:   # the NumPy iteration works on each group's rows and columns (copies)
        gB = [(B[:, dr][:, :, cols], B[:, ir][:, :, cols]) for dr, ir, cols, _ in grows]
    # working set (compacted when it shrinks)
    idx = np.arange(K)
    wB, wa, wmu, wtau, wgi, wY = B, a, mu.copy(), tau, gram_inv, Y
    if use_kernel:
        wB = wa = wgi = None           # read through idx
    if np.any(lower >= upper):             # trivial problems leave at once
        keep0 = lower < upper
        idx = idx[keep0]
        wB, wa, wmu, wtau, wgi, wY = (None if x is None else x[keep0] for x in (wB, wa, wmu, wtau, wgi, wY))
        gB = gB and [(x[keep0], y[keep0]) for x, y in gB]
    it = 0
    dense = len(grows) == 1 and np.array_equal(grows[0][2], np.arange(m))
    n_newton = 0
    while idx.size and it < max_iter:
        it += 1
        k = len(idx)
        n_newton += k
        # one damped Newton step with line search on every problem; with ``stop_below`` also the
        # dual value of the new iterate -- every iterate is dual feasible, so its value is a
        # certified upper bound (weak duality), enough to drop a vertex certified below
        # ``stop_below`` before the path is centred
        if use_kernel:
            # the compiled iteration (evotol.robots.clearance.newton_kernel): same steps as the branch below
            H, lam2, up_it, fail = newton_kernel.newton_iterate(wY, wmu, GB, idx, wtau, nd, kgroups, stop_below is not None)
            if stop_below is None:
                up_it = None
        else:
            H, lam2, wmu, wY, up_it = _numpy_iteration(wY, wmu, wtau, nd, R, m, grows, gB, dense, stop_below is not None)
        if up_it is not None:
            better = up_it < upper[idx]
            if better.any():
                upper[idx[better]] = up_it[better]
                best_mu[idx[better]] = wmu[better]
        centred = np.nonzero(lam2 < options.centred)[0]
        if centred.size:
            c_idx = idx[centred]
            Yc = wY[centred]
            up = true_dual(Yc, nd) if up_it is None else up_it[centred]     # (computed above already)
            better = up < upper[c_idx]
            upper[c_idx] = np.where(better, up, upper[c_idx])
            best_mu[c_idx[better]] = wmu[centred[better]]
            tcen = wtau[centred]
            if use_kernel:
                s0, s_new, lo_new = newton_kernel.project_centred(centred, idx, wY, a, B, gram_inv, wtau, nd)
            else:
                Ydc, Yic, tdc, tic, _, _ = _barrier_terms(Yc, nd, tcen)
                s0 = np.concatenate([(Ydc / tdc[..., None]).reshape(len(c_idx), 2 * nd), Yic / tic], axis=1)
                ac, Bc = wa[centred], wB[centred]
                s_new, lo_new = _project(s0, ac, Bc, nd, wgi[centred])
            tgt = np.maximum(np.maximum(tol[c_idx], rtol * upper[c_idx]), floor[c_idx])
            # complementary-slackness repair once the barrier gap is no longer what limits us
            weak = (upper[c_idx] - lo_new > tgt) & (2.0 * n_cones / tcen < 0.2 * (upper[c_idx] - lo_new))
            if weak.any():
                cw = c_idx[weak]
                s2, lo2 = _project_free(s0[weak], Yc[weak], a[cw], B[cw], nd, gram_inv[cw])
                take = lo2 > lo_new[weak]
                sw, lw = s_new[weak], lo_new[weak]
                sw[take], lw[take] = s2[take], lo2[take]
                s_new[weak], lo_new[weak] = sw, lw
            imp = lo_new > lower[c_idx]
            sigma[c_idx[imp]] = s_new[imp]
            lower[c_idx] = np.maximum(lower[c_idx], lo_new)
            wtau = wtau.copy()
            tnew = np.minimum(tcen * growth, 4.0 * n_cones / tgt)
            wtau[centred] = tnew
            # predictor along the central path. Near the optimum mu(tau) ~ mu* + c / tau, so the
            # tangent step (d mu / d tau)(tau_new - tau_old) overshoots the move to the new centre
            # by tau_new / tau_old; scaled by tau_old / tau_new it is the extrapolation of that model
            # (the old choice among 1, .75, .5, .25, 0 took 0.25 at best: a damped Newton step
            # followed every increase of tau). The unscaled point is kept if the barrier is lower there.
            if options.predictor == "legacy":
                cand = np.broadcast_to(_PRED_LEGACY, (len(tcen), len(_PRED_LEGACY)))
            else:
                cand = np.stack([tcen / tnew, np.zeros_like(tcen)], 1)
            if use_kernel:
                newton_kernel.predict_centred(centred, idx, wY, wmu, B, H, tcen, tnew, cand, nd)
            else:
                _numpy_predictor(Yc, Ydc, Yic, Bc, H[centred], tcen, tnew, cand, nd, wmu, wY, centred)
        gap = upper[idx] - lower[idx]
        keep = gap > np.maximum(tol[idx], rtol * upper[idx])
        if stop_below is not None:
            keep &= upper[idx] > stop_below[idx]
        if not keep.all():
            mu[idx] = wmu
            if keep.sum() < 0.8 * len(idx):
                wB, wa, wmu, wtau, wgi, wY = (None if x is None else x[keep] for x in (wB, wa, wmu, wtau, wgi, wY))
                gB = gB and [(x[keep], y[keep]) for x, y in gB]
                idx = idx[keep]
            elif not keep.any():
                idx = idx[keep]
    mu[idx] = wmu if len(wmu) == len(idx) else mu[idx]
    return SupportResult(upper, lower, sigma[:, inv], best_mu, it, n_newton)


def warm_up() -> bool:
    """Compile (or load from numba's cache) all the kernels of :mod:`.newton_kernel` in this process
    by solving one tiny support problem. Called before a pool of worker processes starts: the
    forked workers inherit the kernels instead of each importing numba and loading them (or, on a
    fresh install, compiling them). Returns whether the compiled kernels are available.

    Returns
    -------
    bool
        True when the compiled kernels are available (and now loaded), False when the NumPy
        iteration is used.
    """
    if newton_kernel._kernel() is None:
        return False
    rng = np.random.default_rng(0)
    solve_support(rng.standard_normal((2, 6)), rng.standard_normal((2, 6, 2)), 2, tol=1e-9, kernel=True)
    return True
