"""Brahmia et al. 2023's geometric-tolerance synthesis of a Delta robot (Sec. 2.3, 3.1, 4.1), the
method part: problem (12)-(13) per posture and imposed displacement, solved with scipy's
``trust-constr`` (interior point, as the paper's fmincon "interior-point"; :func:`solve_displacement`),
the tolerance-interval rule of Fig. 4 (:func:`fig4_intervals`) and the verification of Sec. 4.1
(:func:`verification_errors`); step 2 for every posture and imposed displacement of Tables A1-A2
is :func:`synthesis_runs`. The kinematics are :class:`evotol.robots.delta.DeltaRobot`'s; the paper's
tables and the study around them are :mod:`evotol.studies.brahmia2023_delta`.

Two objectives F are available: ``"closed"`` (the platform position from the loop-closure
forward kinematics with errors must move by ΔP) and ``"open"`` (the paper's eq. 10 read
literally: every serial sub-chain, joints held at Q_k, must end at P + ΔP).

The parameters several definitions of this module share are described once, here.

Parameters
----------
robot : DeltaRobot
    The robot whose kinematics are used.
lo, hi : array_like, shape (47,)
    Lower and upper interval limits of each parameter, SI (m or rad).
"""
from __future__ import annotations

import numpy as np
from scipy.optimize import Bounds, minimize

from evotol.errors import ValidationError
from evotol.robots.delta import LINEAR, PARAMETER_NAMES, POSTURES_MM, DeltaRobot

BOUND_LINEAR_MM = 0.015           # eq. (13)
BOUND_ANGULAR_DEG = 0.015         # eq. (13)
REQUIRED_MM = 0.2                 # imposed accuracy (Sec. 3.1)
SYNTHESIS_POSTURES = ("P1", "P3", "P6", "P9")
#: imposed displacements of Tables A1-A2, unit vectors in the order of the tests 1..6
TEST_DIRECTIONS = {"+x": (1, 0, 0), "+y": (0, 1, 0), "-x": (-1, 0, 0), "-y": (0, -1, 0),
                   "+z": (0, 0, 1), "-z": (0, 0, -1)}
IS_LINEAR = np.isin(PARAMETER_NAMES, LINEAR)


def paper_bounds() -> np.ndarray:
    """Bounds of eq. (13) in SI, (47,): 0.015 mm (m) for linear, 0.015 deg (rad) for angular.

    Returns
    -------
    ndarray, shape (47,)
        Bound of each error parameter (order of :data:`evotol.robots.delta.PARAMETER_NAMES`):
        ``1.5e-5`` m for the linear ones, ``radians(0.015)`` rad for the angular ones.
    """
    return np.where(IS_LINEAR, BOUND_LINEAR_MM * 1e-3, np.radians(BOUND_ANGULAR_DEG))


def postures_m(names=None) -> np.ndarray:
    """Positions of the paper's postures (Fig. 5), in metres.

    Parameters
    ----------
    names : iterable of str or None
        Posture names, keys of :data:`evotol.robots.delta.POSTURES_MM` (``"P1"`` ... ``"P15"``);
        None: all 15, in order.

    Returns
    -------
    ndarray, shape (n, 3)
        Platform positions ``(x, y, z)``, m.
    """
    names = list(POSTURES_MM) if names is None else list(names)
    return np.array([POSTURES_MM[n] for n in names]) / 1e3


# --- step 2: problem (12)-(13) ----------------------------------------------------------------------
def _objective_parts(robot: DeltaRobot, pose, displacement, bounds, objective: str):
    """Scaled residual vector and its Jacobian w.r.t. z = e / bounds, as a cached function of z."""
    req = np.linalg.norm(displacement) or 1.0
    target = pose + displacement
    cache: dict = {}

    def parts(z):
        key = z.tobytes()
        if key not in cache:
            e = z * bounds
            if objective == "closed":
                x, J = robot.position_and_jacobian(pose, e)
                res, jac = (x[0] - target) / req, J[0] * bounds / req
            elif objective == "open":
                h = 1e-30
                E = e[None, None, :] + np.eye(e.size)[None] * (1j * h)
                pts = robot.open_chain_points(pose[None], E)[0]           # (47, 3 legs, 2 branches, 3)
                res = ((pts[0].real - target) / req).ravel()
                jac = (pts.imag / h * bounds[:, None, None, None] / req).reshape(e.size, -1).T
            else:
                raise ValidationError("objective", objective, "'closed' or 'open'")
            cache.clear()
            cache[key] = (res, jac)
        return cache[key]
    return parts


def solve_displacement(robot: DeltaRobot, pose, displacement, bounds=None, *, objective: str = "closed",
                       min_magnitude=None, maxiter: int = 150) -> dict:
    """Problem (12)-(13) for one posture and one imposed displacement ΔP (m).

    Minimises ``F = |P_e - P - ΔP|^2`` (eq. 10; ``objective="open"`` sums it over the 6 serial
    sub-chains at Q_k) over the 47 errors with ``scipy.optimize.minimize(method="trust-constr")``
    -- an interior-point method for the bound constraints, like the paper's fmincon -- with exact
    gradient and Gauss-Newton Hessian, in variables scaled by the bounds.

    ``bounds`` (SI, default eq. 13) bound ``|Δ|``. ``min_magnitude`` (SI) adds the lower limit of
    eq. (12), ``ΔL_min <= |ΔL|``: that set is two intervals per parameter, so the sign of each
    parameter is fixed first to the descent direction of F at zero error (``+`` when the
    parameter has no influence) and the problem is solved on ``sign * [min, max]``. Without it
    the start is zero error. Returns errors (SI), F (in units of ``|ΔP|^2``), the achieved
    displacement of the platform (closed-loop forward kinematics, m), iterations, status.

    Parameters
    ----------
    pose : array_like, shape (3,)
        Nominal platform position P, m.
    displacement : array_like, shape (3,)
        Imposed displacement ΔP, m.
    bounds : array_like, shape (47,) or None
        Upper bound of ``|Δ|`` of each parameter, SI (m or rad); None: :func:`paper_bounds`.
    objective : {"closed", "open"}
        ``"closed"``: loop-closure forward kinematics; ``"open"``: the 6 serial sub-chains (eq. 10).
    min_magnitude : float or array_like, shape (47,), or None
        Lower limit ``ΔL_min`` of ``|Δ|``, SI; None: no lower limit.
    maxiter : int
        Iteration limit of ``trust-constr``.

    Returns
    -------
    dict
        ``"errors"``: (47,) solution, SI; ``"F"``: objective value, dimensionless (relative to
        ``|ΔP|^2``); ``"achieved"``: (3,) displacement of the platform with these errors, m;
        ``"nit"``: iterations; ``"status"``: scipy's status code; ``"residual_mm"``: distance
        between the achieved and the imposed displacement, mm.

    Raises
    ------
    ValidationError
        If ``objective`` is neither ``"closed"`` nor ``"open"``, or ``min_magnitude`` is negative
        or not below ``bounds``.
    """
    if objective not in ("closed", "open"):
        raise ValidationError("objective", objective, "'closed' or 'open'")
    bounds = paper_bounds() if bounds is None else np.asarray(bounds, float)
    pose = np.asarray(pose, float)
    displacement = np.asarray(displacement, float)
    parts = _objective_parts(robot, pose, displacement, bounds, objective)

    def fun(z):
        res, jac = parts(z)
        return float(res @ res), 2 * jac.T @ res

    def hess(z):
        _, jac = parts(z)
        return 2 * jac.T @ jac

    n = bounds.size
    if min_magnitude is None:
        lower, upper, z0 = -np.ones(n), np.ones(n), np.zeros(n)
    else:
        frac = np.broadcast_to(np.asarray(min_magnitude, float), (n,)) / bounds
        if np.any(frac < 0) or np.any(frac >= 1):
            raise ValidationError("min_magnitude", min_magnitude, "0 <= min < bound for every parameter")
        g = fun(np.zeros(n))[1]
        sign = np.where(g > 1e-12 * np.max(np.abs(g)), -1.0, 1.0)
        lower, upper = np.where(sign > 0, frac, -1.0), np.where(sign > 0, 1.0, -frac)
        z0 = (lower + upper) / 2
    sol = minimize(fun, z0, jac=True, hess=hess, method="trust-constr", bounds=Bounds(lower, upper),
                   options=dict(gtol=1e-10, xtol=1e-10, maxiter=int(maxiter)))
    e = np.clip(sol.x, lower, upper) * bounds
    achieved = robot.forward_kinematics(pose[None], e[None, None])[0, 0] - pose
    return {"errors": e, "F": float(sol.fun), "achieved": achieved, "nit": int(sol.nit), "status": int(sol.status),
            "residual_mm": float(np.linalg.norm(achieved - displacement) * 1e3)}


# --- step 3: Fig. 4 rule and the verification of Sec. 4.1 -------------------------------------------------
def fig4_intervals(values, bounds=None, zero_tol: float = 1e-6):
    """Tolerance interval of each parameter by the rule of Fig. 4.

    values: (n_runs, 47) parameter values of the solutions of problem (12). Per parameter, the
    lower limit is the largest negative value (max of y_neg), the upper limit the smallest
    positive value (min of y_pos). Values with ``|v| <= zero_tol * bound`` are "not used" by a
    solution and ignored. The paper does not say what to do when a side is empty: we mirror the
    other side, and use the bound of eq. (13) if the parameter is never used (it then has no
    influence at the postures). Returns (lower, upper) arrays in the units of ``values``.

    Parameters
    ----------
    values : array_like, shape (n_runs, 47)
        Error parameters of the solutions of problem (12), SI (m or rad).
    bounds : array_like, shape (47,) or None
        Bounds of eq. (13), same units; None: :func:`paper_bounds`.
    zero_tol : float
        Threshold of "not used", as a fraction of the bound, dimensionless.

    Returns
    -------
    lower, upper : ndarray, shape (47,)
        Interval limits (``lower <= 0 <= upper``), in the units of ``values``.
    """
    values = np.atleast_2d(np.asarray(values, float))
    bounds = paper_bounds() if bounds is None else np.asarray(bounds, float)
    used = np.abs(values) > zero_tol * bounds
    neg = np.where(used & (values < 0), values, -np.inf).max(axis=0)
    pos = np.where(used & (values > 0), values, np.inf).min(axis=0)
    lo = np.where(np.isfinite(neg), neg, np.where(np.isfinite(pos), -pos, -bounds))
    hi = np.where(np.isfinite(pos), pos, np.where(np.isfinite(neg), -neg, bounds))
    return lo, hi


VERIFICATION_CASES = {
    "case 1: all upper": ("hi", "hi"),
    "case 2: all lower": ("lo", "lo"),
    "case 3: linear upper, angular lower": ("hi", "lo"),
    "case 4: linear lower, angular upper": ("lo", "hi"),
}


def verification_error_vectors(lo, hi) -> dict[str, np.ndarray]:
    """The four error vectors of Sec. 4.1 (SI, (47,)), from interval limits lo, hi (SI).

    Returns
    -------
    dict of str to ndarray, shape (47,)
        Keyed by the case names of ``VERIFICATION_CASES``: each linear parameter at its ``hi``
        or ``lo`` limit and each angular one likewise, SI.
    """
    lim = {"lo": np.asarray(lo, float), "hi": np.asarray(hi, float)}
    return {case: np.where(IS_LINEAR, lim[lin], lim[ang]) for case, (lin, ang) in VERIFICATION_CASES.items()}


def verification_errors(robot: DeltaRobot, lo, hi, postures=None) -> dict[str, dict[str, np.ndarray]]:
    """Position error (mm) at the 15 postures for the 4 cases of Sec. 4.1 (Fig. 7).

    ``closed``: ``|P_e - P|`` with the loop-closure forward kinematics with errors (ours);
    ``open``: the largest ``|P_ei - P|`` over the 6 serial sub-chains at Q_k (the paper's eq. 6 read
    literally); ``linear``: ``|S e|`` with the first-order map.

    Parameters
    ----------
    postures : iterable of str or None
        Posture names (see :func:`postures_m`); None: all 15.

    Returns
    -------
    dict of str to dict of str to ndarray
        For each case of ``VERIFICATION_CASES``, ``{"closed", "open", "linear"}`` each an
        (n_postures,) array of position errors, mm.
    """
    P = postures_m(postures)
    cases = verification_error_vectors(lo, hi)
    E = np.stack(list(cases.values()))                      # (4, 47)
    Eb = np.broadcast_to(E, (len(P),) + E.shape)
    closed = np.linalg.norm(robot.forward_kinematics(P, Eb) - P[:, None], axis=-1) * 1e3   # (15, 4)
    pts = robot.open_chain_points(P, Eb)                                              # (15, 4, 3, 2, 3)
    open_ = np.linalg.norm(pts - P[:, None, None, None], axis=-1).max(axis=(-1, -2)) * 1e3
    S = robot.sensitivity(P)[:, :3]
    lin = np.linalg.norm(np.einsum("nij,cj->nci", S, E), axis=-1) * 1e3
    return {case: {"closed": closed[:, k], "open": open_[:, k], "linear": lin[:, k]} for k, case in enumerate(cases)}


# --- step 2 for every posture and imposed displacement (Tables A1-A2) --------------------------------
def synthesis_runs(robot: DeltaRobot, postures=SYNTHESIS_POSTURES, tests=tuple(TEST_DIRECTIONS), *,
                   objective: str = "closed", min_magnitude=None, maxiter: int = 150,
                   required_mm: float = REQUIRED_MM) -> list[dict]:
    """Step 2 for every (posture, test) of Tables A1-A2; one dict per run (see solve_displacement).

    Parameters
    ----------
    robot : evotol.robots.delta.DeltaRobot
        The Delta robot model.
    postures : sequence of str, optional
        Posture names (keys of :data:`evotol.robots.delta.POSTURES_MM`); default P1, P3, P6, P9.
    tests : sequence of str, optional
        Imposed-displacement directions, keys of :data:`TEST_DIRECTIONS` (``"+x"`` ... ``"-z"``);
        default all six, in the order of tests 1..6.
    objective : {"closed", "open"}, optional
        F of eq. (10): loop-closure forward kinematics (``"closed"``) or every serial sub-chain at
        Q_k (``"open"``, the paper read literally).
    min_magnitude : (47,) array_like or float, optional
        Lower limits of ``|Δ|`` of eq. (12), SI (m or rad); ``None`` solves with the bounds of
        eq. (13) only (see :func:`inferred_min_magnitude`).
    maxiter : int, optional
        Iteration limit of scipy's ``trust-constr`` per run.
    required_mm : float, optional
        Magnitude of the imposed displacement ΔP, mm (default 0.2 mm, Sec. 3.1).

    Returns
    -------
    list of dict
        One dict per (posture, test), postures outer: the output of
        :func:`evotol.robots.delta_synthesis.solve_displacement` (``errors`` (47,) SI, ``F``,
        ``achieved`` (3,) m, ``nit``, ``status``, ``residual_mm`` in mm) plus ``posture`` and
        ``test``.

    Raises
    ------
    ValidationError
        If ``objective`` is not ``"closed"`` or ``"open"``, or ``min_magnitude`` is not within
        [0, bound) for every parameter (from ``solve_displacement``).
    """
    runs = []
    for p in postures:
        pose = postures_m([p])[0]
        for t in tests:
            dP = np.asarray(TEST_DIRECTIONS[t], float) * required_mm * 1e-3
            out = solve_displacement(robot, pose, dP, objective=objective, min_magnitude=min_magnitude,
                                     maxiter=maxiter)
            out.update(posture=p, test=t)
            runs.append(out)
    return runs
