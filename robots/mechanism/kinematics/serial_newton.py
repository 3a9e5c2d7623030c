"""Compiled (numba) Newton kernels of a serial chain: the continued inverse geometry (issue 23 item 5)
and the determinants of the posture check along joint-space paths (issue 33), one pose per loop
iteration with every scratch array allocated once per call (issue 43 item 1).

The chain, its stages and the parameters ``P, ident, kind, var, a, c, mark, n_marks`` are those of
:mod:`evotol.robots.mechanism.kinematics.serial_kernels`. The task at joint values ``q`` is the tip
coordinates ``p[axes]`` (m, divided by ``scale``) and, when ``has_rot``, the rotation vector of
``R Rt^T`` (rad); its Jacobian ``J`` (m, n_vars) has the joint twists of
:mod:`evotol.robots.mechanism.kinematics.tree` as columns (``[z x (p - o); z]`` of a revolute
joint's axis ``z`` through ``o``, ``[z; 0]`` of a prismatic one), times ``jcoef`` (``d value / d q``).
The Gauss-Newton steps are :meth:`InverseGeometry._newton
<evotol.robots.mechanism.posture.inverse_geometry.InverseGeometry._newton>`'s; the determinants are
:func:`evotol.robots.mechanism.posture.held.check_branch`'s.
"""
from __future__ import annotations

import numpy as np

from evotol._runtime.numba_cache import njit     # cache=True that falls back (issue 42)
from evotol.robots.mechanism.kinematics.serial_kernels import _frames, _rotvec


@njit(cache=True, inline="always")
def _jacobian(P, ident, kind, var, a, c, mark, q, has_rot, axes, jstage, jvar, jcoef, scale, J, marks, T, S):
    """Jacobian J (m, n_vars) of the task at q, rows scaled (lengths / scale); the tip into ``T``
    (3x4); ``marks`` and ``S`` (6, n_vars) are scratch."""
    _frames(P, ident, kind, var, a, c, mark, q, marks, T)
    nv = J.shape[1]
    S[:, :] = 0.0
    px, py, pz = T[0, 3], T[1, 3], T[2, 3]
    for t in range(jstage.shape[0]):             # the joint twists: [z x (p - o); z] or [z; 0] (tree.py)
        s, v, coef = jstage[t], jvar[t], jcoef[t]
        m = mark[s]
        ax0, ax1, ax2 = marks[m, 0, 2], marks[m, 1, 2], marks[m, 2, 2]
        if kind[s] == 2:
            S[0, v] += coef * ax0
            S[1, v] += coef * ax1
            S[2, v] += coef * ax2
        else:
            rx, ry, rz = px - marks[m, 0, 3], py - marks[m, 1, 3], pz - marks[m, 2, 3]
            S[0, v] += coef * (ax1 * rz - ax2 * ry)
            S[1, v] += coef * (ax2 * rx - ax0 * rz)
            S[2, v] += coef * (ax0 * ry - ax1 * rx)
            S[3, v] += coef * ax0
            S[4, v] += coef * ax1
            S[5, v] += coef * ax2
    for k in range(axes.shape[0]):
        for v in range(nv):
            J[k, v] = S[axes[k], v] / scale
    if has_rot:
        for k in range(3):
            for v in range(nv):
                J[axes.shape[0] + k, v] = S[3 + k, v]


@njit(cache=True, inline="always")
def _task(P, ident, kind, var, a, c, mark, q, target, Rt, has_rot, axes, jstage, jvar, jcoef, scale, F, J, marks, T, S):
    """Residual F (m,) and Jacobian J (m, n_vars) of the task at q (:func:`_jacobian`), rows scaled
    (lengths / scale). Returns the largest ``|F|``."""
    _jacobian(P, ident, kind, var, a, c, mark, q, has_rot, axes, jstage, jvar, jcoef, scale, J, marks, T, S)
    r = 0
    for k in range(axes.shape[0]):
        F[r] = (T[axes[k], 3] - target[k]) / scale
        r += 1
    if has_rot:
        _rotvec(T, Rt, F, r)
    big = 0.0
    for k in range(F.shape[0]):
        if not abs(F[k]) <= big:
            if F[k] != F[k]:
                return np.nan                    # as np.max: a NaN residual is not converged
            big = abs(F[k])
    return big


@njit(cache=True, inline="always")
def _gram(J, m, nv, rows, A):
    """A = J J^T (rows) or J^T J, damped by 1e-13 of its trace (as Kinematics._newton)."""
    k = m if rows else nv
    tr = 0.0
    for i in range(k):
        for j in range(i + 1):                   # symmetric: the lower triangle, mirrored (the same sums)
            s = 0.0
            if rows:
                for v in range(nv):
                    s += J[i, v] * J[j, v]
            else:
                for r in range(m):
                    s += J[r, i] * J[r, j]
            A[i, j] = A[j, i] = s
        tr += A[i, i]
    lam = 1e-13 * max(tr, 1e-300)
    for i in range(k):
        A[i, i] += lam


@njit(cache=True, inline="always")
def _jt(J, x, v, m):
    """``(J^T x)[v]`` over the first m rows of J."""
    s = 0.0
    for j in range(m):
        s += J[j, v] * x[j]
    return s


@njit(cache=True, inline="always")
def _solve(A, b, k):
    """Solve A x = b in place (b <- x) for the leading k x k block: Gaussian elimination with
    partial pivoting (A is overwritten). Returns det A (the pivots' product, signed by the row
    exchanges); 0.0 at a zero pivot, b then unsolved (a damped Gram matrix never has one)."""
    det = 1.0
    for c in range(k):
        p = c
        for r in range(c + 1, k):
            if abs(A[r, c]) > abs(A[p, c]):
                p = r
        if p != c:
            det = -det
            for j in range(k):
                A[c, j], A[p, j] = A[p, j], A[c, j]
            b[c], b[p] = b[p], b[c]
        piv = A[c, c]
        det *= piv
        if piv == 0.0:
            return 0.0
        for r in range(c + 1, k):
            f = A[r, c] / piv
            if f != 0.0:
                for j in range(c, k):
                    A[r, j] -= f * A[c, j]
                b[r] -= f * b[c]
    for c in range(k - 1, -1, -1):
        s = b[c]
        for j in range(c + 1, k):
            s -= A[c, j] * b[j]
        b[c] = s / A[c, c]
    return det


#: The damping of the Gauss-Newton steps (1e-13 of the trace, :func:`_gram`) leaves a redundant arm's scaled
#: residual at about 1e-12 where the posture is far from the assembly (35 % of the Panda's task box stays
#: between 1e-12 and 2.1e-12): a pose whose step moved no joint by more than STILL (rad or m) with a scaled
#: residual below FLOOR is converged (further steps move its joints by less than 1e-14; the caller accepts 1e-9)
FLOOR, STILL = 1e-10, 1e-13


@njit(cache=True)
def inverse_geometry(P, ident, kind, var, a, c, mark, n_marks, q0, targets, Rts, has_rot, axes, jstage, jvar, jcoef, scale,
                     n_final, tol):
    """Joint values (n, n_vars) continued from q0 through the targets (K, n, n_axes) (rotations
    Rts (K, n, 3, 3)): one Gauss-Newton step per intermediate target, up to n_final at the last;
    redundant tasks step to the solution nearest q0 (see Kinematics._newton). Returns (q, residual,
    evaluations). A pose stops at ``tol`` or at the floor of the damped steps (:data:`FLOOR`, :data:`STILL`).

    Parameters
    ----------
    q0 : (n_vars,) ndarray
        Starting (assembly) joint values (rad or m).
    targets : (K, n, n_axes) ndarray
        Target tip coordinates (m) per continuation step.
    Rts : (K, n, 3, 3) ndarray
        Target tip orientations per step (ignored unless ``has_rot``).
    has_rot : bool
        The orientation is part of the task.
    axes : (n_axes,) ndarray of int64
        Base axis (0-2) of each target coordinate.
    jstage, jvar : (nj,) ndarray of int64
        Joint stages and their joint variable indices.
    jcoef : (nj,) ndarray
        ``a_s`` of those stages (d value / d q).
    scale : float
        Length (m) dividing the position rows.
    n_final : int
        Largest number of Gauss-Newton iterations at the last target.
    tol : float
        Convergence tolerance of the scaled residual (dimensionless).

    Returns
    -------
    Q : (n, n_vars) ndarray
        Joint values at the last targets (rad or m).
    residual : (n,) ndarray
        Largest absolute scaled residual per pose (dimensionless).
    evaluations : (n,) ndarray of int64
        Task evaluations (forward kinematics and Jacobian) per pose, continuation steps included.
    """
    K, n = targets.shape[0], targets.shape[1]
    nv = q0.shape[0]
    m = axes.shape[0] + (3 if has_rot else 0)
    Q = np.empty((n, nv))
    res = np.empty(n)
    evals = np.zeros(n, np.int64)
    F = np.empty(m)
    J = np.empty((m, nv))
    A = np.empty((max(m, nv), max(m, nv)))
    y = np.empty(max(m, nv))
    d = np.empty(nv)
    marks, T, S = np.empty((n_marks, 3, 4)), np.empty((3, 4)), np.empty((6, nv))
    for i in range(n):
        q = q0.copy()
        r = np.inf
        for k in range(K):
            last = k == K - 1
            iters = n_final if last else 1
            moved = step = 0.0
            for it in range(iters + 1):
                if it == iters and not last:
                    break
                r = _task(P, ident, kind, var, a, c, mark, q, targets[k, i], Rts[k, i], has_rot, axes, jstage, jvar, jcoef,
                          scale, F, J, marks, T, S)
                evals[i] += 1
                if (r < tol and moved <= 1e-11) or (r < FLOOR and step <= STILL) or it == iters:
                    break
                if m < nv:                  # redundant: q <- q0 + J^T (J J^T)^-1 (J (q - q0) - F)
                    for j in range(nv):
                        d[j] = q[j] - q0[j]
                    _gram(J, m, nv, True, A)
                    for j in range(m):
                        s_ = -F[j]
                        for v in range(nv):
                            s_ += J[j, v] * d[v]
                        y[j] = s_
                    _solve(A, y, m)
                    moved = 0.0
                    for v in range(nv):
                        s_ = _jt(J, y, v, m)
                        moved = max(moved, abs(s_ - d[v]))
                        q[v] = q0[v] + s_
                    step = moved
                else:                         # q <- q - (J^T J)^-1 J^T F
                    _gram(J, m, nv, False, A)
                    for v in range(nv):
                        y[v] = _jt(J, F, v, m)
                    _solve(A, y, nv)
                    step = 0.0
                    for v in range(nv):
                        q[v] -= y[v]
                        step = max(step, abs(y[v]))
        for v in range(nv):                       # element by element (a row assignment compiles seconds of numba)
            Q[i, v] = q[v]
        res[i] = r
    return Q, res, evals


@njit(cache=True)
def path_determinants(P, ident, kind, var, a, c, mark, n_marks, q0, diff, S, has_rot, axes, jstage, jvar, jcoef, scale):
    """``det J`` of the square scaled task Jacobian at the joint values ``q0 + S[k] diff[i]`` of every
    pose i and path sample k (the posture check's straight joint-space paths, :func:`check_branch
    <evotol.robots.mechanism.posture.held.check_branch>`), and J at each path's last sample.

    Parameters
    ----------
    q0 : (n_vars,) ndarray
        As :func:`inverse_geometry` (the start of every path).
    diff : (n, n_vars) ndarray
        Joint-space displacement of each path (rad or m; revolute ones wrapped by the caller).
    S : (n_samples,) ndarray
        Path parameters of the samples (dimensionless, the last one 1).
    has_rot, axes, jstage, jvar, jcoef, scale
        As :func:`inverse_geometry`; ``len(axes) + 3 * has_rot`` equals ``n_vars``.

    Returns
    -------
    det : (n_samples, n) ndarray
        Determinant of the scaled task Jacobian at every sample (its position rows per rad divided by
        ``scale``, its rotation rows rad per rad: dimensionless for revolute joints).
    J_end : (n, n_vars, n_vars) ndarray
        The scaled task Jacobian at ``q0 + S[-1] diff[i]``.
    """
    n, nv = diff.shape[0], q0.shape[0]
    det = np.empty((S.shape[0], n))
    J_end = np.empty((n, nv, nv))
    J, A, q, b = np.empty((nv, nv)), np.empty((nv, nv)), np.empty(nv), np.zeros(nv)
    marks, T, Sc = np.empty((n_marks, 3, 4)), np.empty((3, 4)), np.empty((6, nv))
    for i in range(n):
        for k in range(S.shape[0]):
            for v in range(nv):
                q[v] = q0[v] + S[k] * diff[i, v]
            _jacobian(P, ident, kind, var, a, c, mark, q, has_rot, axes, jstage, jvar, jcoef, scale, J, marks, T, Sc)
            for u in range(nv):                   # element by element: an array slice assignment compiles
                for v in range(nv):               # numba's error-message machinery (seconds per process)
                    A[u, v] = J[u, v]
            det[k, i] = _solve(A, b, nv)          # b = 0: only the elimination's pivots matter
        for u in range(nv):
            for v in range(nv):
                J_end[i, u, v] = J[u, v]
    return det, J_end
