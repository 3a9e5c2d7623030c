"""The serial-arm Monte Carlo kernel (issue 43 item 2): the perturbed tip of a block of poses times a
block of samples in one compiled pass, :data:`W` samples at a time in SIMD lanes.

The chain of :mod:`evotol.robots.mechanism.kinematics.serial_kernels` (stages ``P_s``, placement
errors ``E_m = exp(delta_m)`` after ``P_s``, joint motions ``J_s(theta_s + delta_s)``) is rewritten,
with ``J(theta + delta) = J(delta) J(theta)`` (rotations about, or translations along, one ``z``), as

    T = C_0 . O_1 . C_1 . O_2 ... O_K . C_K,

where the **operations** ``O_k = E_m J_s(delta_s)`` hold everything that varies by sample and the
**constants** ``C_k`` (products of the ``P_s`` and the nominal joint motions ``J_s(theta_s)``) depend on
the pose only: they are computed once per pose and shared by all its samples. The nominal tip is
``C_0 C_1 ... C_K`` (the same products, so an error vector of zeros gives exactly zero). Per sample
the work is then one 3x4 product per operation and per constant, the placement exponentials and the
final rotation vector, with no call to a transcendental function for the small angles tolerances
give: the Rodrigues coefficients ``sin t/t``, ``(1 - cos t)/t^2``, ``(t - sin t)/t^3``, ``sin d`` and
``cos d`` of a joint error and ``asin(s)/s`` of the result are their Taylor series in ``t^2``
(terms to ``t^10``: truncation below 1e-21 relative for ``t < 0.1`` rad; the rotation vector's
series for ``s < 0.01``); a lane beyond those ranges takes the closed forms. The lanes are the
innermost loops over flat rows of W lanes (a row stride LLVM knows, so its alias checks stay
few and it vectorises them: AVX2/AVX-512); a task is one pose and up to
:data:`TASK` of its samples, and tasks run on the cores by threads
(:mod:`evotol.robots.mechanism.kinematics.task_threads`).

``tests/test_serial_montecarlo.py`` compares it with the general description path
(:class:`evotol.robots.mechanism.kinematics.tree.Kinematics`), the scalar kernel it replaces
(:func:`evotol.robots.mechanism.kinematics.serial_kernels.pose_error`) and an independent product of
4x4 matrices written in the test.

The parameters several definitions of this module share are described once, here.

Parameters
----------
P : (ns, 4, 4) ndarray
    The stages' constant transforms ``P_s`` (lengths in m).
kind : (ns,) ndarray of int64
    0 fixed, 1 revolute, 2 prismatic.
var : (ns,) ndarray of int64
    Index of the joint variable that drives each joint stage.
a, c : (ns,) ndarray
    Nominal joint value ``a_s q[var_s] + c_s`` (rad or m) of each joint stage.
seg_start, fac_kind, fac_stage : ndarray of int64
    The constants: factors ``seg_start[k] <= f < seg_start[k + 1]`` of ``C_k``, each ``P_s``
    (``fac_kind`` 0) or ``J_s(theta_s)`` (1) of stage ``fac_stage``.
op_stage : (K,) ndarray of int64
    Joint stage whose error ``delta_s`` the operation applies, -1 for none.
op_p, p_col, p_field : ndarray of int64
    Placement terms ``op_p[k] <= t < op_p[k + 1]`` of operation ``k``: ``delta[p_field] +=
    e[p_col]`` (fields 0-5: ``shift_x`` ... ``tilt_z``); none: no ``E_m``.
op_j, j_col, j_var : ndarray of int64; j_coef : ndarray
    Joint terms of operation ``k``'s stage: ``delta_s += e[j_col] j_coef (q[j_var] + offset)``
    (1 for ``j_var`` -1).
v_col, v_var : ndarray of int64
    Joint offsets: ``offset[v_var] += e[v_col]``; ``delta_s`` also gets ``a_s offset[var_s]``.
"""
from __future__ import annotations

import numpy as np

from evotol._runtime.numba_cache import njit
from evotol.robots.mechanism.kinematics.task_threads import run_tasks

#: samples per group: the lanes of one row (64 float64: eight AVX-512 registers, sixteen AVX2 ones)
W = 64
#: samples of one pose per task (a thread runs a range of tasks)
TASK = 512
#: t^2 below which the Rodrigues and joint series serve (t < 0.1 rad)
SMALL = 1e-2
#: s^2 below which the series of asin(s)/s serves (rotation < 0.01 rad)
SMALL_ROT = 1e-4


def program(chain) -> tuple:
    """The constants and operations of ``chain`` (module docstring) as the kernel's arrays.

    Parameters
    ----------
    chain : evotol.robots.mechanism.kinematics.serial.SerialChain
        The stages and error terms of a serial arm.

    Returns
    -------
    tuple of ndarray
        ``seg_start, fac_kind, fac_stage, op_stage, op_p, p_col, p_field, op_j, j_col, j_coef,
        j_var`` (see the module docstring).
    """
    ns = len(chain.P)
    has_e = set(chain.p_terms[:, 1].tolist())
    moved = set(chain.j_stage.tolist()) | {s for s in range(ns) if chain.kind[s] > 0 and chain.a[s] != 0.0
                                           and chain.var[s] in set(chain.v_var.tolist())}
    segs, ops, pending = [[]], [], None

    def close():
        ops.append(pending)
        segs.append([])

    for s in range(ns):
        if not chain.ident[s]:
            if pending is not None:
                close()
                pending = None
            segs[-1].append((0, s))
        m = chain.mark[s]
        if m >= 0 and m in has_e:
            if pending is not None:
                close()
            pending = [m, -1]
        if chain.kind[s] > 0:
            if s in moved:
                if pending is None:
                    pending = [-1, s]
                else:
                    pending[1] = s
            if pending is not None:
                close()
                pending = None
            segs[-1].append((1, s))
    if pending is not None:
        close()
    seg_start = np.cumsum([0] + [len(g) for g in segs]).astype(np.int64)
    fac = np.array([f for g in segs for f in g], np.int64).reshape(-1, 2)
    p = chain.p_terms
    pt = [[t for t in range(len(p)) if p[t, 1] == o[0]] for o in ops]
    jt = [[t for t in range(len(chain.j_col)) if chain.j_stage[t] == o[1]] for o in ops]
    pi, ji = [t for g in pt for t in g], [t for g in jt for t in g]
    i64 = np.int64
    return (seg_start, fac[:, 0].copy(), fac[:, 1].copy(), np.array([o[1] for o in ops], i64),
            np.cumsum([0] + [len(g) for g in pt]).astype(i64), p[pi, 0].astype(i64), p[pi, 2].astype(i64),
            np.cumsum([0] + [len(g) for g in jt]).astype(i64), chain.j_col[ji].astype(i64),
            chain.j_coef[ji].astype(float), chain.j_var[ji].astype(i64))


@njit(cache=True, error_model="numpy")
def _mul34(A, B, out):
    """out = A B for 3x4 affine transforms (the last row 0 0 0 1 implied)."""
    for i in range(3):
        for j in range(4):
            s = A[i, 0] * B[0, j] + A[i, 1] * B[1, j] + A[i, 2] * B[2, j]
            out[i, j] = s + A[i, 3] if j == 3 else s


@njit(cache=True, error_model="numpy")
def _constants(P, kind, var, a, c, q, seg_start, fac_kind, fac_stage, C, T0):
    """The constants C (K+1, 3, 4) of one pose and its nominal tip T0 = C_0 ... C_K (3x4)."""
    tmp = np.empty((3, 4))
    for i in range(3):
        for j in range(4):
            T0[i, j] = 1.0 if i == j else 0.0
    for k in range(seg_start.shape[0] - 1):
        for i in range(3):
            for j in range(4):
                C[k, i, j] = 1.0 if i == j else 0.0
        for f in range(seg_start[k], seg_start[k + 1]):
            s = fac_stage[f]
            if fac_kind[f] == 0:
                _mul34(C[k], P[s], tmp)
                for i in range(3):        # element by element: a slice assignment compiles numba's error-text machinery (seconds)
                    for j in range(4):
                        C[k, i, j] = tmp[i, j]
            else:
                v = a[s] * q[var[s]] + c[s]
                if kind[s] == 1:
                    cs, sn = np.cos(v), np.sin(v)
                    for i in range(3):
                        x, y = C[k, i, 0], C[k, i, 1]
                        C[k, i, 0] = cs * x + sn * y
                        C[k, i, 1] = -sn * x + cs * y
                else:
                    for i in range(3):
                        C[k, i, 3] += v * C[k, i, 2]
        _mul34(T0, C[k], tmp)
        for i in range(3):
            for j in range(4):
                T0[i, j] = tmp[i, j]


@njit(cache=True, error_model="numpy")
def _lanes_times_constant(T, C, out):
    """out = T C for every lane (T, out: 12 rows ``4 i + j`` of the 3x4 by W lanes, flat). Row i of a
    lane is read once for its four products (each product the sum it was, in the same order, the
    ``0.0 * t3`` terms included: a NaN or infinite lane stays what it was)."""
    c00, c01, c02, c03 = C[0, 0], C[0, 1], C[0, 2], C[0, 3]
    c10, c11, c12, c13 = C[1, 0], C[1, 1], C[1, 2], C[1, 3]
    c20, c21, c22, c23 = C[2, 0], C[2, 1], C[2, 2], C[2, 3]
    for i in range(3):
        r = 4 * i * W
        for l in range(W):
            t0, t1, t2, t3 = T[r + l], T[r + W + l], T[r + 2 * W + l], T[r + 3 * W + l]
            out[r + l] = t0 * c00 + t1 * c10 + t2 * c20 + 0.0 * t3
            out[r + W + l] = t0 * c01 + t1 * c11 + t2 * c21 + 0.0 * t3
            out[r + 2 * W + l] = t0 * c02 + t1 * c12 + t2 * c22 + 0.0 * t3
            out[r + 3 * W + l] = t0 * c03 + t1 * c13 + t2 * c23 + 1.0 * t3


@njit(cache=True, error_model="numpy")
def _lanes_times_lanes(T, E, out):
    """out = T E lane by lane (3x4 affine, flat rows ``4 i + j`` of W lanes). Row i of T and the
    lane's E are read once for row i's four products (each the sum it was, in the same order)."""
    for i in range(3):
        r = 4 * i * W
        for l in range(W):
            t0, t1, t2, t3 = T[r + l], T[r + W + l], T[r + 2 * W + l], T[r + 3 * W + l]
            out[r + l] = t0 * E[l] + t1 * E[4 * W + l] + t2 * E[8 * W + l]
            out[r + W + l] = t0 * E[W + l] + t1 * E[5 * W + l] + t2 * E[9 * W + l]
            out[r + 2 * W + l] = t0 * E[2 * W + l] + t1 * E[6 * W + l] + t2 * E[10 * W + l]
            out[r + 3 * W + l] = t0 * E[3 * W + l] + t1 * E[7 * W + l] + t2 * E[11 * W + l] + t3


@njit(cache=True, error_model="numpy")
def _exp6_lanes(d, E, co):
    """E = exp(d) lane by lane (12 flat rows) for the local twists d (6 rows) = [shift; tilt]: Rodrigues with
    the coefficients' Taylor series in t^2 (the closed forms for a lane with t^2 >= SMALL); co: a
    4 x W scratch for t^2 and the coefficients. Separate loops, so that each one vectorises."""
    for l in range(W):
        x = d[3 * W + l] * d[3 * W + l] + d[4 * W + l] * d[4 * W + l] + d[5 * W + l] * d[5 * W + l]
        co[0 * W + l] = x
        # sin t/t, (1 - cos t)/t^2, (t - sin t)/t^3 to x^5 (Horner)
        co[1 * W + l] = 1.0 - x * (1.0 / 6.0) * (1.0 - x * (1.0 / 20.0) * (1.0 - x * (1.0 / 42.0) * (1.0 - x * (1.0 / 72.0) * (1.0 - x * (1.0 / 110.0)))))
        co[2 * W + l] = 0.5 - x * (1.0 / 24.0) * (1.0 - x * (1.0 / 30.0) * (1.0 - x * (1.0 / 56.0) * (1.0 - x * (1.0 / 90.0) * (1.0 - x * (1.0 / 132.0)))))
        co[3 * W + l] = 1.0 / 6.0 - x * (1.0 / 120.0) * (1.0 - x * (1.0 / 42.0) * (1.0 - x * (1.0 / 72.0) * (1.0 - x * (1.0 / 110.0) * (1.0 - x * (1.0 / 156.0)))))
    big = 0.0
    for l in range(W):
        big = max(big, co[0 * W + l])
    if not big < SMALL:                           # also NaN: the closed forms say what they say
        for l in range(W):
            x = co[0 * W + l]
            if not x < SMALL:
                t = np.sqrt(x)
                sn, cs = np.sin(t), np.cos(t)
                co[1 * W + l], co[2 * W + l], co[3 * W + l] = sn / t, (1.0 - cs) / x, (t - sn) / (x * t)
    for l in range(W):
        wx, wy, wz, x, A, B, Cc = d[3 * W + l], d[4 * W + l], d[5 * W + l], co[0 * W + l], co[1 * W + l], co[2 * W + l], co[3 * W + l]
        xx, yy, zz, xy, xz, yz = wx * wx - x, wy * wy - x, wz * wz - x, wx * wy, wx * wz, wy * wz
        E[0 * W + l], E[1 * W + l], E[2 * W + l] = 1.0 + B * xx, -A * wz + B * xy, A * wy + B * xz
        E[4 * W + l], E[5 * W + l], E[6 * W + l] = A * wz + B * xy, 1.0 + B * yy, -A * wx + B * yz
        E[8 * W + l], E[9 * W + l], E[10 * W + l] = -A * wy + B * xz, A * wx + B * yz, 1.0 + B * zz
        v0, v1, v2 = d[0 * W + l], d[1 * W + l], d[2 * W + l]
        E[3 * W + l] = (1.0 + Cc * xx) * v0 + (-B * wz + Cc * xy) * v1 + (B * wy + Cc * xz) * v2
        E[7 * W + l] = (B * wz + Cc * xy) * v0 + (1.0 + Cc * yy) * v1 + (-B * wx + Cc * yz) * v2
        E[11 * W + l] = (-B * wy + Cc * xz) * v0 + (B * wx + Cc * yz) * v1 + (1.0 + Cc * zz) * v2


@njit(cache=True, error_model="numpy")
def _joint_coefficients(kind, dl, J):
    """J (2 rows of W): cos and sin of the joint errors dl (kind 1; series below SMALL), or dl itself (kind 2)."""
    if kind == 2:
        for l in range(W):
            J[l] = dl[l]
        return
    for l in range(W):
        u = dl[l]
        x = u * u
        J[1 * W + l] = u * (1.0 - x * (1.0 / 6.0) * (1.0 - x * (1.0 / 20.0) * (1.0 - x * (1.0 / 42.0) * (1.0 - x * (1.0 / 72.0) * (1.0 - x * (1.0 / 110.0))))))
        J[0 * W + l] = 1.0 - x * (1.0 / 2.0) * (1.0 - x * (1.0 / 12.0) * (1.0 - x * (1.0 / 30.0) * (1.0 - x * (1.0 / 56.0) * (1.0 - x * (1.0 / 90.0) * (1.0 - x * (1.0 / 132.0))))))
    big = 0.0
    for l in range(W):
        big = max(big, dl[l] * dl[l])
    if not big < SMALL:
        for l in range(W):
            if not dl[l] * dl[l] < SMALL:
                J[0 * W + l], J[1 * W + l] = np.cos(dl[l]), np.sin(dl[l])


@njit(cache=True, error_model="numpy")
def _joint_apply(T, kind, J):
    """T <- T Rot(z) lane by lane (kind 1, J = cos, sin rows) or T Trans(z, J[0]) (kind 2)."""
    if kind == 2:
        for i in range(3):
            for l in range(W):
                T[(4 * i + 3) * W + l] += J[0 * W + l] * T[(4 * i + 2) * W + l]
        return
    for i in range(3):
        for l in range(W):
            x, y = T[(4 * i) * W + l], T[(4 * i + 1) * W + l]
            T[(4 * i) * W + l] = J[0 * W + l] * x + J[1 * W + l] * y
            T[(4 * i + 1) * W + l] = -J[1 * W + l] * x + J[0 * W + l] * y


@njit(cache=True, error_model="numpy")
def _sample_ops(kind, var, a, op_stage, op_p, p_col, p_field, op_j, j_col, j_coef, j_var, v_col, v_var, e, q, k0, nk,
                EK, JK, d, co, off, dl, eg):
    """The operations of samples k0 <= k < k0 + nk (rows of e (m, n_cols)) at joint values q:
    EK (K, 12 W) the placement exponentials, JK (K, 2 W) the joint errors' coefficients (eg: an
    n_cols x W scratch; lanes from nk on are zero errors)."""
    if nk < W:                                 # the group's errors, one row per column (lanes contiguous)
        eg[:] = 0.0
    for l in range(nk):                        # read sample by sample: e streams from memory in its order
        row = e[k0 + l]
        for col in range(e.shape[1]):
            eg[col * W + l] = row[col]
    # rows as slices of W lanes: a row index read from the program inside the lane loop keeps LLVM
    # from vectorising it (same sums, same order)
    off[:] = 0.0
    for t in range(v_col.shape[0]):
        _add_row(off[v_var[t] * W:(v_var[t] + 1) * W], eg[v_col[t] * W:(v_col[t] + 1) * W])
    for k in range(op_stage.shape[0]):
        if op_p[k + 1] > op_p[k]:
            d[:] = 0.0
            for t in range(op_p[k], op_p[k + 1]):
                _add_row(d[p_field[t] * W:(p_field[t] + 1) * W], eg[p_col[t] * W:(p_col[t] + 1) * W])
            _exp6_lanes(d, EK[k], co)
        s = op_stage[k]
        if s >= 0:                                # offsets and joint terms
            a_s, o = a[s], off[var[s] * W:(var[s] + 1) * W]
            for l in range(W):
                dl[l] = a_s * o[l]
            for t in range(op_j[k], op_j[k + 1]):
                c_t, v, x = j_coef[t], j_var[t], eg[j_col[t] * W:(j_col[t] + 1) * W]
                if v >= 0:
                    qv, ov = q[v], off[v * W:(v + 1) * W]
                    for l in range(W):
                        dl[l] += x[l] * (c_t * (qv + ov[l]))
                else:
                    for l in range(W):
                        dl[l] += x[l] * (c_t * 1.0)
            _joint_coefficients(kind[s], dl, JK[k])


@njit(cache=True, inline="always", error_model="numpy")
def _add_row(dst, src):
    """dst += src (rows of W lanes)."""
    for l in range(W):
        dst[l] += src[l]


@njit(cache=True, error_model="numpy")
def _apply_ops(T, T2, C, EK, JK, kind, op_stage, op_p, seg_start):
    """The perturbed tips C_0 O_1 C_1 ... O_K C_K of a group (module docstring); returns T or T2."""
    for r in range(3):
        for j in range(4):
            for l in range(W):
                T[(4 * r + j) * W + l] = C[0, r, j]
    for k in range(op_stage.shape[0]):
        if op_p[k + 1] > op_p[k]:
            _lanes_times_lanes(T, EK[k], T2)
            T, T2 = T2, T
        if op_stage[k] >= 0:
            _joint_apply(T, kind[op_stage[k]], JK[k])
        if seg_start[k + 2] > seg_start[k + 1]:
            _lanes_times_constant(T, C[k + 1], T2)
            T, T2 = T2, T
    return T


@njit(cache=True, inline="always", error_model="numpy")
def _rotation_lane(T, T0, l):
    """R R0^T of lane l, row-major as a 9-tuple."""
    def row(u, v):
        return T[(4 * u) * W + l] * T0[v, 0] + T[(4 * u + 1) * W + l] * T0[v, 1] + T[(4 * u + 2) * W + l] * T0[v, 2]
    return (row(0, 0), row(0, 1), row(0, 2), row(1, 0), row(1, 1), row(1, 2), row(2, 0), row(2, 1), row(2, 2))


@njit(cache=True, error_model="numpy")
def _tip_error(T, T0, res, i, k0, nk, out):
    """out[i, k0 + l] = [p - p0; rotation vector of R R0^T] for the lanes l < nk (res: an 8 x W scratch)."""
    for l in range(W):
        r = _rotation_lane(T, T0, l)
        vx, vy, vz = 0.5 * (r[7] - r[5]), 0.5 * (r[2] - r[6]), 0.5 * (r[3] - r[1])
        s2 = vx * vx + vy * vy + vz * vz
        f = 1.0 + s2 * (1.0 / 6.0 + s2 * (3.0 / 40.0 + s2 * (5.0 / 112.0 + s2 * (35.0 / 1152.0))))   # asin(s)/s
        res[0 * W + l], res[1 * W + l], res[2 * W + l] = vx, vy, vz
        res[3 * W + l], res[4 * W + l], res[5 * W + l] = s2, 0.5 * (r[0] + r[4] + r[8] - 1.0), f
    for l in range(nk):
        f = res[5 * W + l]
        if not (res[3 * W + l] < SMALL_ROT and res[4 * W + l] > 0.0):   # beyond 0.01 rad: serial_kernels._rotvec's closed form
            th = np.arccos(min(1.0, max(-1.0, res[4 * W + l])))
            f = 1.0 + th * th / 6.0 if th < 1e-8 else th / np.sin(th)
        for u in range(3):
            out[i, k0 + l, u] = T[(4 * u + 3) * W + l] - T0[u, 3]
            out[i, k0 + l, 3 + u] = res[u * W + l] * f


@njit(cache=True, error_model="numpy")
def _task(P, kind, var, a, c, seg_start, fac_kind, fac_stage, op_stage, op_p, p_col, p_field, op_j, j_col, j_coef,
          j_var, v_col, v_var, Q, errors, i, lo, hi, out):
    """Samples lo <= k < hi of pose i into out (one scratch set, W samples at a time)."""
    K = op_stage.shape[0]
    C = np.empty((K + 1, 3, 4))
    T0 = np.empty((3, 4))
    _constants(P, kind, var, a, c, Q[i], seg_start, fac_kind, fac_stage, C, T0)
    EK, JK = np.empty((K, 12 * W)), np.empty((K, 2 * W))
    T, T2, d, co, res = np.empty(12 * W), np.empty(12 * W), np.empty(6 * W), np.empty(4 * W), np.empty(8 * W)
    off, dl, eg = np.empty(Q.shape[1] * W), np.empty(W), np.empty(errors.shape[2] * W)
    e = errors[i]
    for k0 in range(lo, hi, W):
        nk = min(W, hi - k0)
        _sample_ops(kind, var, a, op_stage, op_p, p_col, p_field, op_j, j_col, j_coef, j_var, v_col, v_var, e, Q[i], k0,
                    nk, EK, JK, d, co, off, dl, eg)
        Tt = _apply_ops(T, T2, C, EK, JK, kind, op_stage, op_p, seg_start)
        _tip_error(Tt, T0, res, i, k0, nk, out)


@njit(cache=True, nogil=True, error_model="numpy")
def pose_error_tasks(P, kind, var, a, c, seg_start, fac_kind, fac_stage, op_stage, op_p, p_col, p_field, op_j, j_col,
                     j_coef, j_var, v_col, v_var, Q, errors, b0, b1, out):
    """Tasks ``b0 <= b < b1`` of :func:`pose_error` into ``out`` (n, m, 6): task ``b`` is pose ``b // per`` and
    its samples from ``(b % per) TASK`` (``per`` tasks a pose, :data:`TASK` samples each)."""
    m = errors.shape[1]
    per = (m + TASK - 1) // TASK
    for b in range(b0, b1):
        i, lo = b // per, (b % per) * TASK
        _task(P, kind, var, a, c, seg_start, fac_kind, fac_stage, op_stage, op_p, p_col, p_field, op_j, j_col, j_coef,
              j_var, v_col, v_var, Q, errors, i, lo, min(m, lo + TASK), out)


def pose_error(*args):
    """(n, m, 6) ``[dp (m); rotation vector of R R0^T (rad)]`` of the perturbed tip for errors
    (n, m, n_cols) at joint values Q (n, n_vars): tasks of one pose and up to :data:`TASK` samples,
    run on the cores by threads (:func:`~evotol.robots.mechanism.kinematics.task_threads.run_tasks`);
    each sample's arithmetic does not depend on the number of threads.

    Parameters
    ----------
    *args
        The program (module docstring: ``P`` .. ``v_var``), then ``Q`` (n, n_vars), the poses' joint
        values (rad or m), one row per pose, and ``errors`` (n, m, n_cols), source errors (m or rad);
        any strides (a broadcast array is read as it is).

    Returns
    -------
    (n, m, 6) ndarray
        The tip's error relative to the nominal, base frame.
    """
    errors = args[-1]
    n, m = errors.shape[0], errors.shape[1]
    out = np.empty((n, m, 6))
    run_tasks(lambda b0, b1: pose_error_tasks(*args, b0, b1, out), n * ((m + TASK - 1) // TASK))
    return out


@njit(cache=True, nogil=True, error_model="numpy")
def _shared_ops(kind, var, a, op_stage, op_p, p_col, p_field, op_j, j_col, j_coef, j_var, v_col, v_var, q, errors, g0,
                ga, gb, EK, JK):
    """The operations of sample groups ``g0 + g`` (``ga <= g < gb``, :data:`W` samples each) into ``EK[g]``, ``JK[g]``."""
    m = errors.shape[0]
    for g in range(ga, gb):
        k0 = (g0 + g) * W
        _sample_ops(kind, var, a, op_stage, op_p, p_col, p_field, op_j, j_col, j_coef, j_var, v_col, v_var, errors, q, k0,
                    min(W, m - k0), EK[g], JK[g], np.empty(6 * W), np.empty(4 * W), np.empty(q.shape[0] * W),
                    np.empty(W), np.empty(errors.shape[1] * W))


@njit(cache=True, nogil=True, error_model="numpy")
def _shared_apply(P, kind, var, a, c, seg_start, fac_kind, fac_stage, op_stage, op_p, Q, m, g0, ng, EK, JK, i0, i1, out):
    """Groups ``g0 <= g0 + g < g0 + ng`` of samples applied at poses ``i0 <= i < i1`` into ``out`` (n, m, 6)."""
    K = op_stage.shape[0]
    C, T0 = np.empty((K + 1, 3, 4)), np.empty((3, 4))
    T, T2, res = np.empty(12 * W), np.empty(12 * W), np.empty(8 * W)
    for i in range(i0, i1):
        _constants(P, kind, var, a, c, Q[i], seg_start, fac_kind, fac_stage, C, T0)
        for g in range(ng):
            k0 = (g0 + g) * W
            Tt = _apply_ops(T, T2, C, EK[g], JK[g], kind, op_stage, op_p, seg_start)
            _tip_error(Tt, T0, res, i, k0, min(W, m - k0), out)


def pose_error_shared(*args):
    """:func:`pose_error` for the same samples errors (m, n_cols) at every pose (no joint term
    scaled by a joint value, ``j_var`` all -1): the operations of :data:`TASK` samples at a time are
    computed once, on the cores, then applied at every pose, on the cores (threads, as :func:`pose_error`).

    Parameters
    ----------
    *args
        The program (module docstring: ``P`` .. ``v_var``), then ``Q`` (n, n_vars), the poses' joint
        values (rad or m), one row per pose, and ``errors`` (m, n_cols), source errors (m or rad) shared by
        every pose.

    Returns
    -------
    (n, m, 6) ndarray
        The tip's error relative to the nominal, base frame.
    """
    (P, kind, var, a, c, seg_start, fac_kind, fac_stage, op_stage, op_p, p_col, p_field, op_j, j_col, j_coef, j_var,
     v_col, v_var, Q, errors) = args
    n, m, K = Q.shape[0], errors.shape[0], op_stage.shape[0]
    out = np.empty((n, m, 6))
    G, CH = (m + W - 1) // W, TASK // W
    EK, JK = np.empty((CH, K, 12 * W)), np.empty((CH, K, 2 * W))
    for g0 in range(0, G, CH):
        ng = min(CH, G - g0)
        run_tasks(lambda ga, gb: _shared_ops(kind, var, a, op_stage, op_p, p_col, p_field, op_j, j_col, j_coef, j_var,
                                             v_col, v_var, Q[0], errors, g0, ga, gb, EK, JK), ng)
        run_tasks(lambda i0, i1: _shared_apply(P, kind, var, a, c, seg_start, fac_kind, fac_stage, op_stage, op_p, Q, m,
                                               g0, ng, EK, JK, i0, i1, out), n)
    return out
