"""The planar 5-bar linkage of Deng 2012, Ch. IV: inverse geometry, modified DH table, clearance model.

Geometry (Fig. IV.1, Tab. IV.1-IV.2): base joints ``A = (-L0/2, 0)`` and ``B = (L0/2, 0)``
(actuated, angles ``theta1``, ``theta3``); leg 1 ``A-C-E`` (links ``L1``, ``L2``), leg 2
``B-D-E`` (``L3``, ``L4``); the end-effector ``P`` lies on link ``L2`` extended by ``L5`` beyond
``E`` (``L5 = 0`` in the thesis, so ``P = E``). Joints ``C``, ``D``, ``E`` are passive.

Working mode (eqs. IV.5-IV.18): ``leg1`` elbow-up (``+1``: ``theta1 = theta_AP + theta_A``) or
elbow-down (``-1``); ``leg2`` likewise. The thesis analyses "working mode 2"; its figure is
missing from the extracted text, and we take the combination its Sec. IV.1 selects: leg 1
elbow-up, leg 2 elbow-down (``modes=(+1, -1)``). In this mode both elbows lie outside the
triangle ``A P B``, and the type-2 (parallel) singularity -- ``C``, ``E``, ``D`` aligned -- crosses
the thesis's grid (through ``(0, 50) mm``), as the thesis says its workspace does.

Units: metres and radians inside; poses are ``(x, y)`` in metres.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from evotol.errors import KinematicsError, ValidationError
from robots.base import RobotErrorModel, SourceSpec, Workspace
from robots.clearance.kinematics import DHFrame, DHTree
from robots.clearance.model import Chain, ClearanceBounds, ClearanceMechanism, Joint

MM = 1e-3
#: Tab. IV.2 (m)
THESIS_LENGTHS = dict(L0=100 * MM, L1=50 * MM, L2=50 * MM, L3=50 * MM, L4=50 * MM, L5=0.0)
#: the thesis's Cartesian grid, Sec. IV.3 (m): x in [-20, 20] mm, y in [30, 70] mm, 41 x 41
THESIS_WORKSPACE = Workspace(names=("x", "y"), low=(-20 * MM, 30 * MM), high=(20 * MM, 70 * MM),
                             units=("m", "m"), display_units=("mm", "mm"), display_scale=(1e3, 1e3))
JOINT_NAMES = ("A", "C", "B", "D", "E")


def _wrap(a):
    return (a + np.pi) % (2 * np.pi) - np.pi


@dataclass(frozen=True)
class FiveBar:
    """A 5-bar linkage (lengths in m) in a working mode ``modes = (leg1, leg2)``, +1 elbow-up.

    Parameters
    ----------
    L0 : float
        Base length ``A-B``, m (thesis: 100 mm).
    L1, L2 : float
        Leg-1 links ``A-C`` and ``C-E``, m (50 mm each).
    L3, L4 : float
        Leg-2 links ``B-D`` and ``D-E``, m (50 mm each).
    L5 : float
        Offset ``E-P`` along link ``C-E`` extended, m (0 in the thesis: ``P = E``).
    modes : tuple of int
        Working mode ``(leg1, leg2)``, each +1 (elbow-up) or -1 (elbow-down); default ``(1, -1)``.
    workspace : Workspace
        Pose box; default the thesis's grid ``x`` in [-20, 20] mm, ``y`` in [30, 70] mm.

    Raises
    ------
    ValidationError
        If ``L0`` ... ``L4`` is not positive, ``L5`` is negative, or ``modes`` is not a pair of +1/-1.
    """

    L0: float = THESIS_LENGTHS["L0"]
    L1: float = THESIS_LENGTHS["L1"]
    L2: float = THESIS_LENGTHS["L2"]
    L3: float = THESIS_LENGTHS["L3"]
    L4: float = THESIS_LENGTHS["L4"]
    L5: float = THESIS_LENGTHS["L5"]
    modes: tuple[int, int] = (1, -1)
    workspace: Workspace = field(default=THESIS_WORKSPACE)

    def __post_init__(self):
        for k in ("L0", "L1", "L2", "L3", "L4"):
            v = getattr(self, k)
            if not (np.isfinite(v) and v > 0):
                raise ValidationError(f"FiveBar.{k}", v, "a length > 0 (m)")
        if not (np.isfinite(self.L5) and self.L5 >= 0):
            raise ValidationError("FiveBar.L5", self.L5, "a length >= 0 (m)")
        if tuple(self.modes) not in ((1, 1), (1, -1), (-1, 1), (-1, -1)):
            raise ValidationError("FiveBar.modes", self.modes, "a pair of +1/-1 (elbow-up/-down per leg)")

    # ------------------------------------------------------------------ geometry
    def inverse_geometry(self, poses) -> dict[str, np.ndarray]:
        """Joint angles theta1..theta5 (rad) and points A..E, P (m) for poses (n, 2), eqs. IV.1-IV.19.

        Raises KinematicsError naming the pose when it is out of reach (no NaN).

        Parameters
        ----------
        poses : array_like, shape (n, 2) or (2,)
            End-effector positions ``(x, y)``, m.

        Returns
        -------
        dict of str to ndarray
            ``"theta1"`` ... ``"theta5"``: (n,) joint angles, rad (``theta5`` wrapped to
            ``[-pi, pi)``); ``"A"``, ``"B"``, ``"C"``, ``"D"``, ``"E"``, ``"P"``: (n, 2) points, m.

        Raises
        ------
        ValidationError
            If ``poses`` is not an (n, 2) array.
        KinematicsError
            If leg 1 or leg 2 cannot reach a pose.
        """
        P = np.atleast_2d(np.asarray(poses, float))
        if P.ndim != 2 or P.shape[1] != 2:
            raise ValidationError("poses shape", P.shape, "(n, 2): x, y in metres")
        X, Y = P[:, 0], P[:, 1]
        xa, xb = -self.L0 / 2, self.L0 / 2
        l2 = self.L2 + self.L5
        lap = np.hypot(X - xa, Y)                                       # IV.1
        th_ap = np.arctan2(Y, X - xa)                                   # IV.2
        ca = (self.L1 ** 2 + lap ** 2 - l2 ** 2) / (2 * self.L1 * lap)  # IV.3
        cc = (self.L1 ** 2 + l2 ** 2 - lap ** 2) / (2 * self.L1 * l2)   # IV.4
        bad = ~((np.abs(ca) <= 1) & (np.abs(cc) <= 1) & (lap > 0))
        if bad.any():
            raise KinematicsError(f"5-bar leg 1 cannot reach pose {P[bad][0].tolist()} m", poses=P[bad])
        tA, tC = np.arccos(ca), np.arccos(cc)
        if self.modes[0] > 0:                                           # IV.5-IV.6 (elbow-up)
            th1, th2 = th_ap + tA, -(np.pi - tC)
        else:                                                           # IV.7-IV.8 (elbow-down)
            th1, th2 = th_ap - tA, np.pi - tC
        XE = X - self.L5 * np.cos(th1 + th2)                            # IV.9
        YE = Y - self.L5 * np.sin(th1 + th2)                            # IV.10
        lbe = np.hypot(XE - xb, YE)                                     # IV.11
        th_be = np.arctan2(YE, XE - xb)                                 # IV.12
        cb = (lbe ** 2 + self.L3 ** 2 - self.L4 ** 2) / (2 * lbe * self.L3)   # IV.13
        cd = (self.L3 ** 2 + self.L4 ** 2 - lbe ** 2) / (2 * self.L3 * self.L4)  # IV.14
        bad = ~((np.abs(cb) <= 1) & (np.abs(cd) <= 1) & (lbe > 0))
        if bad.any():
            raise KinematicsError(f"5-bar leg 2 cannot reach pose {P[bad][0].tolist()} m", poses=P[bad])
        tB, tD = np.arccos(cb), np.arccos(cd)
        if self.modes[1] > 0:                                           # IV.15-IV.16
            th3, th4 = th_be + tB, -(np.pi - tD)
        else:                                                           # IV.17-IV.18
            th3, th4 = th_be - tB, np.pi - tD
        th5 = _wrap((th1 + th2) - (th3 + th4))                          # IV.19
        A = np.stack([np.full_like(X, xa), np.zeros_like(X)], 1)
        B = np.stack([np.full_like(X, xb), np.zeros_like(X)], 1)
        C = A + self.L1 * np.stack([np.cos(th1), np.sin(th1)], 1)
        D = B + self.L3 * np.stack([np.cos(th3), np.sin(th3)], 1)
        E = np.stack([XE, YE], 1)
        return dict(theta1=th1, theta2=th2, theta3=th3, theta4=th4, theta5=th5, A=A, B=B, C=C, D=D, E=E, P=P)

    def joint_values(self, poses) -> dict[str, np.ndarray]:
        """Joint angles ``theta1`` ... ``theta5`` of :meth:`inverse_geometry` (the clearance model's joint values).

        Parameters
        ----------
        poses : array_like, shape (n, 2) or (2,)
            End-effector positions ``(x, y)``, m.

        Returns
        -------
        dict of str to ndarray
            ``"theta1"`` ... ``"theta5"``: (n,) joint angles, rad.

        Raises
        ------
        ValidationError, KinematicsError
            As :meth:`inverse_geometry`.
        """
        g = self.inverse_geometry(poses)
        return {k: g[k] for k in ("theta1", "theta2", "theta3", "theta4", "theta5")}

    def parallel_singularity(self, poses) -> np.ndarray:
        """Type-2 singularity measure: sine of the angle between links C-E and D-E (0 when C, E, D
        are aligned, the parallel singularity of the 5-bar).

        Parameters
        ----------
        poses : array_like, shape (n, 2) or (2,)
            End-effector positions ``(x, y)``, m.

        Returns
        -------
        ndarray, shape (n,)
            Signed sine of the angle from ``C-E`` to ``D-E``, dimensionless, in [-1, 1].

        Raises
        ------
        ValidationError, KinematicsError
            As :meth:`inverse_geometry`.
        """
        g = self.inverse_geometry(poses)
        u, v = g["E"] - g["C"], g["E"] - g["D"]
        return (u[:, 0] * v[:, 1] - u[:, 1] * v[:, 0]) / (np.linalg.norm(u, axis=1) * np.linalg.norm(v, axis=1))

    def singularity_locus(self, x, y_low: float, y_high: float, n_bisect: int = 60) -> np.ndarray:
        """Points (x, y) (m) of the parallel singularity (C, E, D aligned) inside ``[y_low, y_high]``
        for each x of ``x``: the sign change of :meth:`parallel_singularity` along y, found by
        bisection (vectorised). x values with no crossing in the range give no point.

        Parameters
        ----------
        x : array_like, shape (k,)
            Abscissae at which to look for the singularity, m.
        y_low, y_high : float
            Search range in ``y``, m, sampled at 81 points before bisection.
        n_bisect : int
            Bisection steps per crossing.

        Returns
        -------
        ndarray, shape (p, 2)
            Singular points ``(x, y)``, m, sorted by ``x`` then ``y`` (several per ``x`` if the
            locus crosses the range more than once; (0, 2) if none).

        Raises
        ------
        ValidationError, KinematicsError
            As :meth:`inverse_geometry` (a grid point out of reach raises).
        """
        x = np.asarray(x, float)
        ys = np.linspace(y_low, y_high, 81)
        X, Yg = np.meshgrid(x, ys, indexing="ij")
        s = self.parallel_singularity(np.stack([X.ravel(), Yg.ravel()], 1)).reshape(X.shape)
        pts = []
        for k in range(len(ys) - 1):
            hit = (np.sign(s[:, k]) * np.sign(s[:, k + 1]) < 0) | (s[:, k] == 0)
            if not hit.any():
                continue
            lo, hi = np.full(hit.sum(), ys[k]), np.full(hit.sum(), ys[k + 1])
            xs = x[hit]
            slo = s[hit, k]
            for _ in range(n_bisect):
                mid = (lo + hi) / 2
                sm = self.parallel_singularity(np.stack([xs, mid], 1))
                left = np.sign(sm) == np.sign(slo)
                lo, hi = np.where(left, mid, lo), np.where(left, hi, mid)
            pts.append(np.stack([xs, (lo + hi) / 2], 1))
        if not pts:
            return np.zeros((0, 2))
        out = np.concatenate(pts)
        return out[np.lexsort((out[:, 1], out[:, 0]))]

    def forward_geometry(self, theta1, theta3, lengths: dict | None = None, reference=None) -> np.ndarray:
        """End-effector position (n, 2) from the actuated angles (circle intersection at E), with
        optionally perturbed lengths ``lengths = {L0..L5: (n,) arrays}`` (m). The assembly
        branch is the one closest to ``reference`` points E (n, 2) (the nominal E).

        Parameters
        ----------
        theta1, theta3 : array_like
            Actuated angles at ``A`` and ``B``, rad, broadcastable (e.g. (n,) or (n, m)).
        lengths : dict of str to array_like, or None
            Replacements for some of ``L0`` ... ``L5``, m, broadcastable with the angles; None: nominal.
        reference : array_like, shape (..., 2), or None
            Points ``E`` (m) selecting the assembly branch; None: the branch on the left of ``C -> D``.

        Returns
        -------
        ndarray, shape (..., 2)
            End-effector positions ``P``, m.

        Raises
        ------
        KinematicsError
            If the loop cannot close for some input (circles at ``C`` and ``D`` do not intersect).
        """
        Ls = {k: getattr(self, k) for k in ("L0", "L1", "L2", "L3", "L4", "L5")}
        if lengths:
            Ls.update(lengths)
        th1, th3 = np.asarray(theta1, float), np.asarray(theta3, float)
        C = np.stack([-Ls["L0"] / 2 + Ls["L1"] * np.cos(th1), Ls["L1"] * np.sin(th1) + 0 * th1], -1)
        D = np.stack([Ls["L0"] / 2 + Ls["L3"] * np.cos(th3), Ls["L3"] * np.sin(th3) + 0 * th3], -1)
        dv = D - C
        dist = np.linalg.norm(dv, axis=-1)
        a = (Ls["L2"] ** 2 - Ls["L4"] ** 2 + dist ** 2) / (2 * dist)
        h2 = Ls["L2"] ** 2 - a ** 2
        if np.any(h2 < 0):
            raise KinematicsError("5-bar: loop cannot close for the given actuated angles / lengths")
        h = np.sqrt(h2)
        ex = dv / dist[..., None]
        ey = np.stack([-ex[..., 1], ex[..., 0]], -1)
        E1 = C + a[..., None] * ex + h[..., None] * ey
        E2 = C + a[..., None] * ex - h[..., None] * ey
        if reference is None:
            E = E1
        else:
            ref = np.asarray(reference, float)
            pick = np.linalg.norm(E1 - ref, axis=-1) <= np.linalg.norm(E2 - ref, axis=-1)
            E = np.where(pick[..., None], E1, E2)
        u = (E - C) / np.asarray(Ls["L2"], float)[..., None]
        return E + np.asarray(Ls["L5"], float)[..., None] * u

    # ------------------------------------------------------------------ clearance model
    def dh_tree(self) -> DHTree:
        """Modified DH table IV.1 (frames 1..7; frames 5 and 6 both sit at E: the cut joint).

        Returns
        -------
        DHTree
            Frames ``"1"`` ... ``"7"`` with joint variables ``theta1`` ... ``theta5``, lengths in m.
        """
        return DHTree([
            DHFrame("1", "0", sigma=0, mu=1, d=-self.L0 / 2, theta="theta1"),
            DHFrame("2", "1", sigma=0, d=self.L1, theta="theta2"),
            DHFrame("3", "0", sigma=0, mu=1, d=self.L0 / 2, theta="theta3"),
            DHFrame("4", "3", sigma=0, d=self.L3, theta="theta4"),
            DHFrame("5", "4", sigma=0, d=self.L4, theta="theta5"),
            DHFrame("6", "2", sigma=2, d=self.L2),
            DHFrame("7", "6", sigma=2, d=self.L5),
        ])

    def clearance_mechanism(self, *, b_xy: float = 0.1 * MM, b_z: float = 0.1 * MM, beta_xy: float = 0.01,
                            beta_z_passive: float = 0.2, beta_z_active: float = 0.0,
                            bounds: dict[str, ClearanceBounds] | None = None) -> ClearanceMechanism:
        """The closed-loop 5-bar with clearances in joints A, C, B, D, E (Sec. IV.3, Fig. IV.4).

        Defaults are the thesis's: ``beta_xy = 0.01 rad``, ``beta_z = 0.2 rad`` for the passive
        joints C, D, E and 0 for the actuated A, B, translational clearances 0.1 mm.
        Leg 1 = chain ``A, C`` (thesis joints (1,1), (1,2)); leg 2 = chain ``B, D, E``
        ((2,1), (2,2), (2,3)).

        Parameters
        ----------
        b_xy, b_z : float
            Radial and axial translational clearance of each joint, m (0.1 mm).
        beta_xy : float
            Tilt clearance about in-plane axes, rad (0.01).
        beta_z_passive, beta_z_active : float
            Rotational clearance about the joint axis of the passive (C, D, E) and actuated (A, B)
            joints, rad (0.2 and 0).
        bounds : dict of str to ClearanceBounds, or None
            Per-joint bounds overriding the above, keyed by joint name ``A``, ``C``, ``B``, ``D``, ``E``.

        Returns
        -------
        ClearanceMechanism
            Planar closed-loop mechanism with end-effector ``P`` (frame 7).
        """
        frames = dict(A="1", C="2", B="3", D="4", E="5")
        active = dict(A=True, B=True, C=False, D=False, E=False)
        joints = []
        for name in JOINT_NAMES:
            bd = (bounds or {}).get(name) or ClearanceBounds.thesis(
                active[name], b_xy=b_xy, b_z=b_z, beta_xy=beta_xy, beta_z_passive=beta_z_passive,
                beta_z_active=beta_z_active)
            joints.append(Joint(name, frames[name], active[name], bd))
        return ClearanceMechanism(
            name="5-bar", tree=self.dh_tree(), joints=joints, bodies={"P": "7"},
            chains=[Chain("leg1", "base", "P", ("A", "C")), Chain("leg2", "base", "P", ("B", "D", "E"), path_end="5")],
            end_effector="P", joint_values=self.joint_values, planar=True)


# ---------------------------------------------------------------------------- geometric sensitivity
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
#: default workspace of the geometric model: the thesis's x range above the singular circle |OP| = 50 mm
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
        The linkage; None: :class:`FiveBar` () (thesis lengths, modes ``(1, -1)``).
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

        Parameters
        ----------
        poses : array_like, shape (n, 2)
            End-effector positions, m.

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
        """First-order map of the 8 sources onto the pose error (eqs. IV.37-IV.43).

        Parameters
        ----------
        poses : array_like, shape (n, 2)
            End-effector positions, m.

        Returns
        -------
        ndarray, shape (n, 6, 8)
            Rows ``dp_x, dp_y`` (m per unit source) from :meth:`jacobian_thesis`, row 5 the rotation
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
        """Exact pose error: the loop re-solved with perturbed lengths and actuated angles.

        Parameters
        ----------
        poses : array_like, shape (n, 2)
            End-effector positions, m.
        errors : array_like, shape (n, m, 8)
            Source values ``dL0 .. dL5`` (m), ``dtheta1, dtheta3`` (rad), ``m`` samples per pose.

        Returns
        -------
        ndarray, shape (n, m, 6)
            Columns 0-1: position error, m; column 5: rotation of link ``C-E``, rad, wrapped to
            ``[-pi, pi)``; columns 2-4 zero.

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
    poses : array_like, shape (n, 2)
        End-effector positions, m.
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
        :func:`robots.clearance.max_pose_error`).

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
    Jb = geo.sensitivity(poses)                         # [dp; dtheta] (robots.base order)
    J = np.concatenate([Jb[:, 3:], Jb[:, :3]], axis=1)  # -> thesis order [dtheta; dp]
    from robots.clearance import max_pose_error
    return max_pose_error(mech, poses, tol=tol, extra=(J, t))
