"""Position kinematics of the planar 5R mechanism (Lara-Molina et al. 2019, Sec. 2.3, eqs. 9-15).

Inverse kinematics in the four working modes (law of cosines in each chain) and forward
kinematics in both assembly modes (intersection of the coupler circles), with the paper's
closed form eqs. 13-15 beside it. Frame and branch signs: :mod:`.conventions`.

The parameters several definitions of this module share are described once, here.

Parameters
----------
theta : array_like, shape (..., 2)
    Crank angles, rad.
"""
from __future__ import annotations

import numpy as np

from evotol.errors import KinematicsError
from evotol.robots.planar5r.kinematics.conventions import (
    DEFAULT_WORKING_MODE, _as_float, _as_points, _check_assembly, _common_float, working_mode_signs)


# --------------------------------------------------------------------------------------------
# Inverse kinematics
# --------------------------------------------------------------------------------------------
def inverse_kinematics_raw(px, py, r1, r2, r3, working_mode=DEFAULT_WORKING_MODE):
    """Crank angles ``theta_1, theta_2`` (rad) and a reachability mask, without raising.

    ``theta_i = atan2(P - A_i) + m_i * arccos((r1^2 + rho_i^2 - r2^2) / (2 r1 rho_i))`` with
    ``rho_i = |P - A_i|`` (law of cosines in the triangle ``A_i B_i P``). A pose is reachable by
    chain ``i`` when ``|r1 - r2| <= rho_i <= r1 + r2`` (inside the annulus of eqs. 16-19).
    Returns ``theta1, theta2, reachable`` (unreachable entries hold a clipped, meaningless value).

    Parameters
    ----------
    px, py : array_like
        End-effector coordinates, length unit, broadcastable.

    Returns
    -------
    theta1, theta2 : ndarray
        Crank angles, rad, of the broadcast shape of ``px, py``.
    reachable : ndarray of bool
        True where both chains reach ``P``.

    Raises
    ------
    ValidationError
        If ``working_mode`` is invalid.
    """
    m1, m2 = working_mode_signs(working_mode)
    px, py, r1, r2, r3 = _common_float(px, py, r1, r2, r3)
    out = []
    ok = np.ones(np.broadcast(px, py).shape, dtype=bool)
    for ax, m in ((-r3, m1), (r3, m2)):
        dx, dy = px - ax, py
        rho = np.hypot(dx, dy)
        with np.errstate(divide="ignore", invalid="ignore"):
            c = (r1 * r1 + rho * rho - r2 * r2) / (2.0 * r1 * rho)
        ok &= np.isfinite(c) & (np.abs(c) <= 1.0)
        out.append(np.arctan2(dy, dx) + m * np.arccos(np.clip(np.nan_to_num(c), -1.0, 1.0)))
    return out[0], out[1], ok


def inverse_kinematics(p, r1, r2, r3, working_mode=DEFAULT_WORKING_MODE) -> np.ndarray:
    """Crank angles (rad), shape (..., 2), for end-effector positions ``p`` (..., 2).

    Raises :class:`KinematicsError` naming the first pose outside the theoretical workspace.

    Parameters
    ----------
    p : array_like, shape (..., 2)
        End-effector positions ``(x, y)``, length unit.
    r1, r2, r3 : float or array_like
        Crank ``A_iB_i``, coupler ``B_iP`` and half base ``OA_i`` lengths, in one length unit
        (dimensionless in the paper, m in :class:`~evotol.robots.planar5r.model.Planar5R`); arrays
        broadcast with ``p[..., 0]`` (one set of lengths per pose).

    Returns
    -------
    ndarray, shape (..., 2)
        Crank angles ``theta_1, theta_2``, rad.

    Raises
    ------
    ValidationError
        If ``p`` is not a finite (..., 2) array or ``working_mode`` is invalid.
    KinematicsError
        If a pose is outside the theoretical workspace (eqs. 16-19).
    """
    p = _as_points(p)
    t1, t2, ok = inverse_kinematics_raw(p[..., 0], p[..., 1], r1, r2, r3, working_mode)
    if not np.all(ok):
        bad = p[~ok]
        # the lengths at that pose (they may be arrays broadcast with the poses)
        l1, l2, l3 = (np.broadcast_to(np.asarray(r), ok.shape)[~ok][0] for r in (r1, r2, r3))
        raise KinematicsError(f"5R: pose {bad[0].tolist()} (x, y) is outside the theoretical workspace "
                              f"(eqs. 16-19) of r1={l1:g}, r2={l2:g}, r3={l3:g}", poses=bad)
    return np.stack([t1, t2], axis=-1)


# --------------------------------------------------------------------------------------------
# Forward kinematics
# --------------------------------------------------------------------------------------------
def circle_intersection(c1x, c1y, rho1, c2x, c2y, rho2, assembly=1):
    """Point at distance ``rho1`` from ``C1`` and ``rho2`` from ``C2`` on the side ``assembly``.

    ``P = C1 + (a/d)(C2 - C1) + sigma (h/d) rot90(C2 - C1)``, ``a = (d^2 + rho1^2 - rho2^2)/(2d)``,
    ``h = sqrt(rho1^2 - a^2)``. Returns ``px, py, h2_over_d2``; ``h2_over_d2 < 0`` means the two
    circles do not meet (no assembly), ``== 0`` a type II singularity.

    Parameters
    ----------
    c1x, c1y : array_like
        Centre ``C1``, length unit.
    rho1 : array_like
        Radius about ``C1``, length unit.
    c2x, c2y : array_like
        Centre ``C2``, length unit.
    rho2 : array_like
        Radius about ``C2``, length unit.
    assembly : {1, -1} or array_like
        sigma: +1 puts ``P`` on the left of ``C1 -> C2``.

    Returns
    -------
    px, py : ndarray
        Intersection point, length unit (on the line ``C1C2`` when the circles do not meet).
    h2_over_d2 : ndarray
        ``(h / d)^2``, dimensionless.
    """
    dx, dy = c2x - c1x, c2y - c1y
    d2 = dx * dx + dy * dy
    r1s = rho1 * rho1
    with np.errstate(divide="ignore", invalid="ignore"):
        a = 0.5 + 0.5 * (r1s - rho2 * rho2) / d2
        h2 = r1s / d2 - a * a
    k = assembly * np.sqrt(np.maximum(h2, 0.0))
    return c1x + a * dx - k * dy, c1y + a * dy + k * dx, h2


def crank_points(theta, r1, r3) -> np.ndarray:
    """Elbows ``B_i = A_i + r1 (cos theta_i, sin theta_i)``, shape (..., 2 chains, 2).

    Returns
    -------
    ndarray, shape (..., 2, 2)
        ``B_1`` and ``B_2`` (axis -2), ``(x, y)`` in the length unit (axis -1).
    """
    theta = _as_float(theta)
    bx = np.stack([-r3 + r1 * np.cos(theta[..., 0]), r3 + r1 * np.cos(theta[..., 1])], axis=-1)
    by = r1 * np.sin(theta)
    return np.stack([bx, by], axis=-1)


def forward_kinematics(theta, r1, r2, r3, assembly=1) -> np.ndarray:
    """End-effector ``P`` (..., 2) from crank angles ``theta`` (..., 2), rad (Sec. 2.3).

    Solved as the intersection of the circles of radius ``r2`` about ``B_1`` and ``B_2`` (the
    constraints eqs. 9-12), which is what eqs. 13-15 do, without eq. 13's division by
    ``2 r3 + r1 (cos theta_2 - cos theta_1)`` (zero when ``B_1B_2`` is vertical).
    Raises :class:`KinematicsError` when the couplers cannot close the loop.

    Parameters
    ----------
    theta : array_like, shape (..., 2)
        Crank angles ``theta_1, theta_2``, rad.

    Returns
    -------
    ndarray, shape (..., 2)
        End-effector positions ``(x, y)``, length unit.

    Raises
    ------
    ValidationError
        If ``assembly`` is not +1 or -1.
    KinematicsError
        If the couplers cannot close the loop for some ``theta``.
    """
    assembly = _check_assembly(assembly)
    theta, r1, r2, r3 = _common_float(theta, r1, r2, r3)
    B = crank_points(theta, r1, r3)
    px, py, h2 = circle_intersection(B[..., 0, 0], B[..., 0, 1], r2, B[..., 1, 0], B[..., 1, 1], r2, assembly)
    bad = ~(h2 >= 0)
    if np.any(bad):
        raise KinematicsError(f"5R: crank angles {theta[bad][0].tolist()} (rad) cannot be assembled "
                              f"(|B1B2| > 2 r2 or B1 = B2)", poses=theta[bad])
    return np.stack([px, py], axis=-1)


def forward_kinematics_eq15(theta, r1, r2, r3, sigma=1, printed=False) -> np.ndarray:
    """The paper's closed form, eqs. 13-15 (``x = e y + f``, ``d y^2 + g y + h = 0``).

    ``printed=False`` uses ``e = r1 (sin theta_1 - sin theta_2) / den``, which is what subtracting
    eq. 12 from eq. 11 gives (verified in the tests). ``printed=True`` uses ``e`` exactly as
    printed, ``r1 (cos(theta_1 + dtheta_1) - sin(theta_1 + dtheta_2)) / den``, a typo that does
    not satisfy the constraints. ``sigma = +1`` is the larger root ``y`` (the paper's choice).
    Kept for reference and for the test that checks eqs. 11-15 against :func:`forward_kinematics`;
    it divides by zero when ``B_1B_2`` is vertical.

    Parameters
    ----------
    sigma : {1, -1}
        Root of eq. 14 (+1: the larger ``y``).
    printed : bool
        Use eq. 13's ``e`` as printed (a typo) instead of the derived one.

    Returns
    -------
    ndarray, shape (..., 2)
        End-effector positions, length unit (NaN where the root is complex).
    """
    theta = np.asarray(theta, dtype=float)
    c1, c2 = np.cos(theta[..., 0]), np.cos(theta[..., 1])
    s1, s2 = np.sin(theta[..., 0]), np.sin(theta[..., 1])
    den = 2 * r3 + r1 * c2 - r1 * c1
    e = r1 * ((c1 - s1) if printed else (s1 - s2)) / den
    f = r1 * r3 * (c1 + c2) / den
    d = 1 + e * e
    g = 2 * (e * f - e * r1 * c1 + e * r3 - r1 * s1)
    h = f * f - 2 * f * (r1 * c1 - r3) - 2 * r1 * r3 * c1 + r3 * r3 + r1 * r1 - r2 * r2
    y = (-g + sigma * np.sqrt(g * g - 4 * d * h)) / (2 * d)
    return np.stack([e * y + f, y], axis=-1)
