"""Kinematics of the planar 5R symmetrical parallel mechanism (Lara-Molina et al. 2019, Secs. 2.3-2.4).

Frame and labels (those of the paper's eqs. 11-12, 16-19): ``O`` is the midpoint of the base,
``A_1 = (-r3, 0)``, ``A_2 = (r3, 0)``; the crank ``A_iB_i`` (length ``r1``) turns by the actuated
angle ``theta_i`` measured from the x axis, ``B_i = A_i + r1 (cos theta_i, sin theta_i)``; the
couplers ``B_iP`` (length ``r2``) meet at the end-effector ``P = (x, y)``.

The printed eqs. 9-10 place ``A_1`` at ``(+r3, 0)``; their expansion, eqs. 11-12, and the
workspace circles, eqs. 16-19, place it at ``(-r3, 0)``. We follow eqs. 11-12 / 16-19.

Branches, as signs of cross products (robust, unlike a choice of root):

* **assembly mode** (forward kinematics, the paper's sigma of eq. 15):
  ``sigma = sign(cross(B_2 - B_1, P - B_1)) = sign(det J_x)``, +1 = ``P`` on the left of the
  directed line ``B_1 -> B_2``. When ``B_2`` lies to the right of ``B_1`` (the usual posture)
  this is the larger root ``y`` of eq. 14, i.e. the paper's ``sigma = +1``.
* **working mode** (inverse kinematics): ``m_i = sign(cross(P - A_i, B_i - A_i))``. The default
  ``"+-"`` (``m_1 = +1, m_2 = -1``) has both elbows ``B_i`` outside the triangle ``A_1 P A_2``;
  it is the mode in which the MIC closed forms eqs. 21-22 describe the usable workspace.

Singularities: type I (serial) where ``A_i, B_i, P`` are aligned (``J_q`` singular; the circles
of eqs. 16-19); type II (parallel) where ``B_1, B_2, P`` are aligned (``det J_x = 0``).

Everything works with lengths in any unit (non-dimensional in the paper, metres in the robot
error model); angles in radians. Arrays broadcast; nothing loops in Python.

Precision: positions and angles keep their floating dtype. ``float64`` is the default; pass
``np.longdouble`` arrays (80-bit extended on x86-64, eps = 1.1e-19) when you need the round trip
``forward(inverse(p))`` to hold near the type II border, where the forward problem amplifies the
rounding of ``theta`` by the condition number ``1 / LCI`` (docs/planar5r.md, "Round trip").
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from evotol.errors import KinematicsError, ValidationError

WORKING_MODES = {"+-": (1, -1), "-+": (-1, 1), "++": (1, 1), "--": (-1, -1)}
DEFAULT_WORKING_MODE = "+-"


def working_mode_signs(working_mode) -> tuple[int, int]:
    """Signs ``(m_1, m_2)`` of a working mode (see the module docstring).

    Parameters
    ----------
    working_mode : str or tuple of int
        ``"+-"`` (default), ``"-+"``, ``"++"``, ``"--"`` or a pair ``(m_1, m_2)`` of +1/-1.

    Returns
    -------
    tuple of int
        ``(m_1, m_2)``, each +1 or -1.

    Raises
    ------
    ValidationError
        If ``working_mode`` is neither a known string nor a pair of +1/-1.
    """
    if isinstance(working_mode, str) and working_mode in WORKING_MODES:
        return WORKING_MODES[working_mode]
    if isinstance(working_mode, (tuple, list)) and len(working_mode) == 2 and all(m in (1, -1) for m in working_mode):
        return int(working_mode[0]), int(working_mode[1])
    raise ValidationError("working_mode", working_mode, f"one of {sorted(WORKING_MODES)} or a pair of +-1")


def _check_assembly(assembly) -> int:
    if assembly not in (1, -1):
        raise ValidationError("assembly", assembly, "+1 or -1 (sigma of eq. 15)")
    return int(assembly)


def _as_points(p, field="p") -> np.ndarray:
    try:
        arr = _as_float(p)
    except (TypeError, ValueError) as exc:
        raise ValidationError(field, p, "an array (..., 2) of numbers") from exc
    if arr.ndim == 0 or arr.shape[-1] != 2:
        raise ValidationError(f"{field} shape", arr.shape, "(..., 2)")
    if not np.all(np.isfinite(arr)):
        raise ValidationError(field, arr[~np.all(np.isfinite(arr), axis=-1)][0].tolist(), "finite numbers")
    return arr


def _as_float(x) -> np.ndarray:
    """``x`` as a floating array: float64 unless it already is a wider float (long double)."""
    arr = np.asarray(x)
    return arr.astype(np.result_type(arr.dtype, np.float64), copy=False)


def _common_float(*xs) -> list[np.ndarray]:
    """``xs`` as arrays of their widest floating dtype (so that lengths given as Python floats
    are squared in long double when the poses are long double, not rounded to float64 first)."""
    arrs = [np.asarray(x) for x in xs]
    dtype = np.result_type(np.float64, *(a.dtype for a in arrs))
    return [a.astype(dtype, copy=False) for a in arrs]


def cross2(ax, ay, bx, by):
    """z component of the cross product of two planar vectors.

    Parameters
    ----------
    ax, ay, bx, by : array_like
        Components of the vectors ``a`` and ``b``, broadcastable.

    Returns
    -------
    ndarray or float
        ``ax * by - ay * bx``, in the product of their units.
    """
    return ax * by - ay * bx


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
    r1, r2, r3 : float
        Crank ``A_iB_i``, coupler ``B_iP`` and half base ``OA_i`` lengths, in one length unit
        (dimensionless in the paper, m in :class:`~robots.planar5r.model.Planar5R`).
    working_mode : str or tuple of int
        ``"+-"`` (default), ``"-+"``, ``"++"``, ``"--"`` or a pair ``(m_1, m_2)`` of +1/-1.

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
        (dimensionless in the paper, m in :class:`~robots.planar5r.model.Planar5R`); arrays
        broadcast with ``p[..., 0]`` (one set of lengths per pose).
    working_mode : str or tuple of int
        ``"+-"`` (default), ``"-+"``, ``"++"``, ``"--"`` or a pair ``(m_1, m_2)`` of +1/-1.

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

    Parameters
    ----------
    theta : array_like, shape (..., 2)
        Crank angles, rad.
    r1, r3 : float
        Crank and half-base lengths (the length unit of the positions).

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
    r1, r2, r3 : float
        Crank ``A_iB_i``, coupler ``B_iP`` and half base ``OA_i`` lengths, in one length unit
        (dimensionless in the paper, m in :class:`~robots.planar5r.model.Planar5R`).
    assembly : {1, -1}
        Assembly mode sigma (side of ``B_1 -> B_2`` on which ``P`` lies).

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
    theta : array_like, shape (..., 2)
        Crank angles, rad.
    r1, r2, r3 : float
        Crank ``A_iB_i``, coupler ``B_iP`` and half base ``OA_i`` lengths, in one length unit
        (dimensionless in the paper, m in :class:`~robots.planar5r.model.Planar5R`).
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
    r1, r2, r3 : float
        Crank ``A_iB_i``, coupler ``B_iP`` and half base ``OA_i`` lengths, in one length unit
        (dimensionless in the paper, m in :class:`~robots.planar5r.model.Planar5R`).
    errors : dict of str to array_like
        Error values by name of :data:`ERROR_PARAMETERS` (lengths and clearance components in
        the length unit, ``dth*`` in rad); missing names are zero.
    assembly : {1, -1}
        Assembly mode sigma (side of ``B_1 -> B_2`` on which ``P`` lies).

    Returns
    -------
    px, py : ndarray
        Perturbed end-effector position, length unit, of the broadcast shape.
    h2 : ndarray
        ``(h / d)^2`` of :func:`circle_intersection`, dimensionless (``< 0``: no assembly).
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


# --------------------------------------------------------------------------------------------
# Jacobians, singularities, LCI
# --------------------------------------------------------------------------------------------
def jacobians(p, theta, r1, r3):
    """``J_x dP = J_q dtheta`` from differentiating ``|P - B_i|^2 = r2^2``.

    ``J_x`` (..., 2, 2) has rows ``(P - B_i)^T``; ``J_q`` (..., 2) is the diagonal
    ``cross(B_i - A_i, P - B_i)``. Type II singular: ``det J_x = 0``; type I: ``J_q,i = 0``.

    Parameters
    ----------
    p : array_like, shape (..., 2)
        End-effector positions, length unit.
    theta : array_like, shape (..., 2)
        Crank angles ``theta_1, theta_2`` at ``p``, rad.
    r1, r3 : float
        Crank and half-base lengths (the length unit of the positions).

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

    Parameters
    ----------
    p : array_like, shape (..., 2)
        End-effector positions, length unit.
    theta : array_like, shape (..., 2)
        Crank angles ``theta_1, theta_2`` at ``p``, rad.
    r1, r3 : float
        Crank and half-base lengths (the length unit of the positions).

    Returns
    -------
    ndarray, shape (..., 2, 2)
        ``dP / dtheta``, length unit per rad.
    """
    jx, jq = jacobians(p, theta, r1, r3)
    return np.linalg.solve(jx, jq[..., :, None] * np.eye(2))


def type2_determinant(p, theta, r1, r3) -> np.ndarray:
    """``det J_x = cross(P - B_1, P - B_2)``; its sign is the assembly mode sigma.

    Parameters
    ----------
    p : array_like, shape (..., 2)
        End-effector positions, length unit.
    theta : array_like, shape (..., 2)
        Crank angles ``theta_1, theta_2`` at ``p``, rad.
    r1, r3 : float
        Crank and half-base lengths (the length unit of the positions).

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

    Parameters
    ----------
    p : array_like, shape (..., 2)
        End-effector positions, length unit.
    r1, r2, r3 : float
        Crank ``A_iB_i``, coupler ``B_iP`` and half base ``OA_i`` lengths, in one length unit
        (dimensionless in the paper, m in :class:`~robots.planar5r.model.Planar5R`).
    working_mode : str or tuple of int
        ``"+-"`` (default), ``"-+"``, ``"++"``, ``"--"`` or a pair ``(m_1, m_2)`` of +1/-1.

    Returns
    -------
    ndarray, shape (...)
        LCI, dimensionless, in [0, 1].

    Raises
    ------
    ValidationError, KinematicsError
        As :func:`inverse_kinematics`.
    """
    p = _as_points(p)
    theta = inverse_kinematics(p, r1, r2, r3, working_mode)
    jx, jq = jacobians(p, theta, r1, r3)
    adj = np.stack([np.stack([jx[..., 1, 1], -jx[..., 0, 1]], -1),
                    np.stack([-jx[..., 1, 0], jx[..., 0, 0]], -1)], -2)
    return inverse_condition_number(adj * jq[..., None, :])


# --------------------------------------------------------------------------------------------
# Singular loci, MIC, usable workspace
# --------------------------------------------------------------------------------------------
def type1_circles(r1, r2, r3) -> list[dict]:
    """The circles bounding the theoretical workspace, eqs. 16-19 (type I singular loci).

    Parameters
    ----------
    r1, r2, r3 : float
        Crank ``A_iB_i``, coupler ``B_iP`` and half base ``OA_i`` lengths, in one length unit
        (dimensionless in the paper, m in :class:`~robots.planar5r.model.Planar5R`).

    Returns
    -------
    list of dict
        Four dicts with ``"name"``, centre abscissa ``"cx"`` (on ``y = 0``) and ``"radius"``,
        length unit.
    """
    return [dict(name="C1o (eq. 16)", cx=-r3, radius=r1 + r2), dict(name="C1i (eq. 17)", cx=-r3, radius=abs(r1 - r2)),
            dict(name="C2o (eq. 18)", cx=r3, radius=r1 + r2), dict(name="C2i (eq. 19)", cx=r3, radius=abs(r1 - r2))]


def type2_locus(r1, r2, r3, working_mode=DEFAULT_WORKING_MODE, n: int = 20000) -> np.ndarray:
    """Points (k, 2) of the type II singular locus of one working mode (``B_1, B_2, P`` aligned).

    Two families: ``P`` the midpoint of ``B_1B_2`` with ``|B_1B_2| = 2 r2`` (parametrised by the
    coupler direction ``u``: ``P`` is on the circles of radius r1 about ``A_1 - r2 u`` and
    ``A_2 + r2 u``), and ``B_1 = B_2`` (possible when ``r1 >= r3``): ``P`` on the circle of
    radius r2 about ``(0, +-sqrt(r1^2 - r3^2))``. Only points whose elbows are in the requested
    working mode are kept.

    Parameters
    ----------
    r1, r2, r3 : float
        Crank ``A_iB_i``, coupler ``B_iP`` and half base ``OA_i`` lengths, in one length unit
        (dimensionless in the paper, m in :class:`~robots.planar5r.model.Planar5R`).
    working_mode : str or tuple of int
        ``"+-"`` (default), ``"-+"``, ``"++"``, ``"--"`` or a pair ``(m_1, m_2)`` of +1/-1.
    n : int
        Samples of the coupler direction (and of each ``B_1 = B_2`` circle).

    Returns
    -------
    ndarray, shape (k, 2)
        Points of the locus, length unit.

    Raises
    ------
    ValidationError
        If ``working_mode`` is invalid.
    """
    m1, m2 = working_mode_signs(working_mode)
    phi = np.linspace(0.0, 2 * np.pi, n, endpoint=False)
    ux, uy = np.cos(phi), np.sin(phi)
    pts, elbows = [], []
    for sig in (1, -1):
        px, py, h2 = circle_intersection(-r3 - r2 * ux, -r2 * uy, r1, r3 + r2 * ux, r2 * uy, r1, sig)
        ok = h2 >= 0
        pts.append(np.stack([px[ok], py[ok]], -1))
        elbows.append(np.stack([px[ok] + r2 * ux[ok], py[ok] + r2 * uy[ok],
                                px[ok] - r2 * ux[ok], py[ok] - r2 * uy[ok]], -1))
    if r1 >= r3:
        yb = np.sqrt(r1 * r1 - r3 * r3)
        for sy in (1, -1):
            px, py = r2 * ux, sy * yb + r2 * uy
            pts.append(np.stack([px, py], -1))
            elbows.append(np.stack([np.zeros_like(px), np.full_like(px, sy * yb)] * 2, -1))
    P, E = np.concatenate(pts), np.concatenate(elbows)
    s1 = np.sign(cross2(P[:, 0] + r3, P[:, 1], E[:, 0] + r3, E[:, 1]))
    s2 = np.sign(cross2(P[:, 0] - r3, P[:, 1], E[:, 2] - r3, E[:, 3]))
    return P[(s1 == m1) & (s2 == m2)]


def mic_closed_form(r1, r2, r3) -> dict:
    """Maximum inscribed circle ``x^2 + (y - y_MIC)^2 = r_MIC^2`` (eq. 20) by eqs. 21-22.

    eq. 21 (``r1 + r3 < r2``): ``r_MIC = (r1 + r2 - |r1 - r2|)/2``,
    ``y_MIC = sqrt((r1 + r2 + |r1 - r2|)^2 / 4 - r3^2)``.
    eq. 22 (otherwise): ``y_col = sqrt(r1^2 - (r2 - r3)^2)``,
    ``y_MIC = ((r1 + r2 + y_col)^2 - r3^2) / (2 (r1 + r2 + y_col))``, ``r_MIC = |y_MIC| - y_col``.
    ``y_col`` is the height of the type II posture with ``B_1 = (-r2, y)``, ``P = (0, y)``,
    ``B_2 = (r2, y)``; eq. 22's circle touches it and the outer circles eqs. 16/18.

    Parameters
    ----------
    r1, r2, r3 : float
        Crank ``A_iB_i``, coupler ``B_iP`` and half base ``OA_i`` lengths, in one length unit
        (dimensionless in the paper, m in :class:`~robots.planar5r.model.Planar5R`).

    Returns
    -------
    dict
        ``"radius"`` (``r_MIC``) and ``"center_y"`` (``y_MIC``), length unit; ``"equation"``:
        ``"eq21"`` or ``"eq22"``; for eq. 22 also ``"y_col"``, length unit.

    Raises
    ------
    ValidationError
        If ``r1``, ``r2`` or ``r3`` is not a scalar (eqs. 21-22 are for one design).
    KinematicsError
        If eq. 22 applies and ``r1 < abs(r2 - r3)``.
    """
    for name, r in (("r1", r1), ("r2", r2), ("r3", r3)):
        if np.ndim(r) != 0:
            raise ValidationError(name, np.asarray(r).tolist(), "a scalar length")
    if r1 + r3 < r2:
        return dict(radius=(r1 + r2 - abs(r1 - r2)) / 2,
                    center_y=float(np.sqrt((r1 + r2 + abs(r1 - r2)) ** 2 / 4 - r3 * r3)), equation="eq21")
    arg = r1 * r1 - (r2 - r3) ** 2
    if arg < 0:
        raise KinematicsError(f"5R: eq. 22 needs r1 >= |r2 - r3| (r1={r1:g}, r2={r2:g}, r3={r3:g})")
    y_col = float(np.sqrt(arg))
    R = r1 + r2 + y_col
    yc = (R * R - r3 * r3) / (2 * R)
    return dict(radius=abs(yc) - y_col, center_y=yc, y_col=y_col, equation="eq22")


def distance_to_singular_loci(points, r1, r2, r3, working_mode=DEFAULT_WORKING_MODE, locus=None) -> np.ndarray:
    """Distance (n,) from points (n, 2) to the nearest singular locus (eqs. 16-19 and type II).

    Parameters
    ----------
    points : array_like, shape (n, 2)
        Points, length unit.
    r1, r2, r3 : float
        Crank ``A_iB_i``, coupler ``B_iP`` and half base ``OA_i`` lengths, in one length unit
        (dimensionless in the paper, m in :class:`~robots.planar5r.model.Planar5R`).
    working_mode : str or tuple of int
        ``"+-"`` (default), ``"-+"``, ``"++"``, ``"--"`` or a pair ``(m_1, m_2)`` of +1/-1.
    locus : ndarray, shape (k, 2), or None
        Precomputed type II locus; None: :func:`type2_locus`.

    Returns
    -------
    ndarray, shape (n,)
        Distance to the nearest type I circle or type II locus point, length unit.
    """
    points = np.atleast_2d(np.asarray(points, dtype=float))
    d = np.full(len(points), np.inf)
    for c in type1_circles(r1, r2, r3):
        d = np.minimum(d, np.abs(np.hypot(points[:, 0] - c["cx"], points[:, 1]) - c["radius"]))
    locus = type2_locus(r1, r2, r3, working_mode) if locus is None else locus
    if len(locus):
        from scipy.spatial import cKDTree

        d = np.minimum(d, cKDTree(locus).query(points)[0])
    return d


def mic_numeric(r1, r2, r3, working_mode=DEFAULT_WORKING_MODE, assembly=1, n: int = 4001) -> dict:
    """MIC found numerically: the largest circle centred on the symmetry axis ``x = 0``,
    inside the usable workspace, and touching no singular locus (independent check of eqs. 21-22).

    Parameters
    ----------
    r1, r2, r3 : float
        Crank ``A_iB_i``, coupler ``B_iP`` and half base ``OA_i`` lengths, in one length unit
        (dimensionless in the paper, m in :class:`~robots.planar5r.model.Planar5R`).
    working_mode : str or tuple of int
        ``"+-"`` (default), ``"-+"``, ``"++"``, ``"--"`` or a pair ``(m_1, m_2)`` of +1/-1.
    assembly : {1, -1}
        Assembly mode sigma (side of ``B_1 -> B_2`` on which ``P`` lies).
    n : int
        Grid size on the axis ``0 <= y <= r1 + r2`` (``y = 0`` dropped) before the local
        refinement.

    Returns
    -------
    dict
        ``"radius"`` and ``"center_y"``, length unit.

    Raises
    ------
    ValidationError
        If ``working_mode`` is invalid.
    KinematicsError
        If no point of the axis is reachable in the working and assembly modes.
    """
    from scipy.optimize import minimize_scalar

    locus = type2_locus(r1, r2, r3, working_mode, n=40000)
    ys = np.linspace(0, r1 + r2, n)[1:]
    pts = np.stack([np.zeros_like(ys), ys], -1)
    t1, t2, ok = inverse_kinematics_raw(pts[:, 0], pts[:, 1], r1, r2, r3, working_mode)
    th = np.stack([t1, t2], -1)
    det = type2_determinant(pts, th, r1, r3)
    ok &= np.sign(det) == assembly
    if not ok.any():
        raise KinematicsError(f"5R: no usable point on the symmetry axis for r=({r1:g}, {r2:g}, {r3:g}), "
                              f"working mode {working_mode}, assembly {assembly}")
    d = np.where(ok, distance_to_singular_loci(pts, r1, r2, r3, working_mode, locus), -np.inf)
    i = int(np.argmax(d))
    lo, hi = ys[max(i - 1, 0)], ys[min(i + 1, len(ys) - 1)]
    res = minimize_scalar(lambda y: -distance_to_singular_loci([[0.0, y]], r1, r2, r3, working_mode, locus)[0],
                          bounds=(lo, hi), method="bounded", options=dict(xatol=1e-10))
    return dict(radius=float(-res.fun), center_y=float(res.x))


@dataclass(frozen=True)
class UsableWorkspaceMap:
    """The usable workspace on a grid: ``mask[j, i]`` for the point ``(x[i], y[j])``; ``lci`` is
    NaN outside the mask (a plotting array, not a kinematic result).

    Parameters
    ----------
    x : ndarray, shape (nx,)
        Grid abscissae, length unit.
    y : ndarray, shape (ny,)
        Grid ordinates, length unit.
    mask : ndarray of bool, shape (ny, nx)
        True in the usable workspace.
    lci : ndarray, shape (ny, nx)
        Local conditioning index, dimensionless (NaN outside ``mask``).
    seed : tuple of float
        Point ``(x, y)`` the region was grown from, length unit.
    """

    x: np.ndarray
    y: np.ndarray
    mask: np.ndarray
    lci: np.ndarray
    seed: tuple[float, float]

    @property
    def area(self) -> float:
        """Area of the masked grid cells, length unit squared."""
        return float(self.mask.sum() * (self.x[1] - self.x[0]) * (self.y[1] - self.y[0]))

    @property
    def lci_max(self) -> float:
        """Largest LCI in the usable workspace, dimensionless."""
        return float(np.nanmax(self.lci))

    def points(self) -> np.ndarray:
        """Grid points of the usable workspace.

        Returns
        -------
        ndarray, shape (k, 2)
            Points ``(x, y)`` where ``mask`` is True, length unit.
        """
        X, Y = np.meshgrid(self.x, self.y)
        return np.stack([X[self.mask], Y[self.mask]], -1)


def usable_workspace(r1, r2, r3, working_mode=DEFAULT_WORKING_MODE, assembly=1, n: int = 241,
                     seed=None, refine: bool = True) -> UsableWorkspaceMap:
    """Usable workspace (Sec. 2.4): the connected region around ``seed`` (default: the numeric
    MIC centre) where both chains reach ``P`` in ``working_mode`` and ``sign(det J_x)`` equals the
    assembly mode, i.e. bounded by singular loci. A first ``n x n`` grid covers the theoretical
    workspace's bounding box; with ``refine`` a second grid of equal spacing (``n`` points along
    the longer side) covers the bounding box of the region found. The LCI map is computed on it.

    Parameters
    ----------
    r1, r2, r3 : float
        Crank ``A_iB_i``, coupler ``B_iP`` and half base ``OA_i`` lengths, in one length unit
        (dimensionless in the paper, m in :class:`~robots.planar5r.model.Planar5R`).
    working_mode : str or tuple of int
        ``"+-"`` (default), ``"-+"``, ``"++"``, ``"--"`` or a pair ``(m_1, m_2)`` of +1/-1.
    assembly : {1, -1}
        Assembly mode sigma (side of ``B_1 -> B_2`` on which ``P`` lies).
    n : int
        Grid points per side of the first grid.
    seed : tuple of float or None
        Point ``(x, y)`` of the region, length unit; None: the centre of :func:`mic_numeric`.
    refine : bool
        Recompute on a second grid fitted to the region.

    Returns
    -------
    UsableWorkspaceMap
        The region and its LCI map.

    Raises
    ------
    ValidationError
        If ``working_mode`` is invalid.
    KinematicsError
        If the seed point is not in the usable workspace (or, with no ``seed``, as
        :func:`mic_numeric`).
    """
    from scipy import ndimage

    if seed is None:
        seed = (0.0, mic_numeric(r1, r2, r3, working_mode, assembly)["center_y"])

    def evaluate(x, y):
        X, Y = np.meshgrid(x, y)
        t1, t2, ok = inverse_kinematics_raw(X, Y, r1, r2, r3, working_mode)
        P = np.stack([X, Y], -1)
        jx, jq = jacobians(P, np.stack([t1, t2], -1), r1, r3)
        det = jx[..., 0, 0] * jx[..., 1, 1] - jx[..., 0, 1] * jx[..., 1, 0]
        good = ok & (np.sign(det) == assembly) & (jq[..., 0] != 0) & (jq[..., 1] != 0)
        labels, _ = ndimage.label(good)
        j, i = int(np.argmin(np.abs(y - seed[1]))), int(np.argmin(np.abs(x - seed[0])))
        if labels[j, i] == 0:
            raise KinematicsError(f"5R: seed point {list(seed)} is not in the usable workspace", poses=np.array([seed]))
        mask = labels == labels[j, i]
        adj = np.stack([np.stack([jx[..., 1, 1], -jx[..., 0, 1]], -1), np.stack([-jx[..., 1, 0], jx[..., 0, 0]], -1)], -2)
        return mask, np.where(mask, inverse_condition_number(adj * jq[..., None, :]), np.nan)

    R = r1 + r2
    x = np.linspace(-(R - r3), R - r3, n)
    y = np.linspace(-R, R, n)
    mask, lci = evaluate(x, y)
    if refine:
        X, Y = np.meshgrid(x, y)
        dx = x[1] - x[0]
        x0, x1 = X[mask].min() - 2 * dx, X[mask].max() + 2 * dx
        y0, y1 = Y[mask].min() - 2 * dx, Y[mask].max() + 2 * dx
        h = max(x1 - x0, y1 - y0) / (n - 1)
        x = np.linspace(x0, x1, int(round((x1 - x0) / h)) + 1)
        y = np.linspace(y0, y1, int(round((y1 - y0) / h)) + 1)
        mask, lci = evaluate(x, y)
    return UsableWorkspaceMap(x=x, y=y, mask=mask, lci=lci, seed=(float(seed[0]), float(seed[1])))
