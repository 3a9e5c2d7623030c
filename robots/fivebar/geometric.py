"""Sensitivity of the Deng 2012 5-bar to its geometric parameters (Sec. III.2, IV.5, eqs. IV.27-IV.43).

:class:`FiveBarGeometric`, the :class:`evotol.robots.base.RobotErrorModel` plugin of the link-length and
actuated-joint errors of :class:`~evotol.robots.fivebar.linkage.FiveBar`, and the worst case of joint
clearances and geometric variations together (:func:`combined_max_pose_error`, Sec. VIII.2).

Units: metres and radians inside; poses are ``(x, y)`` in metres.

The parameters several definitions of this module share are described once, here.

Parameters
----------
poses : array_like, shape (n, 2)
    End-effector positions, m.
"""
from __future__ import annotations

import numpy as np

from evotol.errors import KinematicsError, ValidationError
from evotol.robots.base import RobotErrorModel, SourceSpec, Workspace
from evotol.robots.fivebar.linkage import MM, FiveBar

GEOMETRIC_SOURCES = (
    SourceSpec("L0", 1, "m", "length", "base length A-B (A and B move by -+dL0/2 along x)"),
    SourceSpec("L1", 1, "m", "length", "link A-C (leg 1 proximal)"),
    SourceSpec("L2", 1, "m", "length", "link C-E (leg 1 distal)"),
    SourceSpec("L3", 1, "m", "length", "link B-D (leg 2 proximal)"),
    SourceSpec("L4", 1, "m", "length", "link D-E (leg 2 distal)"),
    SourceSpec("L5", 1, "m", "length", "offset E-P along link C-E"),
    SourceSpec("theta1", 1, "rad", "actuator", "actuated joint A (offset / encoder error)"),
    SourceSpec("theta3", 1, "rad", "actuator", "actuated joint B (offset / encoder error)"),
)
#: default workspace of the geometric model: the thesis's x range above the singular circle ``|OP| = 50 mm``
GEOMETRIC_WORKSPACE = Workspace(names=("x", "y"), low=(-20 * MM, 55 * MM), high=(20 * MM, 70 * MM),
                                units=("m", "m"), display_units=("mm", "mm"), display_scale=(1e3, 1e3))


class FiveBarGeometric(RobotErrorModel):
    """Sensitivity of the 5-bar's end-effector to its geometric parameters (Deng 2012 Sec. III.2, IV.5).

    Sources (intervals): ``dL0..dL5`` (m) and the actuated-joint errors ``dtheta1, dtheta3`` (rad).
    ``sensitivity`` is the vector-differentiation matrix J_p of eqs. IV.27-IV.43 (rows dp_x, dp_y)
    plus the rotation of the end-effector link ``dtheta1 + dtheta2`` (row dtheta_z, from eq.
    IV.39); ``pose_error`` re-solves the loop (circle intersection) with the perturbed lengths
    and actuated angles, so the core's finite-difference check applies.

    Poses at (or within ``singular_tol`` of) the parallel singularity raise KinematicsError: J_p
    is unbounded there (the default workspace stays above the singular circle ``|OP| = 50 mm``).

    Parameters
    ----------
    fivebar : FiveBar or None
        The linkage; None: :class:`~evotol.robots.fivebar.linkage.FiveBar` () (thesis lengths, modes ``(1, -1)``).
    workspace : Workspace or None
        Pose box, m; None: ``GEOMETRIC_WORKSPACE`` (``x`` in [-20, 20] mm, ``y`` in [55, 70] mm).
    singular_tol : float
        Poses with ``abs(parallel_singularity) < singular_tol`` (dimensionless sine) are refused.
    """

    name = "deng2012-5bar-geometric"
    sources = GEOMETRIC_SOURCES

    def __init__(self, fivebar: FiveBar | None = None, workspace: Workspace | None = None, singular_tol: float = 1e-3):
        self.robot = fivebar or FiveBar()
        self.workspace = workspace or GEOMETRIC_WORKSPACE
        self.singular_tol = float(singular_tol)

    def _geometry(self, poses):
        poses = self.check_poses(poses)
        s = self.robot.parallel_singularity(poses)
        bad = np.abs(s) < self.singular_tol
        if bad.any():
            raise KinematicsError(f"{self.name}: pose {poses[bad][0].tolist()} m is at (or within sin = "
                                  f"{self.singular_tol:g} of) the parallel singularity; J_p is unbounded there", poses=poses[bad])
        return poses, self.robot.inverse_geometry(poses)

    def jacobian_thesis(self, poses) -> np.ndarray:
        """J_p (n, 2, 8) of eq. IV.43 and J_theta2 (n, 8) of eq. IV.40, columns dL0..dL5, dth1, dth3.

        Returns
        -------
        Jp : ndarray, shape (n, 2, 8)
            ``d(p_x, p_y)`` per source, m per m (lengths) or m per rad (angles).
        Jtheta2 : ndarray, shape (n, 8)
            ``d theta2`` per source, rad per m or rad per rad.

        Raises
        ------
        ValidationError
            If ``poses`` is not a finite (n, 2) array.
        KinematicsError
            If a pose is outside the workspace, out of reach, or within ``singular_tol`` of the
            parallel singularity.
        """
        poses, g = self._geometry(poses)
        r = self.robot
        n = len(poses)
        E = np.array([[0.0, -1.0], [1.0, 0.0]])
        i = np.array([1.0, 0.0])
        th1, th2, th3, th4 = g["theta1"], g["theta2"], g["theta3"], g["theta4"]
        mu1 = np.stack([np.cos(th1), np.sin(th1)], 1)
        v1 = np.stack([np.cos(th1 + th2), np.sin(th1 + th2)], 1)
        mu2 = np.stack([np.cos(th3), np.sin(th3)], 1)
        v2 = np.stack([np.cos(th3 + th4), np.sin(th3 + th4)], 1)
        dot = lambda a, b: np.einsum("ni,ni->n", a, b)
        Emu1, Emu2, Ev1 = mu1 @ E.T, mu2 @ E.T, v1 @ E.T
        zero = np.zeros(n)
        rows = np.stack([                                                   # eq. IV.37, right matrix
            np.stack([-0.5 * v1 @ i, dot(v1, mu1), dot(v1, v1), zero, zero, zero, dot(v1, Emu1) * r.L1, zero], 1),
            np.stack([0.5 * v2 @ i, zero, zero, dot(v2, mu2), dot(v2, v2), zero, zero, dot(v2, Emu2) * r.L3], 1),
        ], 1)
        V = np.stack([v1, v2], 1)
        Je = np.linalg.solve(V, rows)                                       # eq. IV.38
        Jth2 = (np.einsum("ni,nij->nj", Ev1, Je) / r.L2                     # eq. IV.40 (8 columns; the
                + np.stack([0.5 * Ev1 @ i / r.L2, -dot(Ev1, mu1) / r.L2,     # printed row misses one 0)
                            zero, zero, zero, zero, -dot(Ev1, Emu1) * r.L1 / r.L2 - 1.0, zero], 1))
        JL5 = np.zeros(8); JL5[5] = 1.0
        Jth1 = np.zeros(8); Jth1[6] = 1.0
        Jp = Je + v1[:, :, None] * JL5 + r.L5 * Ev1[:, :, None] * (Jth1 + Jth2)[:, None, :]   # eq. IV.43
        return Jp, Jth2

    def sensitivity(self, poses) -> np.ndarray:
        """First-order map of the 8 sources onto the pose error (eqs. IV.37-IV.43), poses (n, 2) in m:
        rows ``dp_x, dp_y`` (m per unit source) from :meth:`jacobian_thesis`, row 5 the rotation
        ``dtheta1 + dtheta2`` of the end-effector link (rad per unit source); rows 2-4 zero.

        Raises
        ------
        ValidationError, KinematicsError
            As :meth:`jacobian_thesis`.
        """
        Jp, Jth2 = self.jacobian_thesis(poses)
        out = np.zeros((len(Jp), 6, 8))
        out[:, 0:2] = Jp
        out[:, 5] = Jth2
        out[:, 5, 6] += 1.0          # end-effector link angle theta1 + theta2
        return out

    def pose_error(self, poses, errors) -> np.ndarray:
        """Exact pose error: the loop re-solved with perturbed lengths ``dL0 .. dL5`` (m) and actuated
        angles ``dtheta1, dtheta3`` (rad); columns 0-1 the position error (m), column 5 the rotation of
        link ``C-E`` (rad, wrapped to ``[-pi, pi)``), columns 2-4 zero.

        Raises
        ------
        ValidationError, KinematicsError
            As :meth:`jacobian_thesis`; KinematicsError also if the perturbed loop cannot close.
        """
        poses, g = self._geometry(poses)
        errors = np.asarray(errors, float)
        n, m, _ = errors.shape
        r = self.robot
        L = {k: getattr(r, k) + errors[:, :, j] for j, k in enumerate(("L0", "L1", "L2", "L3", "L4", "L5"))}
        th1 = g["theta1"][:, None] + errors[:, :, 6]
        th3 = g["theta3"][:, None] + errors[:, :, 7]
        Eref = np.broadcast_to(g["E"][:, None, :], (n, m, 2))
        P = r.forward_geometry(th1, th3, lengths=L, reference=Eref)
        C = np.stack([-L["L0"] / 2 + L["L1"] * np.cos(th1), L["L1"] * np.sin(th1)], -1)
        # direction of link C-E in the perturbed loop (E = the loop point, P = E + L5 u)
        Eloop = r.forward_geometry(th1, th3, lengths={**L, "L5": np.zeros_like(L["L5"])}, reference=Eref)
        u = Eloop - C
        ang = np.arctan2(u[..., 1], u[..., 0])
        ang0 = (g["theta1"] + g["theta2"])[:, None]
        out = np.zeros((n, m, 6))
        out[..., 0:2] = P - g["P"][:, None, :]
        out[..., 5] = (ang - ang0 + np.pi) % (2 * np.pi) - np.pi
        return out


def combined_max_pose_error(fivebar: FiveBar, poses, *, clearance=None, geometric=None, tol: float = 1e-3):
    """Worst case of joint clearances **and** geometric variations together (the thesis's future
    work 1, Sec. VIII.2): to first order the end-effector error is the sum of the clearance error
    (Ch. III) and ``J_p dg`` (Sec. IV.5) with ``|dg_k| <= t_k``; the feasible set is the Minkowski
    sum, whose support function is the sum of the two, and the same certified branch and bound
    gives its maximum.

    clearance: a ClearanceMechanism (default: the thesis's clearances) or None;
    geometric: dict source name -> tolerance (m or rad) over L0..L5, theta1, theta3 (missing = 0).
    Returns a MaxPoseError with ``p_extra``/``r_extra`` = the maximising geometric errors.

    Parameters
    ----------
    fivebar : FiveBar
        The linkage.
    clearance : ClearanceMechanism or None
        Clearance model; None: ``fivebar.clearance_mechanism()``.
    geometric : dict of str to float, or None
        Tolerance ``t_k`` per geometric source (names of ``GEOMETRIC_SOURCES``), m or rad.
    tol : float
        Relative tolerance of the certified branch and bound.

    Returns
    -------
    MaxPoseError
        Certified worst-case end-effector error at each pose (see
        :func:`evotol.robots.clearance.max_pose_error`).

    Raises
    ------
    ValidationError
        If ``geometric`` names an unknown source.
    KinematicsError
        If a pose is out of reach or too near the parallel singularity.
    """
    mech = clearance if clearance is not None else fivebar.clearance_mechanism()
    poses = np.atleast_2d(np.asarray(poses, float))
    geo = FiveBarGeometric(fivebar, workspace=Workspace(("x", "y"), tuple(poses.min(0)), tuple(poses.max(0)), ("m", "m")))
    names = [s.name for s in GEOMETRIC_SOURCES]
    t = np.zeros(len(names))
    for k, v in (geometric or {}).items():
        if k not in names:
            raise ValidationError("geometric tolerance", k, f"one of {names}")
        t[names.index(k)] = float(v)
    Jb = geo.sensitivity(poses)                         # [dp; dtheta] (evotol.robots.base order)
    J = np.concatenate([Jb[:, 3:], Jb[:, :3]], axis=1)  # -> thesis order [dtheta; dp]
    from evotol.robots.clearance import max_pose_error
    return max_pose_error(mech, poses, tol=tol, extra=(J, t))
