"""Compiled (numba) kernels of a serial chain: forward kinematics, sensitivity and perturbed forward
kinematics, one pose per loop iteration (the Newton kernels, inverse geometry and posture check, are
:mod:`evotol.robots.mechanism.kinematics.serial_newton`).

The chain is a list of **stages** (:class:`evotol.robots.mechanism.kinematics.serial.SerialChain`): ``T <- T P_s``
(a constant 4x4, the fixed rows and the joint row's ``Rot(z,gamma) Trans(z,b) Rot(x,alpha)
Trans(x,d)``), then, for a joint stage, ``T <- T Rot(z, theta)`` or ``T <- T Trans(z, r)`` with the
joint value ``a_s q[var_s] + c_s``. ``mark_s >= 0`` records the frame after ``P_s`` (the stage's
placement, :mod:`evotol.robots.mechanism.kinematics.placement`). Errors enter as **terms**:

* placement terms ``(column, mark, field)``: ``P_s exp(delta)`` with ``delta[field] += e[column]``;
* joint terms ``(column, stage, coef, var)``: the stage's joint value moves by
  ``e[column] * coef * (q[var] if var >= 0 else 1)``.

Sensitivities are ``[dp; dphi]`` of the tip (``evotol.robots.base`` order); the placement twists and the
joint twists are those of :mod:`evotol.robots.mechanism.kinematics.tree` (same equations, per pose).

The parameters several definitions of this module share are described once, here.

Parameters
----------
P : (ns, 4, 4) ndarray
    Constant transform of each stage (m).
ident : (ns,) ndarray of bool
    True where ``P_s`` is the identity (skipped).
kind : (ns,) ndarray of int64
    0 fixed, 1 revolute (``Rot(z, value)``), 2 prismatic (``Trans(z, value)``).
var : (ns,) ndarray of int64
    Joint variable index of each joint stage.
a, c : (ns,) ndarray
    Joint value ``a_s q[var_s] + c_s`` (rad or m) of each joint stage.
mark : (ns,) ndarray of int64
    Mark (placement frame) index of each stage, -1 for none.
n_marks : int
    Number of marks.
"""
from __future__ import annotations

import os

import numba
import numpy as np
from numba import prange

from evotol._runtime.numba_cache import njit     # cache=True that falls back (issue 42)

# The parallel Monte Carlo kernel must survive a fork (evotol's process pool forks after a parent may
# have run it; GNU OpenMP, numba's default layer where present, then kills the child): a fork-safe
# layer (TBB if installed, else numba's workqueue), unless the user chose one. The workqueue is not
# thread-safe, so only the main thread calls the parallel kernel (evotol.robots.mechanism.kinematics.serial).
if "NUMBA_THREADING_LAYER" not in os.environ:
    numba.config.THREADING_LAYER = "forksafe"


@njit(cache=True, inline="always")
def _mul(A, B, out):
    for i in range(3):
        for j in range(4):
            s = A[i, 0] * B[0, j] + A[i, 1] * B[1, j] + A[i, 2] * B[2, j]
            if j == 3:
                s += A[i, 3]
            out[i, j] = s
    out[3, 0] = out[3, 1] = out[3, 2] = 0.0
    out[3, 3] = 1.0


@njit(cache=True)
def _exp6(d, out):
    """exp of the local twist d = [shift(3); tilt(3)] as a 4x4 (Rodrigues, scalar arithmetic)."""
    wx, wy, wz = d[3], d[4], d[5]
    th2 = wx * wx + wy * wy + wz * wz
    if th2 < 1e-16:
        a, b, c = 1.0 - th2 / 6.0, 0.5 - th2 / 24.0, 1.0 / 6.0 - th2 / 120.0
    else:
        th = np.sqrt(th2)
        sn, cs = np.sin(th), np.cos(th)
        a, b, c = sn / th, (1.0 - cs) / th2, (th - sn) / (th2 * th)
    # W^2 = w w^T - th2 I
    xx, yy, zz, xy, xz, yz = wx * wx - th2, wy * wy - th2, wz * wz - th2, wx * wy, wx * wz, wy * wz
    out[0, 0], out[0, 1], out[0, 2] = 1.0 + b * xx, -a * wz + b * xy, a * wy + b * xz
    out[1, 0], out[1, 1], out[1, 2] = a * wz + b * xy, 1.0 + b * yy, -a * wx + b * yz
    out[2, 0], out[2, 1], out[2, 2] = -a * wy + b * xz, a * wx + b * yz, 1.0 + b * zz
    v0, v1, v2 = d[0], d[1], d[2]
    out[0, 3] = (1.0 + c * xx) * v0 + (-b * wz + c * xy) * v1 + (b * wy + c * xz) * v2
    out[1, 3] = (b * wz + c * xy) * v0 + (1.0 + c * yy) * v1 + (-b * wx + c * yz) * v2
    out[2, 3] = (-b * wy + c * xz) * v0 + (b * wx + c * yz) * v1 + (1.0 + c * zz) * v2
    out[3, 0] = out[3, 1] = out[3, 2] = 0.0
    out[3, 3] = 1.0


@njit(cache=True)
def _joint(T, kind, v, out):
    """T Rot(z, v) (kind 1) or T Trans(z, v) (kind 2)."""
    for i in range(4):
        for j in range(4):
            out[i, j] = T[i, j]
    if kind == 1:
        c, s = np.cos(v), np.sin(v)
        for i in range(3):
            x, y = T[i, 0], T[i, 1]
            out[i, 0] = c * x + s * y
            out[i, 1] = -s * x + c * y
    elif kind == 2:
        for i in range(3):
            out[i, 3] = T[i, 3] + v * T[i, 2]


@njit(cache=True)
def _chain(P, ident, kind, var, a, c, mark, q, dq, E, has_E, marks, T, tmp):
    """Forward kinematics of one configuration; joint values ``a q[var] + c + dq``; ``E[mark]``
    applied after ``P`` where ``has_E[mark]``; frames after ``P`` stored in ``marks``; tip in T
    (``tmp``: a 4x4 scratch)."""
    for i in range(4):
        for j in range(4):
            T[i, j] = 1.0 if i == j else 0.0
    for s in range(P.shape[0]):
        if ident[s]:                                # a joint row right after its origin: P = I
            for i in range(4):
                for j in range(4):
                    tmp[i, j] = T[i, j]
        else:
            _mul(T, P[s], tmp)
        m = mark[s]
        if m >= 0 and has_E[m]:
            _mul(tmp, E[m], T)
            for i in range(4):
                for j in range(4):
                    tmp[i, j] = T[i, j]
        if m >= 0 and marks.shape[0] > 0:            # an empty marks array: the tip only (Monte Carlo)
            for i in range(3):
                for j in range(4):
                    marks[m, i, j] = tmp[i, j]
        if kind[s] == 0:
            for i in range(4):
                for j in range(4):
                    T[i, j] = tmp[i, j]
        else:
            _joint(tmp, kind[s], a[s] * q[var[s]] + c[s] + dq[s], T)


@njit(cache=True, inline="always")
def _frames(P, ident, kind, var, a, c, mark, q, marks, T):
    """Nominal forward kinematics at joint values ``a q[var] + c``, row by row (row i of ``T P_s`` and
    of the joint motion needs only row i of ``T``, so nothing is copied): the frames after ``P``
    (3x4) into ``marks``, the tip into ``T`` (3x4). The same products, in the same order, as
    :func:`_chain` with no errors."""
    for i in range(3):
        for j in range(4):
            T[i, j] = 1.0 if i == j else 0.0
    for s in range(P.shape[0]):
        k, m = kind[s], mark[s]
        cs = sn = v = 0.0
        if k == 1:
            v = a[s] * q[var[s]] + c[s]
            cs, sn = np.cos(v), np.sin(v)
        elif k == 2:
            v = a[s] * q[var[s]] + c[s]
        for i in range(3):
            u0, u1, u2, u3 = T[i, 0], T[i, 1], T[i, 2], T[i, 3]
            if not ident[s]:
                r0, r1, r2 = u0, u1, u2
                u0 = r0 * P[s, 0, 0] + r1 * P[s, 1, 0] + r2 * P[s, 2, 0]
                u1 = r0 * P[s, 0, 1] + r1 * P[s, 1, 1] + r2 * P[s, 2, 1]
                u2 = r0 * P[s, 0, 2] + r1 * P[s, 1, 2] + r2 * P[s, 2, 2]
                u3 = r0 * P[s, 0, 3] + r1 * P[s, 1, 3] + r2 * P[s, 2, 3] + u3
            if m >= 0:
                marks[m, i, 0], marks[m, i, 1], marks[m, i, 2], marks[m, i, 3] = u0, u1, u2, u3
            if k == 1:
                u0, u1 = cs * u0 + sn * u1, -sn * u0 + cs * u1
            elif k == 2:
                u3 = u3 + v * u2
            T[i, 0], T[i, 1], T[i, 2], T[i, 3] = u0, u1, u2, u3


@njit(cache=True, error_model="numpy")
def sensitivity(P, ident, kind, var, a, c, mark, n_marks, Q, t_col, t_mark, t_field, t_coef, t_var, n_cols):
    """(n, 6, n_cols) first-order map at joint values Q (n, n_vars); terms: column, mark, field,
    coefficient, variable (coefficient times q[var] when var >= 0): a shift moves the tip along the
    mark's axis, a tilt turns it about the axis through the mark's origin (``[ax x (p - o); ax]``).

    Parameters
    ----------
    Q : (n, n_vars) ndarray
        Joint values (rad or m).
    t_col, t_mark, t_field : (nt,) ndarray of int64
        Per term: source column, mark, and placement field index (0-2 ``shift_x..z``, 3-5
        ``tilt_x..z``; a joint term is ``tilt_z`` (revolute) or ``shift_z`` (prismatic) of its
        stage's mark).
    t_coef : (nt,) ndarray
        Per term: coefficient (dimensionless, or per unit of ``q[var]``).
    t_var : (nt,) ndarray of int64
        Per term: joint variable multiplying the coefficient, -1 for none.
    n_cols : int
        Number of source columns.

    Returns
    -------
    (n, 6, n_cols) ndarray
        ``[dp (m); dphi (rad)]`` of the tip, base frame, per unit of each column (m or rad).
    """
    n = Q.shape[0]
    S = np.empty((n, 6, n_cols))                  # each pose's block zeroed while in cache (np.zeros: a memset pass)
    marks = np.empty((n_marks, 3, 4))
    T = np.empty((3, 4))
    nt = t_col.shape[0]
    for i in range(n):
        _frames(P, ident, kind, var, a, c, mark, Q[i], marks, T)
        S[i] = 0.0
        px, py, pz = T[0, 3], T[1, 3], T[2, 3]
        for t in range(nt):
            coef = t_coef[t]
            if t_var[t] >= 0:
                coef *= Q[i, t_var[t]]
            m, f, col = t_mark[t], t_field[t], t_col[t]
            k = f % 3
            ax0, ax1, ax2 = marks[m, 0, k] * coef, marks[m, 1, k] * coef, marks[m, 2, k] * coef
            if f < 3:
                S[i, 0, col] += ax0
                S[i, 1, col] += ax1
                S[i, 2, col] += ax2
            else:
                rx, ry, rz = px - marks[m, 0, 3], py - marks[m, 1, 3], pz - marks[m, 2, 3]
                S[i, 0, col] += ax1 * rz - ax2 * ry
                S[i, 1, col] += ax2 * rx - ax0 * rz
                S[i, 2, col] += ax0 * ry - ax1 * rx
                S[i, 3, col] += ax0
                S[i, 4, col] += ax1
                S[i, 5, col] += ax2
    return S


@njit(cache=True, inline="always")
def _rotvec(T, Rt, w, r):
    """Rotation vector (rad) of ``R Rt^T`` (``R`` the rotation of the 3x4 ``T``) into ``w[r:r + 3]``."""
    R00 = T[0, 0] * Rt[0, 0] + T[0, 1] * Rt[0, 1] + T[0, 2] * Rt[0, 2]
    R11 = T[1, 0] * Rt[1, 0] + T[1, 1] * Rt[1, 1] + T[1, 2] * Rt[1, 2]
    R22 = T[2, 0] * Rt[2, 0] + T[2, 1] * Rt[2, 1] + T[2, 2] * Rt[2, 2]
    cs = min(1.0, max(-1.0, (R00 + R11 + R22 - 1.0) / 2.0))
    th = np.arccos(cs)
    f = 0.5 + th * th / 12.0 if th < 1e-8 else th / (2.0 * np.sin(th))
    for k in range(3):                  # R[i, j] - R[j, i] for (i, j) = (2, 1), (0, 2), (1, 0)
        i, j = (k + 2) % 3, (k + 1) % 3
        Rij = T[i, 0] * Rt[j, 0] + T[i, 1] * Rt[j, 1] + T[i, 2] * Rt[j, 2]
        Rji = T[j, 0] * Rt[i, 0] + T[j, 1] * Rt[i, 1] + T[j, 2] * Rt[i, 2]
        w[r + k] = (Rij - Rji) * f


@njit(cache=True)
def _pose_error_block(P, ident, kind, var, a, c, mark, n_marks, Q, errors, p_col, p_mark, p_field, j_col, j_stage,
                      j_coef, j_var, v_col, v_var, lo, hi, out):
    """Pose-samples ``lo <= i m + k < hi`` of :func:`pose_error` into ``out`` (one scratch set)."""
    m = errors.shape[1]
    marks = np.empty((n_marks, 3, 4))
    T0 = np.empty((4, 4))
    T = np.empty((4, 4))
    ns = P.shape[0]
    dq0 = np.zeros(ns)
    E = np.empty((n_marks, 4, 4))
    none = np.zeros(n_marks, np.bool_)
    has_E = np.zeros(n_marks, np.bool_)
    delta = np.zeros((n_marks, 6))
    for mm in range(p_mark.shape[0]):
        has_E[p_mark[mm]] = True
    R = np.empty((3, 3))
    tmp = np.empty((4, 4))
    qe = np.empty(Q.shape[1])
    dq = np.zeros(ns)
    nomarks = np.empty((0, 3, 4))
    i_done = -1
    for flat in range(lo, hi):
        i, k = flat // m, flat % m
        if i != i_done:                                  # the nominal tip of pose i, once per block
            _chain(P, ident, kind, var, a, c, mark, Q[i], dq0, E, none, marks, T0, tmp)
            i_done = i
        e = errors[i, k]
        delta[:, :] = 0.0
        for t in range(p_col.shape[0]):
            delta[p_mark[t], p_field[t]] += e[p_col[t]]
        for mk in range(n_marks):
            if has_E[mk]:
                _exp6(delta[mk], E[mk])
        for v in range(Q.shape[1]):
            qe[v] = Q[i, v]
        for t in range(v_col.shape[0]):
            qe[v_var[t]] += e[v_col[t]]
        dq[:] = 0.0
        for t in range(j_col.shape[0]):
            dq[j_stage[t]] += e[j_col[t]] * j_coef[t] * (qe[j_var[t]] if j_var[t] >= 0 else 1.0)
        _chain(P, ident, kind, var, a, c, mark, qe, dq, E, has_E, nomarks, T, tmp)
        for r in range(3):
            out[i, k, r] = T[r, 3] - T0[r, 3]
            for s in range(3):
                R[r, s] = T[r, 0] * T0[s, 0] + T[r, 1] * T0[s, 1] + T[r, 2] * T0[s, 2]
        cs = min(1.0, max(-1.0, (R[0, 0] + R[1, 1] + R[2, 2] - 1.0) / 2.0))
        th = np.arccos(cs)
        f = 0.5 + th * th / 12.0 if th < 1e-8 else th / (2.0 * np.sin(th))
        out[i, k, 3] = (R[2, 1] - R[1, 2]) * f
        out[i, k, 4] = (R[0, 2] - R[2, 0]) * f
        out[i, k, 5] = (R[1, 0] - R[0, 1]) * f


@njit(cache=True)
def pose_error_serial(P, ident, kind, var, a, c, mark, n_marks, Q, errors, p_col, p_mark, p_field, j_col, j_stage, j_coef,
                      j_var, v_col, v_var):
    """:func:`pose_error` in the calling thread only (for threads other than the main one)."""
    out = np.empty((errors.shape[0], errors.shape[1], 6))
    _pose_error_block(P, ident, kind, var, a, c, mark, n_marks, Q, errors, p_col, p_mark, p_field, j_col, j_stage,
                      j_coef, j_var, v_col, v_var, 0, errors.shape[0] * errors.shape[1], out)
    return out


#: pose-samples per parallel block of :func:`pose_error` (large enough that a block's scratch and its
#: nominal chains are negligible, small enough that two threads share the work evenly)
BLOCK = 2048


@njit(cache=True, parallel=True)
def pose_error(P, ident, kind, var, a, c, mark, n_marks, Q, errors, p_col, p_mark, p_field, j_col, j_stage, j_coef, j_var, v_col, v_var):
    """(n, m, 6) nonlinear tip error for errors (n, m, n_cols): placement terms (column, mark, field),
    joint terms (column, stage, coefficient, variable: times the *perturbed* q[var]), joint offsets
    (column, variable: q[var] += e), so an error of a mimic multiplier and of its leader's offset
    combine exactly as in the description (``(m + dm) (q + dq)``).

    Parameters
    ----------
    Q : (n, n_vars) ndarray
        Nominal joint values (rad or m).
    errors : (n, m, n_cols) ndarray
        Source errors (m or rad).
    p_col, p_mark, p_field : (np,) ndarray of int64
        Placement terms: source column, mark, placement field index (0-5, ``shift_x`` ...
        ``tilt_z``).
    j_col, j_stage : (nj,) ndarray of int64
        Joint terms: source column and stage whose joint value moves.
    j_coef : (nj,) ndarray
        Joint terms: coefficient.
    j_var : (nj,) ndarray of int64
        Joint terms: joint variable multiplying the coefficient (perturbed value), -1 for none.
    v_col, v_var : (nv,) ndarray of int64
        Joint offsets: source column added to joint variable ``v_var``.

    Returns
    -------
    (n, m, 6) ndarray
        ``[dp (m); rotation vector of R R0^T (rad)]`` of the perturbed tip relative to the
        nominal, base frame.

    Notes
    -----
    The pose-samples are cut into blocks of consecutive flat indices ``i m + k``, run in parallel
    (``numba.prange``, one scratch set per block, nothing allocated per sample); each sample's
    arithmetic is the serial one, so the result does not depend on the number of threads.
    """
    n, m = errors.shape[0], errors.shape[1]
    out = np.empty((n, m, 6))
    total = n * m
    n_blocks = (total + BLOCK - 1) // BLOCK
    for b in prange(n_blocks):
        _pose_error_block(P, ident, kind, var, a, c, mark, n_marks, Q, errors, p_col, p_mark, p_field, j_col, j_stage,
                          j_coef, j_var, v_col, v_var, b * BLOCK, min(total, (b + 1) * BLOCK), out)
    return out
