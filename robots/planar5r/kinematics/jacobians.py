"""Jacobians and conditioning of the planar 5R mechanism (Lara-Molina et al. 2019, Secs. 2.4 and 3).

``J_x dP = J_q dtheta`` from differentiating ``|P - B_i|^2 = r2^2``; the type II determinant
``det J_x`` (its sign is the assembly mode), the closed-form inverse condition number of 2x2
matrices and the local conditioning index (LCI, Gao et al. 1998).

The parameters several definitions of this module share are described once, here.

Parameters
----------
p : array_like, shape (..., 2)
    End-effector positions, length unit.
theta : array_like, shape (..., 2)
    Crank angles ``theta_1, theta_2`` at ``p``, rad.
"""
from __future__ import annotations

import numpy as np

from evotol.robots.planar5r.kinematics.conventions import DEFAULT_WORKING_MODE, _as_points, cross2
from evotol.robots.planar5r.kinematics.position import crank_points, inverse_kinematics


def jacobians(p, theta, r1, r3):
    """``J_x dP = J_q dtheta`` from differentiating ``|P - B_i|^2 = r2^2``.

    ``J_x`` (..., 2, 2) has rows ``(P - B_i)^T``; ``J_q`` (..., 2) is the diagonal
    ``cross(B_i - A_i, P - B_i)``. Type II singular: ``det J_x = 0``; type I: ``J_q,i = 0``.

    Returns
    -------
    J_x : ndarray, shape (..., 2, 2)
        Rows ``P - B_i``, length unit.
    J_q : ndarray, shape (..., 2)
        Diagonal of ``J_q``, length unit squared per rad.
    """
    p = np.asarray(p, dtype=float)
    B = crank_points(theta, r1, r3)
    w = p[..., None, :] - B                                      # (..., 2, 2): rows P - B_i
    ax = np.array([-r3, r3], dtype=float) if np.ndim(r3) == 0 else np.stack([-r3, r3], axis=-1)
    bax, bay = B[..., 0] - ax, B[..., 1]
    jq = cross2(bax, bay, w[..., 0], w[..., 1])
    return w, jq


def jacobian(p, theta, r1, r3) -> np.ndarray:
    """``J = J_x^{-1} diag(J_q)``, (..., 2, 2): ``dP = J dtheta`` (length per radian).

    Returns
    -------
    ndarray, shape (..., 2, 2)
        ``dP / dtheta``, length unit per rad.
    """
    jx, jq = jacobians(p, theta, r1, r3)
    return np.linalg.solve(jx, jq[..., :, None] * np.eye(2))


def type2_determinant(p, theta, r1, r3) -> np.ndarray:
    """``det J_x = cross(P - B_1, P - B_2)``; its sign is the assembly mode sigma.

    Returns
    -------
    ndarray, shape (...)
        ``det J_x``, length unit squared.
    """
    jx, _ = jacobians(p, theta, r1, r3)
    return jx[..., 0, 0] * jx[..., 1, 1] - jx[..., 0, 1] * jx[..., 1, 0]


def inverse_condition_number(M) -> np.ndarray:
    """``sigma_min / sigma_max`` of 2x2 matrices (..., 2, 2), in closed form.

    With ``k = ||M||_F^2 / (2 |det M|)``: ``sigma_max / sigma_min = k + sqrt(k^2 - 1)``.
    Returns 0 for a singular matrix.

    Parameters
    ----------
    M : array_like, shape (..., 2, 2)
        Matrices.

    Returns
    -------
    ndarray, shape (...)
        Inverse condition number, dimensionless, in [0, 1].
    """
    M = np.asarray(M, dtype=float)
    fro2 = np.sum(M * M, axis=(-2, -1))
    det = np.abs(M[..., 0, 0] * M[..., 1, 1] - M[..., 0, 1] * M[..., 1, 0])
    with np.errstate(divide="ignore", invalid="ignore"):
        k = fro2 / (2 * det)
        out = 1.0 / (k + np.sqrt(np.maximum(k * k - 1.0, 0.0)))
    return np.where(det > 0, out, 0.0)


def local_conditioning_index(p, r1, r2, r3, working_mode=DEFAULT_WORKING_MODE) -> np.ndarray:
    """LCI = 1 / cond(J) at positions ``p`` (..., 2) (Sec. 3; Gao et al. 1998), in [0, 1].

    Uses ``adj(J_x) diag(J_q)``, which has the condition number of ``J`` and stays finite at
    type II singularities (LCI = 0 there).

    Returns
    -------
    ndarray, shape (...)
        LCI, dimensionless, in [0, 1].

    Raises
    ------
    ValidationError, KinematicsError
        As :func:`~evotol.robots.planar5r.kinematics.position.inverse_kinematics`.
    """
    p = _as_points(p)
    theta = inverse_kinematics(p, r1, r2, r3, working_mode)
    jx, jq = jacobians(p, theta, r1, r3)
    adj = np.stack([np.stack([jx[..., 1, 1], -jx[..., 0, 1]], -1),
                    np.stack([-jx[..., 1, 0], jx[..., 0, 0]], -1)], -2)
    return inverse_condition_number(adj * jq[..., None, :])
