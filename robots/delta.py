"""Delta parallel robot with Khalil–Kleinfinger geometric errors (Brahmia et al. 2023).

Model (Brahmia, Kerboua, Kelaiaia, Latreche, *Appl. Sci.* 13:10703, 2023, Sec. 2):

* three legs ``i = 1, 2, 3`` at ``theta_i = 2 pi (i - 1) / 3`` about the base axis ``z0``;
* each leg is an actuated revolute (``q1``, axis tangent to the base circle of radius ``Ra``),
  an upper arm ``La``, and a parallelogram of two rods ``Lb`` whose bars have half-width ``d``;
  the platform centre ``P`` is at ``Rb`` from the lower bar's centre;
* each leg is written as a Khalil–Kleinfinger (KK) tree (Table 1 / Table 2): frame ``j`` with
  antecedent ``a(j)`` is ``Rot(z, gamma_j) Trans(z, b_j) Rot(x, alpha_j) Trans(x, d_j)
  Rot(z, q_j) Trans(z, r_j)`` (eq. 4). Branch 1 (rod 1) is ``A-1-2-3-4-5-E`` (eq. 1), branch 2
  (rod 2) is ``A-1-2-6-7-5-E`` (eq. 2);
* ``z0`` points from the base towards the platform (the paper's postures have ``z > 0``).

Error parameters (eq. 5 / Table 2; the 47 of eq. 12): ``Ra``, ``Rb`` and per leg ``d_i``,
``La_i``, ``Lb_i``, ``alpha1_i``, ``alpha3_i``, ``alpha5_i``, ``alpha6_i``, ``q1_i`` ... ``q7_i``,
``theta_i``, all entering the KK transforms as ``nominal + error`` exactly as in Table 2.

What differs from the printed paper, and why (see ``docs/delta.md``):

* The printed matrix ``1_2 T`` has no ``La`` and ``3_4 T`` an offset ``d`` along ``z``; both
  contradict Table 1 (``d_2 = La``, ``r_4 = 0``) and would not close the loop. We follow Table 1.
* Table 1 lists ``b = 2d`` in row 2 and ``r_5 = -d`` for the rod-2 cut joint; a frame with a
  single successor has no ``b``. We read ``b_6 = -2(d + Δd)`` (rod 2 starts at the other end of
  the upper bar) and ``r_5' = +(d + Δd)`` (it ends at the other end of the lower bar), which is
  the only reading in which the two rods form the parallelogram at nominal.
* The paper imposes the parallelogram relations ``q6 = q3``, ``q4 = q7 = -q3`` (Sec. 2.1.2) and,
  for the platform to stay parallel to the base, ``q5 = pi - q1 - q2``. We keep these relations
  between the joint variables and add the joint errors ``Δq_j`` on top, so ``Δq3..Δq7`` model
  the parallelism errors of the parallelogram; in the closed-loop model the level relation
  holds for the actual rotations of joints 1 and 2, so ``Δq1`` is a pure actuator offset and
  ``Δq2`` (an offset of a free passive joint) has no effect (see :meth:`DeltaRobot.branch_points`).
* A parallelogram of revolute joints with errors is over-constrained (a spatial 4R loop has
  mobility -2), so the two branches of a leg end at slightly different points. The leg's end
  point is the midpoint of the two branch ends (the least-squares closure of the two branches).
  The forward kinematics with errors then solves the 9 equations "leg end point i = P" (eq. 3)
  for ``P`` and the free passive joints ``q2_i, q3_i``, given the commanded actuated angles.

The position-only model leaves rows 3-5 (orientation) of the error twist at zero, as the paper
does (eq. 3 constrains positions only).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from evotol.errors import ConvergenceError, KinematicsError, ValidationError
from robots.base import RobotErrorModel, SourceSpec, Workspace

__all__ = ["DeltaGeometry", "DeltaRobot", "POSTURES_MM", "PARAMETER_NAMES", "LINEAR", "ANGULAR",
           "cylinder_poses"]

LEG_PARAMETERS = ("d", "La", "Lb", "alpha1", "alpha3", "alpha5", "alpha6",
                  "q1", "q2", "q3", "q4", "q5", "q6", "q7", "theta")
LINEAR_LEG = ("d", "La", "Lb")
#: the 47 error parameters of eq. (12), in the order of Tables A1-A2.
PARAMETER_NAMES: tuple[str, ...] = ("Ra", "Rb") + tuple(f"{p}_{i}" for i in (1, 2, 3) for p in LEG_PARAMETERS)
#: the error parameters that are lengths (m): Ra, Rb and every d, La, Lb
LINEAR: tuple[str, ...] = tuple(n for n in PARAMETER_NAMES if n in ("Ra", "Rb") or n.split("_")[0] in LINEAR_LEG)
#: the error parameters that are angles (rad): the alphas, joint offsets q and theta
ANGULAR: tuple[str, ...] = tuple(n for n in PARAMETER_NAMES if n not in LINEAR)
_INDEX = {n: k for k, n in enumerate(PARAMETER_NAMES)}
# (n_params,) index arrays: column of parameter p for leg i -> _LEG_COL[p][i]
_LEG_COL = {p: np.array([_INDEX[f"{p}_{i}"] for i in (1, 2, 3)]) for p in LEG_PARAMETERS}

_DESCRIPTIONS = {
    "Ra": "base radius O0-A_i (all legs)", "Rb": "platform radius P-B_i (all legs)",
    "d": "half-width of the parallelogram bars", "La": "upper-arm length", "Lb": "rod length (both rods)",
    "alpha1": "twist of the actuated axis (KK alpha_1)", "alpha3": "twist of rod-1 upper hinge (alpha_3)",
    "alpha5": "twist of the lower-bar hinge (alpha_5)", "alpha6": "twist of rod-2 upper hinge (alpha_6)",
    "q1": "actuated joint offset", "q2": "upper-bar joint offset", "q3": "rod-1 upper hinge offset",
    "q4": "rod-1 lower hinge offset", "q5": "lower-bar joint offset", "q6": "rod-2 upper hinge offset",
    "q7": "rod-2 lower hinge offset", "theta": "angular position of the leg on the base",
}

#: The 15 postures of the regular cylindrical workspace (Fig. 5), mm. P1, P3, P6, P9 are given by
#: the paper; the others are our reading of Fig. 5: five vertical lines (axis, +x, +y, -x, -y at
#: radius 100 mm) times three heights (z = 250, 375, 500 mm), numbered line by line.
POSTURES_MM: dict[str, tuple[float, float, float]] = {}
for _line, (_x, _y) in enumerate(((0, 0), (100, 0), (0, 100), (-100, 0), (0, -100))):
    for _lev, _z in enumerate((250.0, 375.0, 500.0)):
        POSTURES_MM[f"P{3 * _line + _lev + 1}"] = (float(_x), float(_y), _z)
del _line, _x, _y, _lev, _z


@dataclass(frozen=True)
class DeltaGeometry:
    """Nominal dimensions (m), Brahmia et al. 2023 Sec. 2.1.1 / 3.1.

    Parameters
    ----------
    La : float
        Upper-arm length, m (0.260).
    Lb : float
        Length of the two parallelogram rods, m (0.480).
    Ra : float
        Base radius ``O0-A_i``, m (0.194).
    Rb : float
        Platform radius ``P-B_i``, m (0.030).
    d : float
        Half-width of the parallelogram bars, m (0.020).

    Raises
    ------
    ValidationError
        If a length is not finite and positive.
    """

    La: float = 0.260   # upper arm
    Lb: float = 0.480   # parallelogram rods
    Ra: float = 0.194   # base radius
    Rb: float = 0.030   # platform radius
    d: float = 0.020    # half-width of the parallelogram bars

    def __post_init__(self):
        for f in ("La", "Lb", "Ra", "Rb", "d"):
            v = getattr(self, f)
            if not (np.isfinite(v) and v > 0):
                raise ValidationError(f"DeltaGeometry.{f}", v, "a positive length in metres")

    @property
    def theta(self) -> np.ndarray:
        """Leg angles theta_i = 2 pi (i - 1) / 3 (rad)."""
        return 2 * np.pi * np.arange(3) / 3


def cylinder_poses(n: int, radius: float = 0.1, z_range=(0.25, 0.5), seed: int | None = 0) -> np.ndarray:
    """``n`` scrambled-Halton points uniform in the cylindrical workspace, shape (n, 3), m.

    Parameters
    ----------
    n : int
        Number of points (at least 1).
    radius : float
        Radius of the cylinder about the base axis, m.
    z_range : tuple of float
        ``(z_min, z_max)`` heights of the cylinder, m.
    seed : int or None
        Seed of the scrambled Halton sequence (None: not reproducible).

    Returns
    -------
    (n, 3) ndarray
        Platform positions ``(x, y, z)``, m, uniform in the disk of ``radius`` times ``z_range``.

    Raises
    ------
    ValidationError
        If ``n`` is below 1.
    """
    from scipy.stats import qmc

    if int(n) < 1:
        raise ValidationError("cylinder_poses n", n, "a positive integer")
    u = qmc.Halton(d=3, scramble=True, seed=seed).random(int(n))
    r = radius * np.sqrt(u[:, 0])  # uniform in the disk
    phi = 2 * np.pi * u[:, 1]
    z = z_range[0] + (z_range[1] - z_range[0]) * u[:, 2]
    return np.stack([r * np.cos(phi), r * np.sin(phi), z], axis=1)


# --- elementary KK operations on points (components kept apart for broadcasting) -----------------
def _rot_z(c, s, p):
    x, y, z = p
    return (c * x - s * y, s * x + c * y, z)


def _rot_x(c, s, p):
    x, y, z = p
    return (x, c * y - s * z, s * y + c * z)


def _kk(p, alpha, dx, q, r, b=None):
    """Apply Rot(x, alpha) Trans(x, dx) Rot(z, q) Trans(z, r) (eq. 4), preceded by Trans(z, b)."""
    x, y, z = p
    x, y, z = _rot_z(np.cos(q), np.sin(q), (x, y, z + r))
    x, y, z = _rot_x(np.cos(alpha), np.sin(alpha), (x + dx, y, z))
    if b is not None:
        z = z + b
    return x, y, z


class DeltaRobot(RobotErrorModel):
    """Delta robot error model (Brahmia et al. 2023) as a :class:`robots.base.RobotErrorModel`.

    Pose coordinates: platform centre ``(x, y, z)`` in metres, base frame (``z`` towards the
    platform). Sources: the 47 geometric error parameters (:data:`PARAMETER_NAMES`), each an
    interval, in m (group ``"linear"``) or rad (group ``"angular"``).

    Parameters
    ----------
    geometry : DeltaGeometry or dict or None
        Nominal dimensions, m; a dict takes keys among ``La, Lb, Ra, Rb, d`` (the others keep
        their defaults); None: :class:`DeltaGeometry` ().
    workspace : Workspace or None
        Pose box; None: ``x, y`` in [-0.1, 0.1] m, ``z`` in [0.25, 0.5] m (displayed in mm).
    newton_tol : float
        Stopping step of the forward kinematics with errors, m / rad.
    max_iter : int
        Maximum number of chord-Newton iterations.

    Raises
    ------
    ValidationError
        If ``geometry`` has unknown keys or is neither a :class:`DeltaGeometry` nor a dict, or a
        length is not positive.
    """

    name = "delta"

    def __init__(self, geometry: DeltaGeometry | dict | None = None, workspace: Workspace | None = None,
                 *, newton_tol: float = 1e-14, max_iter: int = 60):
        if isinstance(geometry, dict):  # e.g. from a study file: geometry = {La = 0.26, Lb = 0.48}
            unknown = set(geometry) - {"La", "Lb", "Ra", "Rb", "d"}
            if unknown:
                raise ValidationError("DeltaRobot geometry", sorted(unknown), "keys among La, Lb, Ra, Rb, d (m)")
            geometry = DeltaGeometry(**{k: float(v) for k, v in geometry.items()})
        if geometry is not None and not isinstance(geometry, DeltaGeometry):
            raise ValidationError("DeltaRobot geometry", geometry, "a DeltaGeometry or a dict of lengths (m)")
        self.geometry = geometry or DeltaGeometry()
        self.workspace = workspace or Workspace(("x", "y", "z"), (-0.1, -0.1, 0.25), (0.1, 0.1, 0.5),
                                                ("m", "m", "m"), ("mm", "mm", "mm"), (1e3, 1e3, 1e3))
        self.sources = tuple(
            SourceSpec(n, 1, "m" if n in LINEAR else "rad", "linear" if n in LINEAR else "angular",
                       f"Δ{n}: {_DESCRIPTIONS[n.split('_')[0]]}" + (f", leg {n.split('_')[1]}" if "_" in n else ""))
            for n in PARAMETER_NAMES)
        self.newton_tol, self.max_iter = float(newton_tol), int(max_iter)

    # --- KK chains (eq. 1, 2, 6) -----------------------------------------------------------------
    def _unpack(self, errors):
        """errors (..., 47) -> common (..., ) and per-leg (..., 3) error arrays."""
        e = {"Ra": errors[..., _INDEX["Ra"]][..., None], "Rb": errors[..., _INDEX["Rb"]][..., None]}
        for p, cols in _LEG_COL.items():
            e[p] = errors[..., cols]
        return e

    def branch_points(self, q1, q2, q3, errors, *, level_on_actual: bool = True):
        """End points of the two branches of every leg (eq. 6 with Table 2), in the base frame.

        q1: actuated joint variables; q2, q3: passive joint variables, all (..., 3) rad,
        broadcastable; errors: (..., 47) SI. Each joint turns by its variable plus its error
        ``Δq_j``; the dependent variables follow the paper's relations q6 = q3, q4 = q7 = -q3
        and the platform-level relation q5 = pi - q1 - q2. With ``level_on_actual`` (the
        closed-loop model) the level relation holds for the *actual* rotations of joints 1 and 2
        (j5 = pi - j1 - j2 + Δq5: the parallelogram keeps the lower bar parallel to the upper one
        whatever the encoder offset), so Δq1 is a pure actuator offset and Δq2 is absorbed by the
        free joint q2; without it (the paper's open chain, eq. 5) j5 = q5 + Δq5 with q5 from
        the nominal relation. Returns two tuples (x, y, z) of arrays (..., 3): rod-1 and rod-2
        branch ends. Works with complex inputs (complex-step derivatives).

        Parameters
        ----------
        q1, q2, q3 : array_like, shape (..., 3)
            Actuated joint variables and the passive joint variables ``q2``, ``q3`` of the three
            legs, rad (real or complex), broadcastable together and with ``errors``.
        errors : array_like, shape (..., 47)
            Error parameters in the order of :data:`PARAMETER_NAMES`, SI (m or rad).
        level_on_actual : bool
            True (closed-loop model): ``j5 = pi - j1 - j2 + Δq5``; False (open chain, eq. 5):
            ``j5 = pi - q1 - q2 + Δq5``.

        Returns
        -------
        branch1, branch2 : tuple of 3 ndarray, each shape (..., 3)
            ``(x, y, z)`` of the rod-1 and rod-2 branch ends of each leg, base frame, m.
        """
        e = self._unpack(errors)
        j1, j2 = q1 + e["q1"], q2 + e["q2"]
        j5 = np.pi - (j1 + j2 if level_on_actual else q1 + q2) + e["q5"]
        return self._chain(j1, j2, q3 + e["q3"], -q3 + e["q4"], j5, q3 + e["q6"], -q3 + e["q7"], e)

    def _chain(self, j1, j2, j3, j4, j5, j6, j7, e):
        """KK chains of Table 2 for given actual joint rotations j1..j7 (rad)."""
        g = self.geometry
        La, Lb, Ra, Rb = g.La + e["La"], g.Lb + e["Lb"], g.Ra + e["Ra"], g.Rb + e["Rb"]
        d = g.d + e["d"]
        a1, a3 = np.pi / 2 + e["alpha1"], -(np.pi / 2 + e["alpha3"])
        a5, a6 = np.pi / 2 + e["alpha5"], -(np.pi / 2 + e["alpha6"])
        th = g.theta + e["theta"]
        zero = 0.0 * (La + j1 + j2 + j3 + j5 + j6 + a1 + a3 + a5 + a6 + th + Ra + Rb)  # broadcast shape/dtype
        pE = (Rb + zero, zero, zero)  # Rot(x, pi/2) Trans(x, Rb) applied to the origin of E
        out = []
        for jq, jr, aj, r5, b in ((j3, j4, a3, -d, None), (j6, j7, a6, d, -2 * d)):
            p = _kk(pE, a5, 0.0, j5, r5)               # 5 (cut joint, antecedent 4 or 7)
            p = _kk(p, 0.0, Lb, jr, 0.0)                 # 4 or 7: rod end hinge
            p = _kk(p, aj, 0.0, jq, 0.0, b)              # 3 or 6: rod start hinge (6: b = -2d)
            p = _kk(p, 0.0, La, j2, d)                   # 2: upper bar
            p = _kk(p, a1, Ra, j1, 0.0)                  # 1: actuated joint
            p = _rot_z(np.cos(th), np.sin(th), p)        # A: leg on the base
            out.append(p)
        return out[0], out[1]

    def leg_points(self, q1, q2, q3, errors):
        """Leg end points (midpoint of the two branch ends), array (..., 3 legs, 3 xyz), m.

        Parameters
        ----------
        q1, q2, q3 : array_like, shape (..., 3)
            Actuated and passive joint variables of the three legs, rad (see :meth:`branch_points`).
        errors : array_like, shape (..., 47)
            Error parameters (:data:`PARAMETER_NAMES`), SI.

        Returns
        -------
        ndarray, shape (..., 3, 3)
            Leg end points, base frame, m: axis -2 is the leg, axis -1 is ``x, y, z``.
        """
        b1, b2 = self.branch_points(q1, q2, q3, errors)
        return np.stack([(u + v) / 2 for u, v in zip(b1, b2)], axis=-1)

    # --- inverse kinematics (eq. 3, 11) --------------------------------------------------------
    def inverse_kinematics(self, poses) -> np.ndarray:
        """Joint variables Q_k (eq. 11) of the nominal robot, shape (n, 3 legs, 7) rad.

        Solves eq. (3) leg by leg in closed form: in the leg frame, p' = Rot(z, -theta_i) P =
        (R + La c1 + Lb c3 c12, Lb s3, La s1 + Lb c3 s12) with R = Ra - Rb; the elbow-out solution
        of the actuated joint is kept. q4 = q7 = -q3, q6 = q3, q5 = pi - q1 - q2.

        Parameters
        ----------
        poses : array_like, shape (n, 3) or (3,)
            Platform positions ``(x, y, z)``, m.

        Returns
        -------
        ndarray, shape (n, 3, 7)
            Joint variables ``q1 .. q7`` of each leg, rad.

        Raises
        ------
        ValidationError
            If ``poses`` is not a finite (n, 3) array.
        KinematicsError
            If a pose is outside the workspace or out of reach of a leg.
        """
        poses = self.check_poses(poses)
        q1, q2, q3 = self._ik(poses)
        return np.stack([q1, q2, q3, -q3, np.pi - q1 - q2, q3, -q3], axis=-1)

    def _ik(self, poses):
        g = self.geometry
        th = g.theta
        c, s = np.cos(th), np.sin(th)
        x, y, z = poses[:, 0:1], poses[:, 1:2], poses[:, 2:3]
        xp, yp = c * x + s * y, -s * x + c * y  # (n, 3) leg frame
        wx, wz = xp - (g.Ra - g.Rb), np.broadcast_to(z, xp.shape)
        s3 = yp / g.Lb
        rho = g.Lb * np.sqrt(np.clip(1 - s3 ** 2, 0, None))
        r = np.hypot(wx, wz)
        K = (r ** 2 + g.La ** 2 - rho ** 2) / (2 * g.La * np.where(r > 0, r, 1.0))
        bad = (np.abs(s3) >= 1) | (np.abs(K) >= 1) | (r == 0)
        if bad.any():
            k = int(np.argwhere(bad.any(axis=1))[0, 0])
            raise KinematicsError(f"delta: pose {poses[k].tolist()} m is out of reach of leg "
                                  f"{int(np.argwhere(bad[k])[0, 0]) + 1}", poses=poses[bad.any(axis=1)])
        phi = np.arctan2(wz, wx)
        q1 = phi - np.arccos(K)  # elbow out: arm tip on the outer side of the base circle
        q12 = np.arctan2(wz - g.La * np.sin(q1), wx - g.La * np.cos(q1))
        q3 = np.arcsin(s3)
        return q1, q12 - q1, q3

    def forward_kinematics_nominal(self, q1) -> np.ndarray:
        """Closed-form forward kinematics of the error-free robot (intersection of 3 spheres).

        q1: (n, 3) actuated angles, rad. Returns (n, 3) platform positions, m (solution with z
        towards the platform). An independent check of :meth:`inverse_kinematics`.

        Parameters
        ----------
        q1 : array_like, shape (n, 3) or (3,)
            Actuated joint angles of the three legs, rad.

        Returns
        -------
        ndarray, shape (n, 3)
            Platform positions, m.

        Raises
        ------
        KinematicsError
            If the three spheres do not intersect (no assembly) for some row of ``q1``.
        """
        g = self.geometry
        q1 = np.atleast_2d(np.asarray(q1, dtype=float))
        c, s = np.cos(g.theta), np.sin(g.theta)
        rad = g.Ra - g.Rb + g.La * np.cos(q1)
        C = np.stack([c * rad, s * rad, g.La * np.sin(q1)], axis=-1)  # (n, 3 legs, 3)
        # |P - C_i|^2 = Lb^2: subtract leg 1 -> two linear equations, P = P0 + t n
        A = 2 * (C[:, 1:] - C[:, :1])                       # (n, 2, 3)
        bvec = np.sum(C[:, 1:] ** 2, -1) - np.sum(C[:, :1] ** 2, -1)  # (n, 2)
        nrm = np.cross(A[:, 0], A[:, 1])
        # particular solution of A P = b with minimum norm
        P0 = np.einsum("nij,nj->ni", np.linalg.pinv(A), bvec)
        nrm = nrm / np.linalg.norm(nrm, axis=1, keepdims=True)
        dP = P0 - C[:, 0]
        bq = np.sum(nrm * dP, 1)
        cq = np.sum(dP * dP, 1) - g.Lb ** 2
        disc = bq ** 2 - cq
        if np.any(disc < 0):
            k = int(np.argmax(disc < 0))
            raise KinematicsError(f"delta: actuated angles {q1[k].tolist()} rad give no assembly", poses=q1[disc < 0])
        t = np.stack([-bq + np.sqrt(disc), -bq - np.sqrt(disc)], 1)
        sols = P0[:, None, :] + t[:, :, None] * nrm[:, None, :]
        pick = np.argmax(sols[:, :, 2], axis=1)
        return sols[np.arange(len(q1)), pick]

    # --- forward kinematics with errors (eq. 5) ------------------------------------------------
    def _residual(self, X, q1, errors):
        """Loop-closure residual: leg end point i minus P, (..., 9). X = (P, q2_1, q3_1, ..., q3_3)."""
        P = X[..., :3]
        q2 = X[..., 3::2]
        q3 = X[..., 4::2]
        legs = self.leg_points(q1, q2, q3, errors)  # (..., 3, 3)
        return (legs - P[..., None, :]).reshape(*legs.shape[:-2], 9)

    def _closure_jacobian(self, X, q1, errors, h=1e-30):
        """d residual / d X, (..., 9, 9), by complex step (exact to rounding)."""
        shape = np.broadcast_shapes(X.shape[:-1], q1.shape[:-1], errors.shape[:-1])
        J = np.zeros(shape + (9, 9))
        J[..., :, :3] = -np.tile(np.eye(3), (3, 1))
        q2 = X[..., 3::2].astype(complex)
        q3 = X[..., 4::2].astype(complex)
        for k, (a, b) in enumerate(((q2 + 1j * h, q3), (q2, q3 + 1j * h))):
            legs = self.leg_points(q1, a, b, errors).imag / h  # (..., 3 legs, 3): leg i depends on its own joints
            for i in range(3):
                J[..., 3 * i:3 * i + 3, 3 + 2 * i + k] = legs[..., i, :]
        return J

    def _nominal_state(self, poses):
        q1, q2, q3 = self._ik(poses)
        X = np.empty((len(poses), 9))
        X[:, :3] = poses
        X[:, 3::2], X[:, 4::2] = q2, q3
        zero = np.zeros((len(poses), len(PARAMETER_NAMES)))
        J = self._closure_jacobian(X, q1, zero)
        cond = np.linalg.cond(J)
        if np.any(cond > 1e8):
            k = int(np.argmax(cond))
            raise KinematicsError(f"delta: pose {poses[k].tolist()} m is (near) singular "
                                  f"(loop-closure Jacobian condition {cond[k]:.3g})", poses=poses[cond > 1e8])
        return q1, X, J

    def forward_kinematics(self, poses, errors) -> np.ndarray:
        """Platform position of the robot *with errors*, commanded to the nominal IK of ``poses``.

        poses: (n, 3) m; errors: (n, s, 47) SI (or (s, 47) / (47,), broadcast over poses).
        Solves the 9 loop-closure equations (eq. 3 with eq. 5: leg end point i = P) for P and the
        free passive joints q2_i, q3_i by a chord-Newton iteration from the nominal solution
        (Jacobian at the nominal pose, exact by complex step), vectorised over poses and samples,
        until the step is below ``newton_tol`` (m / rad). Returns (n, s, 3) m. Raises
        ConvergenceError naming the pose if it does not converge.

        Parameters
        ----------
        poses : array_like, shape (n, 3)
            Commanded platform positions, m.
        errors : array_like, shape (n, s, 47), (s, 47) or (47,)
            Error parameters (:data:`PARAMETER_NAMES`), SI; ``s`` samples per pose.

        Returns
        -------
        ndarray, shape (n, s, 3)
            Actual platform positions, m.

        Raises
        ------
        ValidationError
            If ``poses`` or ``errors`` has a wrong shape or non-finite entries.
        KinematicsError
            If a pose is outside the workspace, out of reach or (near) singular.
        ConvergenceError
            If the iteration does not converge within ``max_iter`` iterations.
        """
        return self._solve(poses, errors)[1][..., :3]

    def closure_residual(self, poses, errors) -> np.ndarray:
        """Max over legs of ``|leg end point - P|`` (m) at the solution of :meth:`forward_kinematics`.

        Parameters
        ----------
        poses : array_like, shape (n, 3)
            Commanded platform positions, m.
        errors : array_like, shape (n, s, 47), (s, 47) or (47,)
            Error parameters, SI.

        Returns
        -------
        ndarray, shape (n, s)
            Largest loop-closure residual over the three legs, m.

        Raises
        ------
        ValidationError, KinematicsError, ConvergenceError
            As :meth:`forward_kinematics`.
        """
        q1, X, errors = self._solve(poses, errors)
        r = self._residual(X, q1[:, None, :], errors).reshape(*X.shape[:-1], 3, 3)
        return np.max(np.linalg.norm(r, axis=-1), axis=-1)

    def _solve(self, poses, errors):
        poses = self.check_poses(poses)
        errors = self._check_errors(errors, len(poses))
        q1, X0, J0 = self._nominal_state(poses)
        Jinv = np.linalg.inv(J0)[:, None]              # (n, 1, 9, 9)
        q1b = q1[:, None, :]
        X = np.broadcast_to(X0[:, None, :], errors.shape[:2] + (9,)).copy()
        for _ in range(self.max_iter):
            r = self._residual(X, q1b, errors)
            step = np.einsum("nsij,nsj->nsi", np.broadcast_to(Jinv, r.shape + (9,)), r)
            X -= step
            if np.max(np.abs(step), initial=0.0) < self.newton_tol:
                return q1, X, errors
        bad = np.max(np.abs(step), axis=-1) >= self.newton_tol
        k = int(np.argwhere(bad.any(axis=1))[0, 0])
        raise ConvergenceError(f"delta: forward kinematics with errors did not converge at pose "
                               f"{poses[k].tolist()} m after {self.max_iter} iterations "
                               f"(step {np.max(np.abs(step)):.3g})")

    def position_and_jacobian(self, pose, errors, h: float = 1e-30):
        """Platform position with errors and its exact Jacobian w.r.t. the 47 errors *at* those errors.

        pose: (3,) m; errors: (s, 47) SI. Returns P (s, 3) m and dP/de (s, 3, 47) by the implicit
        function theorem at the solved loop closure (dX/de = -(dr/dX)^-1 dr/de, both by complex
        step). Used by gradient-based solvers of the paper's problem (12).

        Parameters
        ----------
        pose : array_like, shape (3,)
            Commanded platform position, m.
        errors : array_like, shape (s, 47) or (47,)
            Error parameters at which to evaluate, SI.
        h : float
            Complex step, dimensionless (exact to rounding for any small value).

        Returns
        -------
        P : ndarray, shape (s, 3)
            Actual platform positions, m.
        dP_de : ndarray, shape (s, 3, 47)
            Jacobian of ``P`` w.r.t. the errors, m per m or m per rad.

        Raises
        ------
        ValidationError, KinematicsError, ConvergenceError
            As :meth:`forward_kinematics`.
        """
        pose = self.check_poses(pose)
        q1, X, errors = self._solve(pose, np.atleast_2d(errors)[None])
        X, errors = X[0], errors[0]                              # (s, 9), (s, 47)
        JX = self._closure_jacobian(X, q1, errors)              # (s, 9, 9)
        m = errors.shape[-1]
        E = errors[:, None, :] + np.eye(m)[None] * (1j * h)      # (s, m, 47)
        dr = self._residual(X[:, None, :], q1[:, None, :], E).imag / h  # (s, m, 9)
        dX = -np.linalg.solve(JX[:, None], dr[..., None])[..., 0]       # (s, m, 9)
        return X[:, :3], dX[..., :3].transpose(0, 2, 1)

    def _check_errors(self, errors, n_poses):
        try:
            errors = np.asarray(errors, dtype=float)
        except (TypeError, ValueError) as exc:
            raise ValidationError("errors", errors, "an array of numbers") from exc
        if errors.ndim == 1:
            errors = errors[None, None, :]
        elif errors.ndim == 2:
            errors = errors[None, :, :]
        if errors.ndim != 3 or errors.shape[-1] != len(PARAMETER_NAMES) or errors.shape[0] not in (1, n_poses):
            raise ValidationError("errors shape", errors.shape,
                                  f"(n_poses={n_poses}, n_samples, {len(PARAMETER_NAMES)})")
        if not np.all(np.isfinite(errors)):
            raise ValidationError("errors", "non-finite entries", "finite numbers")
        return np.broadcast_to(errors, (n_poses,) + errors.shape[1:])

    # --- protocol -------------------------------------------------------------------------------
    def sensitivity(self, poses) -> np.ndarray:
        """First-order map (n, 6, 47): d P / d e = -J_X^{-1} d r / d e (implicit function of eq. 3).

        ``d r / d e`` by complex step through the KK chains (exact to rounding). Rows 3-5 are zero
        (position-only model).

        Parameters
        ----------
        poses : array_like, shape (n, 3)
            Platform positions, m.

        Returns
        -------
        ndarray, shape (n, 6, 47)
            Sensitivity of the pose error to each error parameter, m per m or m per rad (rows 0-2);
            rows 3-5 are zero.

        Raises
        ------
        ValidationError
            If ``poses`` is not a finite (n, 3) array.
        KinematicsError
            If a pose is outside the workspace, out of reach or (near) singular.
        """
        poses = self.check_poses(poses)
        q1, X0, J0 = self._nominal_state(poses)
        n, m = len(poses), len(PARAMETER_NAMES)
        h = 1e-30
        E = np.eye(m)[None] * (1j * h)               # (1, m, 47)
        dr = self._residual(X0[:, None, :], q1[:, None, :], E).imag / h  # (n, m, 9)
        dX = -np.linalg.solve(J0[:, None], dr[..., None])[..., 0]       # (n, m, 9)
        out = np.zeros((n, 6, m))
        out[:, :3, :] = dX[..., :3].transpose(0, 2, 1)
        return out

    def pose_error(self, poses, errors) -> np.ndarray:
        """Nonlinear position error (n, s, 6): forward kinematics with errors minus the pose.

        Parameters
        ----------
        poses : array_like, shape (n, 3)
            Commanded platform positions, m.
        errors : array_like, shape (n, s, 47), (s, 47) or (47,)
            Error parameters, SI.

        Returns
        -------
        ndarray, shape (n, s, 6)
            Position error ``P - pose``, m (columns 0-2); columns 3-5 (orientation) are zero.

        Raises
        ------
        ValidationError, KinematicsError, ConvergenceError
            As :meth:`forward_kinematics`.
        """
        poses = self.check_poses(poses)
        P = self.forward_kinematics(poses, errors)
        out = np.zeros(P.shape[:2] + (6,))
        out[..., :3] = P - poses[:, None, :]
        return out

    # --- the paper's open-chain error (eq. 6-10) ----------------------------------------------------
    def open_chain_points(self, poses, errors) -> np.ndarray:
        """Branch end points with errors at the *nominal* joint variables Q_k (eq. 6, as in eq. 10).

        This is the quantity the paper's objective (10) compares with P + ΔP: every serial
        sub-chain (3 legs x 2 branches) is evaluated with its errors, joints held at Q_k.
        poses (n, 3) m, errors (n, s, 47). Returns (n, s, 3 legs, 2 branches, 3) m.

        Parameters
        ----------
        poses : array_like, shape (n, 3)
            Platform positions, m, giving the nominal joint variables ``Q_k``.
        errors : array_like, shape (n, s, 47)
            Error parameters, SI.

        Returns
        -------
        ndarray, shape (n, s, 3, 2, 3)
            Branch end points, base frame, m (pose, sample, leg, branch, ``x, y, z``).

        Raises
        ------
        ValidationError
            If ``poses`` is not a finite (n, 3) array.
        KinematicsError
            If a pose is outside the workspace or out of reach of a leg.
        """
        poses = self.check_poses(poses)
        errors = np.asarray(errors)
        q1, q2, q3 = self._ik(poses)
        b1, b2 = self.branch_points(q1[:, None], q2[:, None], q3[:, None], errors, level_on_actual=False)
        return np.stack([np.stack(b1, -1), np.stack(b2, -1)], axis=-2)
