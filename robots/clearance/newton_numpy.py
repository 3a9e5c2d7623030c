"""One barrier-Newton iteration and the path predictor of the support-function solver, with
batched NumPy operations: the reference of the compiled kernels (:mod:`evotol.robots.clearance.newton_kernel`)
and the iteration used without numba (``EngineOptions(kernel=False)``).

:func:`evotol.robots.clearance.support.solve_support` (its docstring has the method) minimises per
problem the reduced log barrier ``F(mu) = sum_c q_c - log(1 + q_c)``,
``q_c = sqrt(1 + tau^2 ||y_c||^2)``, ``y = a + B mu``: gradient ``tau B^T sigma`` and Hessian
``B^T W B - sum_disks G_c G_c^T`` assembled per column group of ``B``, the damped Newton step
with a backtracking line search, and at a centred point the tangent predictor to the next
``tau``.
"""
from __future__ import annotations

import numpy as np

from evotol.robots.clearance.certificate import true_dual
from evotol.robots.clearance.newton_kernel import LINE_SEARCH


def _barrier_terms(Y: np.ndarray, nd: int, tau: np.ndarray):
    """Cone-wise pieces of the reduced log barrier at y (see solve_support)."""
    K = Y.shape[0]
    Yd = Y[:, :2 * nd].reshape(K, nd, 2)
    Yi = Y[:, 2 * nd:]
    rd = np.sqrt((Yd ** 2).sum(-1))
    tc = tau[:, None]
    qd = np.sqrt(1.0 + (tc * rd) ** 2)           # = tau t - 1
    qi = np.sqrt(1.0 + (tc * Yi) ** 2)
    td = (1.0 + qd) / tc
    ti = (1.0 + qi) / tc
    return Yd, Yi, td, ti, qd, qi


def _group_newton(sig, wrow, Yd, cd, dr, ir, dcone, Bgd, Bgi, k):
    """Gradient part ``B_g^T sigma`` and Hessian ``B_g^T W B_g - G^T G`` of one column group
    (see :func:`solve_support`); the disk terms ``G_c = c_c y_c^T B_c`` are formed elementwise
    (a (1 x 2) @ (2 x s) product per disk would be one BLAS call each)."""
    gg = (sig[:, None, dr] @ Bgd)[:, 0, :] + (sig[:, None, ir] @ Bgi)[:, 0, :]
    Hg = np.swapaxes(Bgd * wrow[:, dr, None], 1, 2) @ Bgd + np.swapaxes(Bgi * wrow[:, ir, None], 1, 2) @ Bgi
    ndg = dcone.stop - dcone.start
    if ndg:
        B4 = Bgd.reshape(k, ndg, 2, -1)
        Y = Yd[:, dcone]
        Gd = (Y[:, :, 0, None] * B4[:, :, 0] + Y[:, :, 1, None] * B4[:, :, 1]) * cd[:, dcone, None]
        Hg -= np.swapaxes(Gd, 1, 2) @ Gd
    return gg, Hg


def _barrier_value(Y: np.ndarray, nd: int, tau: np.ndarray) -> np.ndarray:
    """Reduced barrier sum_c q_c - log(1 + q_c), q_c = sqrt(1 + tau^2 |y_c|^2); Y (k, T, R), tau (k,)."""
    k, T = Y.shape[:2]
    t2 = (tau ** 2)[:, None, None]
    qd = np.sqrt(1.0 + t2 * (Y[..., :2 * nd].reshape(k, T, nd, 2) ** 2).sum(-1))
    qi = np.sqrt(1.0 + t2 * Y[..., 2 * nd:] ** 2)
    return (qd - np.log1p(qd)).sum(-1) + (qi - np.log1p(qi)).sum(-1)


def _numpy_iteration(wY, wmu, wtau, nd, R, m, grows, gB, dense, want_dual):
    """One barrier-Newton iteration with batched NumPy operations (the reference for
    :mod:`evotol.robots.clearance.newton_kernel`, used when numba is unavailable); returns
    ``(H, lam2, mu, Y, dual)``."""
    k = len(wY)
    diag = np.arange(m)
    Yd, Yi, td, ti, qd, qi = _barrier_terms(wY, nd, wtau)
    tc = wtau[:, None]
    sig = np.concatenate([(Yd / td[..., None]).reshape(k, 2 * nd), Yi / ti], axis=1)
    wd = tc / td
    wi = (tc / ti) * (1.0 - tc * Yi ** 2 / (ti * qi))
    wrow = np.concatenate([np.repeat(wd, 2, axis=1), wi], axis=1)
    cd = np.sqrt(tc ** 2 / (td ** 2 * qd)) if nd else None
    if dense:                      # one group over every column: no scatter (the IRSBot-2 distal module)
        (dr, ir, cols, dcone), (Bgd, Bgi) = grows[0], gB[0]
        g, H = _group_newton(sig, wrow, Yd, cd, dr, ir, dcone, Bgd, Bgi, k)
    else:
        g = np.zeros((k, m))
        H = np.zeros((k, m, m))
        for (dr, ir, cols, dcone), (Bgd, Bgi) in zip(grows, gB):
            gg, Hg = _group_newton(sig, wrow, Yd, cd, dr, ir, dcone, Bgd, Bgi, k)
            g[:, cols] += gg
            H[:, cols[:, None], cols[None, :]] += Hg
    g *= tc
    H[:, diag, diag] += ((np.trace(H, axis1=1, axis2=2) / m + 1e-300) * 1e-14)[:, None]
    try:
        d = -np.linalg.solve(H, g[..., None])[..., 0]
    except np.linalg.LinAlgError:
        d = -(np.linalg.pinv(H, hermitian=True) @ g[..., None])[..., 0]
    lam2 = np.maximum(-(g * d).sum(-1), 0.0)
    lam = np.sqrt(lam2)
    BD = np.zeros((k, R))
    for (dr, ir, cols, _), (Bgd, Bgi) in zip(grows, gB):
        dc = d[:, cols, None]
        BD[:, dr] = (Bgd @ dc)[..., 0]
        BD[:, ir] = (Bgi @ dc)[..., 0]
    # backtracking line search on the reduced barrier F = sum_c q_c - log(1 + q_c),
    # q_c = sqrt(1 + tau^2 |y_c|^2); never shorter than the damped step 1/(1+lambda), which
    # self-concordance guarantees to decrease F
    damped = np.where(lam > 0.25, 1.0 / (1.0 + lam), 1.0)
    step = damped.copy()
    bi = np.nonzero(lam > 0.25)[0]
    if bi.size:
        # F at the current point from the Newton pieces already computed (no second evaluation)
        F0 = (qd[bi] - np.log1p(qd[bi])).sum(-1) + (qi[bi] - np.log1p(qi[bi])).sum(-1)
        pending = np.ones(bi.size, bool)
        for t in LINE_SEARCH:              # progressive backtracking: most problems accept t = 1
            if t <= 0 or not pending.any():
                break
            pi = bi[pending]
            Ft = _barrier_value((wY[pi] + t * BD[pi])[:, None, :], nd, wtau[pi])[:, 0]
            ok = Ft <= F0[pending] - 0.1 * t * lam2[pi]
            acc = np.nonzero(pending)[0][ok]
            step[bi[acc]] = np.maximum(t, damped[bi[acc]])
            pending[acc] = False
    wmu = wmu + step[:, None] * d
    wY = wY + step[:, None] * BD
    # every iterate is dual feasible: its value is a certified upper bound (weak duality)
    up_it = true_dual(wY, nd) if want_dual else None
    return H, lam2, wmu, wY, up_it


def _numpy_predictor(Yc, Ydc, Yic, Bc, Hc, tcen, tnew, cand, nd, wmu, wY, centred):
    """The path predictor with batched NumPy (reference of ``newton_kernel.predict_centred``):
    in place on ``wmu``, ``wY`` at the rows ``centred``."""
    tc2 = tcen[:, None]
    rdc = np.sqrt((Ydc ** 2).sum(-1))
    qdc, qic = np.sqrt(1 + (tc2 * rdc) ** 2), np.sqrt(1 + (tc2 * Yic) ** 2)
    cfd = (2 * tc2 * (1 + qdc) - tc2 ** 3 * rdc ** 2 / qdc) / (1 + qdc) ** 2
    cfi = (2 * tc2 * (1 + qic) - tc2 ** 3 * Yic ** 2 / qic) / (1 + qic) ** 2
    dY = np.concatenate([(Ydc * cfd[..., None]).reshape(len(tcen), 2 * nd), Yic * cfi], axis=1)
    dg = (dY[:, None, :] @ Bc)[:, 0, :]
    try:
        dmu = -np.linalg.solve(Hc, dg[..., None])[..., 0] * (tnew - tcen)[:, None]
    except np.linalg.LinAlgError:
        return
    dYp = (Bc @ dmu[..., None])[..., 0]
    trial = Yc[:, None, :] + cand[:, :, None] * dYp[:, None, :]
    Fp = _barrier_value(trial, nd, tnew)
    best = np.argmin(Fp, axis=1)
    sc = cand[np.arange(len(best)), best]
    wmu[centred] = wmu[centred] + sc[:, None] * dmu
    wY[centred] = Yc + sc[:, None] * dYp
