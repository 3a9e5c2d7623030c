"""The thesis's own method, kept as a baseline: equality elimination + multistart local optimisation.

Deng 2012 (eqs. III.29-III.48 for simple legs, V.15-V.37 for hybrid legs) removes the loop
equalities by a QR factorisation of the transposed error mapping matrices, leaving
``v`` free variables ``delta u`` (24 for the 5-bar, 78 / 114 for the IRSBot-2), and maximises the
convex quadratic ``||dp||^2`` (or ``||dtheta||^2``) under the quadratic clearance constraints
``delta u^T F delta u <= 1`` with Matlab's ``fmincon`` from 200 starting points per pose.

Here: the same elimination written once for any body/chain graph -- the consistent screws are
``s = D Z z`` with ``Z`` an orthonormal basis (from a QR factorisation) of ``null(B^T)`` in
scaled screws, ``v = dim z`` -- and scipy's SLSQP from ``n_starts`` random feasible starts. The
problem is the thesis's (all six screw components of every joint, no planar split), so the
number of variables matches the thesis's ``v``. A local solver can stop at a local maximum; the
best of the starts is a lower bound on the true maximum, never a certificate.
"""
from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np

from evotol.robots.clearance.model import ClearanceMechanism, PoseMaps


@dataclass
class MultistartResult:
    """Result of the thesis's multistart method (:func:`multistart_max_pose_error`): lower bounds only.

    Parameters
    ----------
    p_max : (n,) ndarray
        Best local maximum of ``||dp||`` per pose, m.
    r_max : (n,) ndarray
        Best local maximum of ``||dtheta||`` per pose, rad.
    p_locals : list of ndarray
        Per pose: the ``||dp||`` (m) reached from each start, ``(n_starts,)``.
    r_locals : list of ndarray
        Per pose: the ``||dtheta||`` (rad) reached from each start.
    n_variables : int
        Number of free variables ``v`` of the thesis (screw rows minus loop equations).
    seconds : float
        Wall-clock time, s.
    """

    p_max: np.ndarray        # (n,) best local maximum of ||dp|| (m)
    r_max: np.ndarray        # (n,) best local maximum of ||dtheta|| (rad)
    p_locals: list           # per pose: the local maxima reached by each start
    r_locals: list
    n_variables: int         # v of the thesis
    seconds: float


def _spatial_maps(mech: ClearanceMechanism, poses) -> PoseMaps:
    return mech.pose_maps(poses, split=False)[0]


def _local_problem(C: np.ndarray, B: np.ndarray, D: np.ndarray, nd: int):
    """Scaled, equality-free form: returns (Ct, Z, cone index lists)."""
    from scipy.linalg import qr      # imported here: scipy costs ~1-2 s at import of evotol.robots.clearance (issue 13)

    Bt = B * D[:, None]
    keep = D > 0                      # zero bounds: the component is fixed at 0
    Bk = Bt[keep]
    R = int(keep.sum())
    if Bk.shape[1]:
        Q, Rr, _ = qr(Bk, mode="full", pivoting=True)
        rank = int(np.sum(np.abs(np.diag(Rr)) > 1e-12 * max(np.abs(Rr).max(), 1e-300)))
        Z = Q[:, rank:]
    else:
        Z = np.eye(R)
    Ct = (C * D[None, :])[:, keep]
    # cones over the kept rows
    rows = np.arange(len(D))
    cones = [rows[2 * c:2 * c + 2] for c in range(nd)] + [rows[r:r + 1] for r in range(2 * nd, len(D))]
    newpos = -np.ones(len(D), int)
    newpos[keep] = np.arange(R)
    cones = [newpos[c] for c in cones if np.all(keep[c])]
    return Ct, Z, cones


def multistart_max(C: np.ndarray, B: np.ndarray, D: np.ndarray, nd: int, n_starts: int, rng) -> tuple[float, np.ndarray]:
    """Best local maximum of ``||C s||`` over the clearance set by SLSQP from ``n_starts`` starts.

    Parameters
    ----------
    C : (k, n_rows) ndarray
        Target rows (m or rad per unit screw row) at one pose.
    B : (n_rows, m) ndarray
        Loop-equation map at the pose (``B^T s = 0``).
    D : (n_rows,) ndarray
        Bound of each row (rad or m); rows with a zero bound are fixed at 0.
    nd : int
        Number of disk cones (their ``2 * nd`` rows come first).
    n_starts : int
        Number of random feasible starting points.
    rng : numpy.random.Generator
        Random number generator of the starts.

    Returns
    -------
    best : float
        Largest local maximum of ``||C s||`` (units of ``C s``: m or rad), a lower bound.
    values : (n_starts,) ndarray
        The value reached from each start (after scaling back into the feasible set).
    """
    from scipy.optimize import minimize

    Ct, Z, cones = _local_problem(C, B, D, nd)
    v = Z.shape[1]
    A = Ct @ Z                                     # objective ||A z||^2
    AtA = A.T @ A
    # the cones' rows stacked, a one-row cone padded with a zero row: one product per call
    Zc = np.zeros((len(cones), 2, v))
    for i, c in enumerate(cones):
        Zc[i, :len(c)] = Z[c]

    def f(z):
        return -z @ AtA @ z, -2 * AtA @ z

    def g(z):
        w = Zc @ z
        return 1.0 - (w * w).sum(1)

    def jg(z):
        return -2 * np.einsum("crv,cr->cv", Zc, Zc @ z)

    cons = [{"type": "ineq", "fun": g, "jac": jg}]
    out = np.empty(n_starts)
    for k in range(n_starts):
        z0 = rng.normal(size=v)
        norms = np.linalg.norm(Zc @ z0, axis=1)
        z0 = z0 / max(norms.max(), 1e-300) * rng.uniform(0.2, 1.0)
        r = minimize(f, z0, jac=True, constraints=cons, method="SLSQP", options=dict(maxiter=300, ftol=1e-14))
        z = r.x
        viol = max(0.0, -g(z).min())
        z = z / np.sqrt(1.0 + viol) if viol > 0 else z   # back into the feasible set
        out[k] = np.linalg.norm(A @ z)
    return float(out.max()), out


def multistart_max_pose_error(mech: ClearanceMechanism, poses, bounds=None, *, n_starts: int = 20,
                              seed: int = 0) -> MultistartResult:
    """The thesis's method at each pose (QR elimination + ``n_starts`` SLSQP local solves).

    Parameters
    ----------
    mech : ClearanceMechanism
        The mechanism (solved as one 6-D block, as in the thesis).
    poses : (n, d) array_like
        Poses in the mechanism's pose coordinates (m).
    bounds : array_like or None, optional
        ``(n_joints, 4)`` or ``(n, n_joints, 4)``, columns ``[beta_xy (rad), beta_z (rad),
        b_xy (m), b_z (m)]``; None (default): the joints' own bounds.
    n_starts : int, optional
        Local solves per pose and target (default 20; the thesis used 200).
    seed : int, optional
        Seed of the random starts (default 0).

    Returns
    -------
    MultistartResult
        Best local maxima per pose (m, rad): lower bounds, not certified.
    """
    t0 = time.perf_counter()
    poses = np.atleast_2d(np.asarray(poses, float))
    pm = _spatial_maps(mech, poses)
    b = mech.default_bounds() if bounds is None else np.asarray(bounds, float)
    b = np.broadcast_to(b, (len(poses), mech.n_joints, 4))
    D = pm.row_bounds(b)
    rng = np.random.default_rng(seed)
    p, r, pl, rl = [], [], [], []
    for i in range(len(poses)):
        best, loc = multistart_max(pm.C_pos[i], pm.B[i], D[i], pm.n_disk, n_starts, rng)
        p.append(best), pl.append(loc)
        best, loc = multistart_max(pm.C_rot[i], pm.B[i], D[i], pm.n_disk, n_starts, rng)
        r.append(best), rl.append(loc)
    nvar = pm.n_rows - pm.n_loops
    return MultistartResult(np.array(p), np.array(r), pl, rl, nvar, time.perf_counter() - t0)
