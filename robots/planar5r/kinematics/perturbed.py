"""Forward kinematics of the planar 5R mechanism with errors (Lara-Molina et al. 2019, Sec. 2.5).

Geometric errors of the links and the base, actuator errors and joint clearances (the
effective-link model of a revolute joint with clearance) displace the joint centres of each
chain; the end-effector is the intersection of the perturbed coupler circles.
"""
from __future__ import annotations

import numpy as np

from evotol.robots.planar5r.kinematics.position import circle_intersection

#: Names of the scalar error parameters understood by :func:`perturbed_position` (lengths in the
#: unit of r1..r3, angles in rad). ``c*x, c*y`` are clearance displacement vectors.
ERROR_PARAMETERS = ("dA1B1", "dA2B2", "dB1P", "dB2P", "dOA1", "dOA2", "dth1", "dth2",
                    "cA1x", "cA1y", "cA2x", "cA2y", "cB1x", "cB1y", "cB2x", "cB2y")


def perturbed_position(theta, r1, r2, r3, errors: dict, assembly=1):
    """End-effector position with geometric errors, actuator errors and joint clearances.

    Each chain is an open loop ``O -> A_i -> B_i`` whose joint centres are displaced by the
    clearance vectors (the effective-link model of a revolute joint with clearance, Sec. 2.5)::

        A_1 = (-(r3 + dOA1), 0) + c_A1,          A_2 = (r3 + dOA2, 0) + c_A2
        B_i = A_i + (r1 + dA_iB_i) e(theta_i + dth_i) + c_Bi
        |P - B_i| = r2 + dB_iP   (i = 1, 2)    ->    P = circle intersection (assembly sigma)

    ``theta`` (..., 2) are the nominal crank angles; every entry of ``errors`` (see
    :data:`ERROR_PARAMETERS`; missing = 0) broadcasts against ``theta[..., 0]``, so all poses x
    all samples are one array pass. ``cos(theta + dth)`` is expanded as
    ``cos theta cos dth - sin theta sin dth`` so the trigonometry runs once per pose and once
    per sample, not once per pose-sample. Returns ``px, py, h2`` (``h2 < 0``: no assembly).

    Parameters
    ----------
    theta : array_like, shape (..., 2)
        Nominal crank angles, rad.
    errors : dict of str to array_like
        Error values by name of :data:`ERROR_PARAMETERS` (lengths and clearance components in
        the length unit, ``dth*`` in rad); missing names are zero.

    Returns
    -------
    px, py : ndarray
        Perturbed end-effector position, length unit, of the broadcast shape.
    h2 : ndarray
        ``(h / d)^2`` of :func:`~evotol.robots.planar5r.kinematics.position.circle_intersection`, dimensionless (``< 0``: no assembly).
    """
    g = errors.get
    theta = np.asarray(theta, dtype=float)
    pts = []
    for i, (side, A, B) in enumerate(((-1.0, "A1", "B1"), (1.0, "A2", "B2"))):
        th = theta[..., i]
        c, s = np.cos(th), np.sin(th)
        dth = g(f"dth{i + 1}")
        if dth is not None:
            cd, sd = np.cos(dth), np.sin(dth)
            c, s = c * cd - s * sd, s * cd + np.cos(th) * sd
        crank = r1 + g(f"d{A}{B}", 0.0)
        bx = side * (r3 + g(f"dO{A}", 0.0)) + g(f"c{A}x", 0.0) + g(f"c{B}x", 0.0) + crank * c
        by = g(f"c{A}y", 0.0) + g(f"c{B}y", 0.0) + crank * s
        pts.append((bx, by, r2 + g(f"d{B}P", 0.0)))
    (b1x, b1y, rho1), (b2x, b2y, rho2) = pts
    return circle_intersection(b1x, b1y, rho1, b2x, b2y, rho2, assembly)

