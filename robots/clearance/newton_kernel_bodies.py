"""The kernel bodies of the compiled barrier-Newton iteration: plain Python loops over the problems
of a batch, which :mod:`evotol.robots.clearance.newton_kernel` compiles with numba (``cache=True``) and
calls.

:func:`_newton_iterate_py` is one iteration of :func:`evotol.robots.clearance.support.solve_support`
(barrier pieces per cone, gradient and Hessian assembled per column group of ``B``, Newton step by
Cholesky -- :func:`_chol_factor`, :func:`_chol_solve` -- or LU, backtracking line search, update
and the certified dual value); at a centred point :func:`_project_centred_py` gives the feasible
primal point (the certified lower bound) and :func:`_predict_centred_py` the path predictor. The
steps are numbered and derived in :mod:`evotol.robots.clearance.newton_kernel`; the NumPy iteration
(:mod:`evotol.robots.clearance.newton_numpy`) is the reference. Run uncompiled (the Python functions
themselves) they give the same results, slowly.
"""
from __future__ import annotations

import numpy as np


def _chol_factor(H, L, m):
    """Cholesky factor ``L`` (lower) of the leading m x m block of ``H``; False when a pivot is
    not positive (round-off made H indefinite). Rows are taken four at a time: their entries left
    of the four rows' diagonal block are four independent sums computed side by side (each with
    its terms in the textbook order, so the factor is the row-by-row one to the last bit; the
    side-by-side sums take about 60 % of the time of one chain after another at m = 30), then the
    diagonal block row by row."""
    a0 = 0
    while a0 < m:
        nb = min(4, m - a0)
        if nb == 4:
            for b in range(a0):
                v0 = H[a0, b]
                v1 = H[a0 + 1, b]
                v2 = H[a0 + 2, b]
                v3 = H[a0 + 3, b]
                for c in range(b):
                    lb = L[b, c]
                    v0 -= L[a0, c] * lb
                    v1 -= L[a0 + 1, c] * lb
                    v2 -= L[a0 + 2, c] * lb
                    v3 -= L[a0 + 3, c] * lb
                piv = L[b, b]
                L[a0, b] = v0 / piv
                L[a0 + 1, b] = v1 / piv
                L[a0 + 2, b] = v2 / piv
                L[a0 + 3, b] = v3 / piv
        for a in range(a0, a0 + nb):
            for b in range(a0 if nb == 4 else 0, a + 1):
                v = H[a, b]
                for c in range(b):
                    v -= L[a, c] * L[b, c]
                if a == b:
                    if v <= 0.0:
                        return False
                    L[a, a] = np.sqrt(v)
                else:
                    L[a, b] = v / L[b, b]
        a0 += nb
    return True


def _chol_solve(L, rhs, out, m):
    """``out = (L L^T)^{-1} rhs`` by forward and back substitution (``rhs`` is overwritten)."""
    for a in range(m):
        v = rhs[a]
        for c in range(a):
            v -= L[a, c] * rhs[c]
        rhs[a] = v / L[a, a]
    for a in range(m - 1, -1, -1):
        v = rhs[a]
        for c in range(a + 1, m):
            v -= L[c, a] * out[c]
        out[a] = v / L[a, a]


def _newton_iterate_py(Y, mu, GB, rows, tau, nd, gd, gi, gcols, goff, boff, ls, want_dual, H_out, lam2_out, dual_out, fail_out):
    """Kernel body (compiled by numba when available; see :mod:`evotol.robots.clearance.newton_kernel`).

    In place: ``Y`` (k, R), ``mu`` (k, m) updated by the accepted step; ``H_out`` (k, m, m) the
    Hessian at the start point (for the path predictor); ``lam2_out`` (k,) the squared Newton
    decrement; ``dual_out`` (k,) ``sum_c ||y_c||`` after the step (when ``want_dual``);
    ``fail_out`` (k,) 1 where ``H`` is exactly singular (no step; ``lam2`` is reported as 0, so
    the caller treats the point as centred and the barrier path moves on)."""
    k, R = Y.shape
    m = mu.shape[1]
    ng = gd.shape[0]
    smax = 0
    nrmax = 0
    dnmax = 0
    for q in range(ng):
        smax = max(smax, goff[q + 1] - goff[q])
        dnmax = max(dnmax, gd[q, 1] - gd[q, 0])
        nrmax = max(nrmax, 2 * (gd[q, 1] - gd[q, 0]) + gi[q, 1] - gi[q, 0])
    sig = np.empty(R)
    w = np.empty(R)
    cd = np.empty(nd)
    qv = np.empty(R)
    g = np.empty(m)
    L = np.empty((m, m))
    d = np.empty(m)
    z = np.empty(m)
    BD = np.empty(R)
    dl = np.empty(max(smax, 1))
    Bwb = np.empty(max(nrmax * smax, 1))
    Gmb = np.empty(max(dnmax * smax, 1))
    sgb = np.empty(max(nrmax, 1))
    Hgb = np.empty(max(smax * smax, 1))
    Gsb = np.empty(max(smax * smax, 1))
    ggb = np.empty(max(smax, 1))
    bdb = np.empty(max(nrmax, 1))
    for p in range(k):
        t = tau[p]
        F0 = 0.0
        # 1. barrier pieces
        for c in range(nd):
            y0 = Y[p, 2 * c]
            y1 = Y[p, 2 * c + 1]
            r = np.sqrt(y0 * y0 + y1 * y1)
            q = np.sqrt(1.0 + (t * r) ** 2)
            td = (1.0 + q) / t
            sig[2 * c] = y0 / td
            sig[2 * c + 1] = y1 / td
            w[2 * c] = t / td
            w[2 * c + 1] = t / td
            cd[c] = np.sqrt(t * t / (td * td * q))
            qv[c] = q
        for j in range(2 * nd, R):
            y = Y[p, j]
            q = np.sqrt(1.0 + (t * y) ** 2)
            ti = (1.0 + q) / t
            sig[j] = y / ti
            w[j] = (t / ti) * (1.0 - t * y * y / (ti * q))
            qv[j] = q
        # 2. gradient and Hessian, group by group (two BLAS products per group into buffers allocated
        #    once per call, scattered into H)
        H = H_out[p]
        for a in range(m):
            g[a] = 0.0
            for b in range(m):
                H[a, b] = 0.0
        for q in range(ng):
            c0 = goff[q]
            s = goff[q + 1] - c0
            dn = gd[q, 1] - gd[q, 0]
            nr = 2 * dn + gi[q, 1] - gi[q, 0]
            Bg = GB[rows[p], boff[q]:boff[q] + nr * s].reshape((nr, s))   # the group's rows x columns
            Bw = Bwb[:nr * s].reshape((nr, s))
            Gm = Gmb[:dn * s].reshape((dn, s))
            sg = sgb[:nr]
            # the group's rows: its disks' pairs, then its intervals
            for rr in range(nr):
                j = 2 * gd[q, 0] + rr if rr < 2 * dn else gi[q, 0] + rr - 2 * dn
                wj = w[j]
                for a in range(s):
                    Bw[rr, a] = wj * Bg[rr, a]
                sg[rr] = sig[j]
            for c in range(dn):
                e0 = Y[p, 2 * (gd[q, 0] + c)] * cd[gd[q, 0] + c]
                e1 = Y[p, 2 * (gd[q, 0] + c) + 1] * cd[gd[q, 0] + c]
                for a in range(s):
                    Gm[c, a] = e0 * Bg[2 * c, a] + e1 * Bg[2 * c + 1, a]
            Hg = Hgb[:s * s].reshape((s, s))
            np.dot(Bw.T, Bg, Hg)
            if dn:
                Gs = Gsb[:s * s].reshape((s, s))
                np.dot(Gm.T, Gm, Gs)
                for a in range(s):
                    for b in range(s):
                        Hg[a, b] -= Gs[a, b]
            gg = ggb[:s]
            np.dot(sg, Bg, gg)
            for a in range(s):
                ja = gcols[c0 + a]
                g[ja] += gg[a]
                for b in range(s):
                    H[ja, gcols[c0 + b]] += Hg[a, b]
        tr = 0.0
        for a in range(m):
            g[a] *= t
            tr += H[a, a]
        reg = (tr / m + 1e-300) * 1e-14
        for a in range(m):
            H[a, a] += reg
        # 3. Newton step: Cholesky, else LU with partial pivoting
        if _chol_factor(H, L, m):
            for a in range(m):
                z[a] = -g[a]
            _chol_solve(L, z, d, m)
        else:
            for a in range(m):
                for b in range(m):
                    L[a, b] = H[a, b]
                z[a] = -g[a]
            singular = False
            for c in range(m):
                best = c
                for a in range(c + 1, m):
                    if abs(L[a, c]) > abs(L[best, c]):
                        best = a
                if L[best, c] == 0.0:
                    singular = True
                    break
                if best != c:
                    for b in range(m):
                        L[c, b], L[best, b] = L[best, b], L[c, b]
                    z[c], z[best] = z[best], z[c]
                for a in range(c + 1, m):
                    f = L[a, c] / L[c, c]
                    if f != 0.0:
                        for b in range(c, m):
                            L[a, b] -= f * L[c, b]
                        z[a] -= f * z[c]
            if singular:
                fail_out[p] = 1
                lam2_out[p] = 0.0
                continue
            for a in range(m - 1, -1, -1):
                v = z[a]
                for b in range(a + 1, m):
                    v -= L[a, b] * d[b]
                d[a] = v / L[a, a]
        fail_out[p] = 0
        lam2 = 0.0
        for a in range(m):
            lam2 -= g[a] * d[a]
        lam2 = max(lam2, 0.0)
        lam2_out[p] = lam2
        lam = np.sqrt(lam2)
        # B d on the groups' rows (the other rows do not enter the loop equations)
        for j in range(R):
            BD[j] = 0.0
        for q in range(ng):
            c0 = goff[q]
            s = goff[q + 1] - c0
            dn = gd[q, 1] - gd[q, 0]
            nr = 2 * dn + gi[q, 1] - gi[q, 0]
            Bg = GB[rows[p], boff[q]:boff[q] + nr * s].reshape((nr, s))
            for a in range(s):
                dl[a] = d[gcols[c0 + a]]
            bd = bdb[:nr]
            np.dot(Bg, dl[:s], bd)
            for rr in range(nr):
                j = 2 * gd[q, 0] + rr if rr < 2 * dn else gi[q, 0] + rr - 2 * dn
                BD[j] = bd[rr]
        # 4. line search
        step = 1.0
        if lam > 0.25:
            damped = 1.0 / (1.0 + lam)
            step = damped
            # the barrier at the start point, summed in the order of step 1 (disks, then intervals)
            for c in range(nd):
                F0 += qv[c] - np.log1p(qv[c])
            for j in range(2 * nd, R):
                F0 += qv[j] - np.log1p(qv[j])
            for i in range(ls.shape[0]):
                st = ls[i]
                if st <= damped:      # max(st, damped) is the damped step whether or not st passes
                    break
                Ft = 0.0
                for c in range(nd):
                    y0 = Y[p, 2 * c] + st * BD[2 * c]
                    y1 = Y[p, 2 * c + 1] + st * BD[2 * c + 1]
                    q = np.sqrt(1.0 + t * t * (y0 * y0 + y1 * y1))
                    Ft += q - np.log1p(q)
                for j in range(2 * nd, R):
                    y = Y[p, j] + st * BD[j]
                    q = np.sqrt(1.0 + (t * y) ** 2)
                    Ft += q - np.log1p(q)
                if Ft <= F0 - 0.1 * st * lam2:
                    step = max(st, damped)
                    break
        # 5. update (and the certified dual value of the new point)
        for a in range(m):
            mu[p, a] += step * d[a]
        for j in range(R):
            Y[p, j] += step * BD[j]
        if want_dual:
            f = 0.0
            for c in range(nd):
                f += np.sqrt(Y[p, 2 * c] ** 2 + Y[p, 2 * c + 1] ** 2)
            for j in range(2 * nd, R):
                f += abs(Y[p, j])
            dual_out[p] = f


def _project_centred_py(cidx, rows, Y, a, B, gram_inv, tau, nd, s0_out, s_out, lo_out):
    """Feasible point of each centred problem ``p = cidx[i]`` (certificate._project on the barrier
    point): ``s0 = y_c / t_c`` cone-wise, the loop residual ``B^T s0`` removed with ``pinv(B^T B)``,
    scaled back into the unit cones; ``lo = a^T s``. Writes s0_out, s_out (n, R), lo_out (n,)."""
    R = Y.shape[1]
    m = B.shape[2]
    r = np.empty(m)
    z = np.empty(m)
    for i in range(cidx.shape[0]):
        p = cidx[i]
        o = rows[p]
        t = tau[p]
        for c in range(nd):
            y0 = Y[p, 2 * c]
            y1 = Y[p, 2 * c + 1]
            td = (1.0 + np.sqrt(1.0 + t * t * (y0 * y0 + y1 * y1))) / t
            s0_out[i, 2 * c] = y0 / td
            s0_out[i, 2 * c + 1] = y1 / td
        for j in range(2 * nd, R):
            y = Y[p, j]
            s0_out[i, j] = y / ((1.0 + np.sqrt(1.0 + (t * y) ** 2)) / t)
        for b in range(m):
            r[b] = 0.0
        for j in range(R):
            sj = s0_out[i, j]
            if sj != 0.0:
                for b in range(m):
                    r[b] += sj * B[o, j, b]
        for b in range(m):
            v = 0.0
            for e in range(m):
                v += gram_inv[o, b, e] * r[e]
            z[b] = v
        worst = 1.0
        for j in range(R):
            v = s0_out[i, j]
            for b in range(m):
                v -= B[o, j, b] * z[b]
            s_out[i, j] = v
        for c in range(nd):
            worst = max(worst, np.sqrt(s_out[i, 2 * c] ** 2 + s_out[i, 2 * c + 1] ** 2))
        for j in range(2 * nd, R):
            worst = max(worst, abs(s_out[i, j]))
        lo = 0.0
        for j in range(R):
            s_out[i, j] /= worst
            lo += a[o, j] * s_out[i, j]
        lo_out[i] = lo


def _predict_centred_py(cidx, rows, Y, mu, B, H, told, tnew, cand, nd):
    """Path predictor of each centred problem ``p = cidx[i]`` (see support.solve_support): the
    tangent ``d mu / d tau = -H^{-1} B^T dY/dtau`` times ``tnew - told``, tried at the scales
    ``cand[i]`` and taken where the barrier at ``tnew`` is lowest (first of equals). In place on Y,
    mu; a problem whose Hessian Cholesky fails keeps its point."""
    R = Y.shape[1]
    m = B.shape[2]
    nc = cand.shape[1]
    dY = np.empty(R)
    dg = np.empty(m)
    L = np.empty((m, m))
    dmu = np.empty(m)
    dYp = np.empty(R)
    for i in range(cidx.shape[0]):
        p = cidx[i]
        o = rows[p]
        t = told[i]
        for c in range(nd):
            y0 = Y[p, 2 * c]
            y1 = Y[p, 2 * c + 1]
            rd = np.sqrt(y0 * y0 + y1 * y1)
            q = np.sqrt(1.0 + (t * rd) ** 2)
            cf = (2.0 * t * (1.0 + q) - t ** 3 * rd * rd / q) / (1.0 + q) ** 2
            dY[2 * c] = y0 * cf
            dY[2 * c + 1] = y1 * cf
        for j in range(2 * nd, R):
            y = Y[p, j]
            q = np.sqrt(1.0 + (t * y) ** 2)
            dY[j] = y * (2.0 * t * (1.0 + q) - t ** 3 * y * y / q) / (1.0 + q) ** 2
        for b in range(m):
            dg[b] = 0.0
        for j in range(R):
            v = dY[j]
            if v != 0.0:
                for b in range(m):
                    dg[b] += v * B[o, j, b]
        if not _chol_factor(H[p], L, m):
            continue
        _chol_solve(L, dg, dmu, m)
        scale = -(tnew[i] - t)
        for r_ in range(m):
            dmu[r_] *= scale
        for j in range(R):
            v = 0.0
            for b in range(m):
                v += B[o, j, b] * dmu[b]
            dYp[j] = v
        t2 = tnew[i] * tnew[i]
        best = 0
        Fbest = np.inf
        for e in range(nc):
            sc = cand[i, e]
            F = 0.0
            for c in range(nd):
                y0 = Y[p, 2 * c] + sc * dYp[2 * c]
                y1 = Y[p, 2 * c + 1] + sc * dYp[2 * c + 1]
                q = np.sqrt(1.0 + t2 * (y0 * y0 + y1 * y1))
                F += q - np.log1p(q)
            for j in range(2 * nd, R):
                y = Y[p, j] + sc * dYp[j]
                q = np.sqrt(1.0 + t2 * y * y)
                F += q - np.log1p(q)
            if F < Fbest:
                Fbest = F
                best = e
        sc = cand[i, best]
        for b in range(m):
            mu[p, b] += sc * dmu[b]
        for j in range(R):
            Y[p, j] += sc * dYp[j]
