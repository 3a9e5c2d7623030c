"""The planar 5-bar linkage of Deng 2012, Ch. IV: inverse geometry, modified DH table, clearance model.

:class:`FiveBar`, its geometry (eqs. IV.1-IV.19) and its joint-clearance mechanism (Tab. IV.1,
Sec. IV.3); the sensitivity to geometric errors is :mod:`evotol.robots.fivebar.geometric`.

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

The parameters several definitions of this module share are described once, here.

Parameters
----------
poses : array_like, shape (n, 2) or (2,)
    End-effector positions ``(x, y)``, m.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from evotol.errors import KinematicsError, ValidationError
from evotol.robots.base import Workspace
from evotol.robots.clearance.kinematics import DHFrame, DHTree
from evotol.robots.clearance.model import Chain, ClearanceBounds, ClearanceMechanism, Joint
from evotol.units import MM

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
