"""The IRSBot-2 (Deng 2012, Ch. II and VI): inverse geometry, modified DH tables II.1-II.2, clearance model.

A 2-DOF translational spatial robot: two hybrid legs, each a parallelogram (proximal module,
actuated crank ``A_iB_i`` and passive crank ``D_iC_i``, coupler ``C_iB_i`` carrying the elbow
``E_i``) in series with a spatial distal module of two links ``E_jiF_ji`` (length ``l2``) with a
universal joint at each end (four revolute joints ``7..10``). The platform point ``P = (x, 0, z)``
moves in the plane ``x_0 O z_0`` (``z`` up; the robot hangs below the base, ``z < 0``).

Units: metres and radians; poses are ``(x, z)`` in metres.

Corrections to the printed equations (each checked against the DH tables by closing all loops
in :func:`IRSBot2.loop_residual`):

* eq. II.1 prints ``l2eq = sqrt(l2^2 - (a1 - a2)^2 cos(beta))``; the offsets of ``E_11`` and
  ``F_11`` from the plane ``y = 0`` are ``a1 cos(beta)`` and ``a2 cos(beta)`` (eqs. II.16-II.17), so
  ``l2eq = sqrt(l2^2 - (a1 - a2)^2 cos(beta)^2)``. The printed form is kept as
  ``l2eq_variant="printed"`` (the loops then do not close);
* eq. II.8 (``psi_2``) repeats eq. II.7 with ``q2``; from eq. II.4 the leg-2 terms are
  ``x - b - l1 cos q2 + a1 sin(beta) + p``;
* eq. II.16 prints ``y_F11 = -a1 cos(beta)``; it is ``-a1 cos(beta) + l2 cos(theta8) sin(theta7)``
  (eq. II.19 is the inverse of that corrected form).
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from evotol.errors import KinematicsError, ValidationError
from robots.base import Workspace
from robots.clearance.kinematics import DHFrame, DHTree
from robots.clearance.model import Chain, ClearanceBounds, ClearanceMechanism, Joint
from robots.geometry import largest_centred_rectangle, largest_rectangle

MM = 1e-3
PI = np.pi

#: Tab. VI.1-VI.2 (used for Figs. VI.1-VI.3): b, d, alpha_d, beta, e, l1, l2, a1, a2, p
THESIS_VI1 = dict(b=50 * MM, d=50 * MM, alpha_d=PI / 6, beta=PI / 6, e=0.0, l1=50 * MM, l2=50 * MM,
                  a1=30 * MM, a2=15 * MM, p=25 * MM)
#: Tab. VI.4-VI.5 (used for Figs. VI.4-VI.5): as VI.1-VI.2 with beta = pi/4
THESIS_VI4 = dict(THESIS_VI1, beta=PI / 4)


@dataclass(frozen=True)
class IRSBot2:
    """IRSBot-2 geometry (m, rad), Fig. II.4. ``modes``: sign of the square root in eqs. II.5/II.6
    per leg; the default ``(-1, -1)`` puts both elbows outside (``B_1`` left of ``A_1``, ``B_2``
    right of ``A_2``), the configuration of Figs. II.1-II.2, in which the type-2 singularity
    (``psi_1 = psi_2``) closes a region below the base, as in Fig. VI.2.

    Parameters
    ----------
    b : float
        Base radius ``O A_i`` (actuated joints at ``x = -+b``), m (thesis: 50 mm).
    d : float
        Length of the parallelogram bars ``A_iD_i`` and ``B_iC_i``, m (50 mm).
    alpha_d : float
        Angle between the first universal-joint axis at the elbow and ``z_0`` (Sec. II.2.2), rad,
        in (0, pi/2) (pi/6).
    beta : float
        Angle of the offsets ``E_iE_ji`` (and ``H_hiF_ji``) about the ``x_0 z_0`` plane (Fig. II.4),
        rad, in [0, pi/2) (pi/6; pi/4 for Tab. VI.4).
    e : float
        Offset of the elbow below the crank end ``B_i`` (eqs. II.3-II.4), m (0).
    l1 : float
        Proximal crank length ``A_iB_i``, m (50 mm).
    l2 : float
        Length of each distal link ``E_jiF_ji``, m (50 mm); must exceed
        ``abs(a1 - a2) cos(beta)`` (``cos(beta)^2`` in the corrected variant).
    a1 : float
        Length ``E_iE_ji`` (elbow to a distal link's upper joint), m (30 mm).
    a2 : float
        Length of the platform-side counterpart (``H_hi`` to ``F_ji``), m (15 mm).
    p : float
        Horizontal offset ``H_hi P`` of the platform point, m (25 mm).
    modes : tuple of int
        Sign of the square root of eqs. II.5/II.6 per leg, each +1 or -1 (default elbows out).
    l2eq_variant : {"corrected", "printed"}
        Form of eq. II.1 used by :attr:`l2eq`.

    Raises
    ------
    ValidationError
        If a length ``b, d, l1, l2, a1, a2`` is not positive, ``alpha_d`` is not in (0, pi/2),
        ``beta`` not in [0, pi/2), ``l2eq_variant`` or ``modes`` is invalid, or ``l2`` is too short
        for the equivalent link ``l2eq`` to exist.
    """

    b: float = THESIS_VI1["b"]
    d: float = THESIS_VI1["d"]
    alpha_d: float = THESIS_VI1["alpha_d"]
    beta: float = THESIS_VI1["beta"]
    e: float = THESIS_VI1["e"]
    l1: float = THESIS_VI1["l1"]
    l2: float = THESIS_VI1["l2"]
    a1: float = THESIS_VI1["a1"]
    a2: float = THESIS_VI1["a2"]
    p: float = THESIS_VI1["p"]
    modes: tuple[int, int] = (-1, -1)
    l2eq_variant: str = "corrected"

    def __post_init__(self):
        for k in ("b", "d", "l1", "l2", "a1", "a2"):
            v = getattr(self, k)
            if not (np.isfinite(v) and v > 0):
                raise ValidationError(f"IRSBot2.{k}", v, "a length > 0 (m)")
        if not (0 < self.alpha_d < PI / 2):
            raise ValidationError("IRSBot2.alpha_d", self.alpha_d, "an angle in (0, pi/2) rad")
        if not (0 <= self.beta < PI / 2):
            raise ValidationError("IRSBot2.beta", self.beta, "an angle in [0, pi/2) rad")
        if self.l2eq_variant not in ("corrected", "printed"):
            raise ValidationError("IRSBot2.l2eq_variant", self.l2eq_variant, "'corrected' or 'printed'")
        if tuple(self.modes) not in ((1, 1), (1, -1), (-1, 1), (-1, -1)):
            raise ValidationError("IRSBot2.modes", self.modes, "a pair of +1/-1")
        c = np.cos(self.beta) ** 2 if self.l2eq_variant == "corrected" else np.cos(self.beta)
        if not self.l2 ** 2 - (self.a1 - self.a2) ** 2 * c > 0:
            raise ValidationError("IRSBot2.l2", self.l2, "l2 > |a1 - a2| cos(beta)")

    @classmethod
    def thesis(cls, table: str = "VI.1", **kw) -> "IRSBot2":
        """The thesis's robot of Tab. VI.1 (``beta = pi/6``) or Tab. VI.4 (``beta = pi/4``).

        Parameters
        ----------
        table : {"VI.1", "VI.4"}
            Which parameter table.
        **kw
            Fields of :class:`IRSBot2` overriding the table's values (m, rad).

        Returns
        -------
        IRSBot2
            The robot.

        Raises
        ------
        KeyError
            If ``table`` is not one of the two.
        ValidationError
            If the resulting geometry is invalid.
        """
        base = {"VI.1": THESIS_VI1, "VI.4": THESIS_VI4}[table]
        return cls(**{**base, **kw})

    @property
    def l2eq(self) -> float:
        """Length of the equivalent planar link H_b H_h, eq. II.1 (corrected: cos^2)."""
        c = np.cos(self.beta) ** 2 if self.l2eq_variant == "corrected" else np.cos(self.beta)
        return float(np.sqrt(self.l2 ** 2 - (self.a1 - self.a2) ** 2 * c))

    @property
    def base_x(self) -> float:
        """``|x|`` of the equivalent planar base points O_1, O_2 (eqs. II.3-II.4: b - a1 sin(beta) - p), m."""
        return self.b - self.a1 * math.sin(self.beta) - self.p

    # ------------------------------------------------------------------ inverse geometry
    def planar_legs(self, x, z) -> dict[str, np.ndarray]:
        """The equivalent planar mechanism (Sec. II.2.1, Fig. II.3) at platform points (x, z) (arrays, m),
        without raising where a point is out of reach -- for sampling a workspace.

        Leg i is a planar 2R chain from ``O_i = (-+base_x, -e)`` with proximal length l1 and distal
        length l2eq to P. Returns ``reachable`` (eqs. II.5-II.6: A_i² + B_i² >= C_i²), elbow points
        ``E1``, ``E2`` (..., 2) of the elbows-out working mode (``modes=(-1, -1)``), ``q1``, ``q2``
        (actuated angles, x = ... + l1 cos q, z = ... - l1 sin q), ``psi1``, ``psi2`` (eqs. II.7-II.8),
        ``sin_t2`` = sin(psi_1 - psi_2) (Type 2 measure, det A of eq. II.38 / (2 l2eq)²) and
        ``sin_t1_1``, ``sin_t1_2`` = sin(q_i - psi_i) (Type 1 measures, eq. II.37).

        Parameters
        ----------
        x, z : array_like
            Platform point coordinates, m, broadcastable together.

        Returns
        -------
        dict of str to ndarray
            ``"reachable"``: bool, the shape of ``x``; ``"E1"``, ``"E2"``: (..., 2) elbow points
            ``(x, z)``, m; ``"q1"``, ``"q2"``, ``"psi1"``, ``"psi2"``: rad; ``"sin_t2"``,
            ``"sin_t1_1"``, ``"sin_t1_2"``: dimensionless. Entries at unreachable points are
            meaningless (the elbow is put on the line ``O_i P``).

        Raises
        ------
        ValidationError
            If ``modes`` is not ``(-1, -1)``.
        """
        if tuple(self.modes) != (-1, -1):
            raise ValidationError("IRSBot2.modes", self.modes, "(-1, -1) (elbows out) for planar_legs")
        x, z = np.broadcast_arrays(np.asarray(x, float), np.asarray(z, float))
        L1, L2 = self.l1, self.l2eq
        out = {"reachable": np.ones(x.shape, bool)}
        for i, (ox, side) in enumerate(((-self.base_x, 1.0), (self.base_x, -1.0)), start=1):
            dx, dz = x - ox, z + self.e
            d2 = dx * dx + dz * dz
            d = np.sqrt(d2)
            # elbow on circle(O_i, L1) ∩ circle(P, L2): foot along O->P, offset perpendicular
            a = (d2 + L1 * L1 - L2 * L2) / (2 * np.where(d > 0, d, 1.0))
            h2 = L1 * L1 - a * a
            ok = (h2 >= 0) & (d > 0)
            h = np.sqrt(np.where(ok, h2, 0.0))
            ux, uz = dx / np.where(d > 0, d, 1.0), dz / np.where(d > 0, d, 1.0)
            # elbows outward: leg 1's elbow on the right-hand normal of O_1 -> P (to the left
            # when P is straight below), leg 2's on the left-hand normal (mirror image)
            nx, nz = side * uz, -side * ux
            ex, ez = ox + a * ux + h * nx, -self.e + a * uz + h * nz
            out[f"E{i}"] = np.stack([ex, ez], -1)
            out[f"q{i}"] = np.arctan2(-(ez + self.e), ex - ox)
            out[f"psi{i}"] = np.arctan2(-(z - ez), x - ex)
            out[f"sin_t1_{i}"] = np.sin(out[f"q{i}"] - out[f"psi{i}"])
            out["reachable"] &= ok
        out["sin_t2"] = np.sin(out["psi1"] - out["psi2"])
        return out

    def inverse_geometry(self, poses) -> dict[str, np.ndarray]:
        """Actuated angles q1, q2 (II.5-II.6), psi1, psi2 (II.7-II.8) and the universal-joint
        angles of the four distal chains (II.18-II.35), for poses (n, 2) = (x, z) in metres.

        Parameters
        ----------
        poses : array_like, shape (n, 2) or (2,)
            Platform points ``(x, z)``, m.

        Returns
        -------
        dict of str to ndarray, each shape (n,)
            ``"q1"``, ``"q2"``, ``"psi1"``, ``"psi2"`` and ``"th{j}{i}_{k}"`` (``j, i`` in 1, 2;
            ``k`` = 7 ... 10), rad.

        Raises
        ------
        ValidationError
            If ``poses`` is not an (n, 2) array.
        KinematicsError
            If a leg or a distal chain cannot reach a pose.
        """
        P = np.atleast_2d(np.asarray(poses, float))
        if P.ndim != 2 or P.shape[1] != 2:
            raise ValidationError("poses shape", P.shape, "(n, 2): x, z in metres")
        x, z = P[:, 0], P[:, 1]
        sb, cb = np.sin(self.beta), np.cos(self.beta)
        L = self.l2eq
        out = {}
        for leg, sgn in ((1, -1.0), (2, 1.0)):
            # W = H_b - A (planar), the loop |W - l1 (cos q, -sin q)| = l2eq, eqs. II.3-II.6
            wx = x - sgn * self.b + sgn * (self.p + self.a1 * sb)
            wz = z + self.e
            A = -2 * self.l1 * wx
            B = 2 * self.l1 * wz
            C = wx ** 2 + wz ** 2 + self.l1 ** 2 - L ** 2
            disc = B ** 2 + A ** 2 - C ** 2
            bad = disc < 0
            if bad.any():
                raise KinematicsError(f"IRSBot-2 leg {leg} cannot reach pose {P[bad][0].tolist()} (x, z in m)", poses=P[bad])
            root = self.modes[leg - 1] * sgn * np.sqrt(disc)
            q = 2 * np.arctan2(-B + root, C - A)
            # psi from eq. II.7 (leg 1) / its leg-2 counterpart (eq. II.8 corrected)
            psi = np.arctan2(-wz - self.l1 * np.sin(q), wx - self.l1 * np.cos(q))
            out[f"q{leg}"], out[f"psi{leg}"] = q, psi
        # distal module: universal joints (II.18-II.35)
        ca, sa = np.cos(self.alpha_d), np.sin(self.alpha_d)
        for i in (1, 2):
            psi = out[f"psi{i}"]
            for j, ysign in ((1, -1.0), (2, 1.0)):
                # F_ji relative to H_bi (eq. II.17 and its mirrors)
                xs = 1.0 if i == 1 else -1.0
                xF = xs * L * np.cos(psi)
                yF = ysign * self.a2 * cb
                zF = -L * np.sin(psi)
                s8 = xs * (ca * zF + sa * xF) / self.l2
                if np.any(np.abs(s8) > 1):
                    bad = np.abs(s8) > 1
                    raise KinematicsError(f"IRSBot-2 distal chain {j}{i} cannot reach pose {P[bad][0].tolist()}", poses=P[bad])
                th8 = np.arcsin(s8)
                # chain 11: (a1 cb + yF); 21: (-a1 cb + yF); 12: (-a1 cb - yF); 22: (a1 cb - yF)
                num = {(1, 1): self.a1 * cb + yF, (2, 1): -self.a1 * cb + yF,
                       (1, 2): -self.a1 * cb - yF, (2, 2): self.a1 * cb - yF}[(j, i)]
                s7 = num / (self.l2 * np.cos(th8))
                if np.any(np.abs(s7) > 1):
                    bad = np.abs(s7) > 1
                    raise KinematicsError(f"IRSBot-2 distal chain {j}{i} cannot reach pose {P[bad][0].tolist()}", poses=P[bad])
                th7 = np.arcsin(s7)
                out[f"th{j}{i}_7"], out[f"th{j}{i}_8"] = th7, th8
                out[f"th{j}{i}_9"], out[f"th{j}{i}_10"] = -th8, -th7       # II.22-II.23 etc.
        return out

    def dh_values(self, poses, variant: str = "corrected") -> dict[str, np.ndarray]:
        """Values of the variables of Tabs. II.1-II.2 at the poses.

        The parallelogram angles follow the tables (``theta1 = -(pi - q1)`` ...). The four
        universal joints are solved from the geometry on the DH tree itself: the world points
        ``E_ji`` (origins of frames 7, 12, 23, 28) and ``F_ji = H_hi +- (0, a2 cos(beta), 0)`` give
        the direction ``u`` of link ``E_jiF_ji`` in frame 7's pre-rotation, hence ``theta_7 =
        atan2(u_y, u_x)``, ``theta_8 = asin(u_z / sin(alpha_8))``; then ``theta_9 = -theta_8`` and
        ``theta_10 = -(theta_7 - o)`` with ``o`` the table's offset of ``theta_7`` (``+pi/2`` for
        frames 7 and 28, ``-pi/2`` for 12 and 23): eqs. II.22-II.23 in the thesis's angles.
        ``variant="thesis"`` returns eqs. II.18-II.35 instead; they agree in the default
        (elbows-out) mode and flip the sign of ``theta_7`` in the elbows-in mode (arcsin branch).

        Parameters
        ----------
        poses : array_like, shape (n, 2) or (2,)
            Platform points ``(x, z)``, m.
        variant : {"corrected", "thesis"}
            ``"corrected"`` (default): solved on the corrected DH tree; ``"thesis"``: the
            universal-joint angles of eqs. II.18-II.35.

        Returns
        -------
        dict of str to ndarray, each shape (n,)
            Values of the joint variables (``"t1"``, ``"g3"``, ... as named in :meth:`dh_tree`), rad.

        Raises
        ------
        ValidationError
            If ``poses`` is not an (n, 2) array, or ``variant`` is neither ``"corrected"`` nor
            ``"thesis"``.
        KinematicsError
            If a pose is out of reach, or a distal link of the DH tree does not have length ``l2``
            (``l2eq`` inconsistent with the tree, e.g. ``l2eq_variant="printed"``).
        """
        from robots.clearance.kinematics import rot_x, rot_z, trans

        if variant not in ("corrected", "thesis"):
            raise ValidationError("dh_values variant", variant, "'corrected' or 'thesis'")
        g = self.inverse_geometry(poses)
        q1, q2 = g["q1"], g["q2"]
        v = {"t1": -(PI - q1), "t2": -q1, "g3": PI - q1, "t3": -(PI - q1), "t4": -q1,
             "t17": q2, "t18": PI - q2, "g19": -q2, "t19": q2, "t20": PI - q2}
        if variant == "thesis":
            v.update({"t7": g["th11_7"] + PI / 2, "t8": g["th11_8"], "t9": g["th11_9"], "t10": g["th11_10"],
                      "t12": g["th21_7"] - PI / 2, "t13": g["th21_8"], "t14": g["th21_9"], "t15": g["th21_10"],
                      "t23": g["th12_7"] - PI / 2, "t24": g["th12_8"], "t25": g["th12_9"], "t26": g["th12_10"],
                      "t28": g["th22_7"] + PI / 2, "t29": g["th22_8"], "t30": g["th22_9"], "t31": g["th22_10"]})
            return v
        P = np.atleast_2d(np.asarray(poses, float))
        n = len(P)
        tree = self.dh_tree()
        W = tree.world_transforms({**v, **{k: np.zeros(n) for k in tree.variables() if k not in v}}, n)
        cb = np.cos(self.beta)
        Pw = np.stack([P[:, 0], np.zeros(n), P[:, 1]], 1)
        for f7, f8, f9, f10, hx, fy, off in (("7", "8", "9", "10", -self.p, -1, PI / 2), ("12", "13", "14", "15", -self.p, 1, -PI / 2),
                                             ("23", "24", "25", "26", self.p, -1, -PI / 2), ("28", "29", "30", "31", self.p, 1, PI / 2)):
            fr = tree.frames[f7]
            Tpre = W[fr.antecedent] @ rot_z(fr.gamma) @ trans(z=fr.b) @ rot_x(fr.alpha) @ trans(x=fr.d)
            O7 = (Tpre @ np.array([0.0, 0.0, fr.r, 1.0]))[:, :3]
            F = Pw + np.array([hx, fy * self.a2 * cb, 0.0])
            u = np.einsum("nji,nj->ni", Tpre[:, :3, :3], F - O7) / self.l2
            s8 = u[:, 2] / np.sin(tree.frames[f8].alpha)
            if np.any(np.abs(np.linalg.norm(u, axis=1) - 1) > 1e-9) or np.any(np.abs(s8) > 1):
                bad = np.abs(np.linalg.norm(u, axis=1) - 1) > 1e-9
                raise KinematicsError(f"IRSBot-2 distal link {f7}: |E F| != l2 at pose {P[bad][0].tolist() if bad.any() else P[0].tolist()}"
                                      " (l2eq inconsistent with the geometry?)", poses=P)
            t8 = np.arcsin(s8)
            t7 = np.arctan2(u[:, 1], u[:, 0])
            v.update({"t" + f7: t7, "t" + f8: t8, "t" + f9: -t8, "t" + f10: -(t7 - off)})
        return v

    def dh_tree(self, variant: str = "corrected") -> DHTree:
        """Modified DH tables II.1 (frames 1-16) and II.2 (frames 17-32).

        ``variant="printed"``: as printed. ``"corrected"`` (default): row 28 has
        ``alpha = -alpha_d`` -- the printed ``+alpha_d`` puts ``E_22`` at ``+a1 sin(beta)`` instead
        of ``-a1 sin(beta)`` from the elbow and tilts its axis the wrong way, so chain ``E_22F_22``
        misses the platform (by 79 mm at the centre of the map); every other row closes its loop
        (checked by :meth:`loop_residual`).

        Parameters
        ----------
        variant : {"corrected", "printed"}
            Which form of row 28.

        Returns
        -------
        DHTree
            The 32 frames, lengths in m, angles in rad.

        Raises
        ------
        ValidationError
            If ``variant`` is neither ``"corrected"`` nor ``"printed"``.
        """
        if variant not in ("corrected", "printed"):
            raise ValidationError("dh_tree variant", variant, "'corrected' or 'printed'")
        ad, sb, cb = self.alpha_d, np.sin(self.beta), np.cos(self.beta)
        a1, a2, p, l1, l2, d, b, e = self.a1, self.a2, self.p, self.l1, self.l2, self.d, self.b, self.e
        bb = -a1 * sb / np.tan(ad)
        rr = a1 * sb / np.sin(ad)
        bp, rp = p / np.sin(ad), -p / np.tan(ad)
        F = DHFrame
        rows = [
            F("1", "0", 0, 1, PI, 0, PI / 2, b, "t1", 0),
            F("2", "1", 0, 0, 0, 0, 0, l1, "t2", 0),
            F("3", "1", 0, 0, "g3", 0, 0, d, "t3", 0),
            F("4", "3", 0, 0, 0, 0, 0, l1, "t4", 0),
            F("5", "4", 2, 0, 0, 0, 0, d, 0, 0),
            F("6", "2", 2, 0, 0, 0, PI / 2, 0, 0, -e),
            F("7", "6", 0, 0, -PI / 2, bb, -ad, a1 * cb, "t7", rr),
            F("8", "7", 0, 0, 0, 0, PI / 2, 0, "t8", 0),
            F("9", "8", 0, 0, 0, 0, 0, l2, "t9", 0),
            F("10", "9", 0, 0, 0, 0, -PI / 2, 0, "t10", 0),
            F("11", "10", 2, 0, PI / 2, bp, -ad, a2 * cb, -PI / 2, rp),
            F("12", "6", 0, 0, PI / 2, bb, ad, a1 * cb, "t12", rr),
            F("13", "12", 0, 0, 0, 0, PI / 2, 0, "t13", 0),
            F("14", "13", 0, 0, 0, 0, 0, l2, "t14", 0),
            F("15", "14", 0, 0, 0, 0, -PI / 2, 0, "t15", 0),
            F("16", "15", 2, 0, -PI / 2, bp, ad, a2 * cb, PI / 2, rp),
            F("17", "0", 0, 1, 0, 0, -PI / 2, b, "t17", 0),
            F("18", "17", 0, 0, 0, 0, 0, l1, "t18", 0),
            F("19", "17", 0, 0, "g19", 0, 0, d, "t19", 0),
            F("20", "19", 0, 0, 0, 0, 0, l1, "t20", 0),
            F("21", "20", 2, 0, 0, 0, 0, d, 0, 0),
            F("22", "18", 2, 0, 0, 0, -PI / 2, 0, PI, -e),
            F("23", "22", 0, 0, -PI / 2, bb, ad, a1 * cb, "t23", rr),
            F("24", "23", 0, 0, 0, 0, -PI / 2, 0, "t24", 0),
            F("25", "24", 0, 0, 0, 0, 0, l2, "t25", 0),
            F("26", "25", 0, 0, 0, 0, PI / 2, 0, "t26", 0),
            F("27", "26", 2, 0, -PI / 2, bp, ad, a2 * cb, -PI / 2, rp),
            F("28", "22", 0, 0, PI / 2, bb, ad, a1 * cb, "t28", rr),
            F("29", "28", 0, 0, 0, 0, -PI / 2, 0, "t29", 0),
            F("30", "29", 0, 0, 0, 0, 0, l2, "t30", 0),
            F("31", "30", 0, 0, 0, 0, PI / 2, 0, "t31", 0),
            F("32", "31", 2, 0, PI / 2, bp, -ad, a2 * cb, PI / 2, rp),
        ]
        if variant == "corrected":
            from dataclasses import replace
            rows = [replace(r, alpha=-ad) if r.name == "28" else r for r in rows]
        return DHTree(rows)

    # ------------------------------------------------------------------ checks and singularities
    def loop_residual(self, poses, variant: str = "corrected") -> dict[str, float]:
        """Largest closure error of every loop on the DH tree (m for positions, rad for
        orientations): parallelograms (frame 5 vs 2, 21 vs 18) and the four distal chains
        (frames 11, 16, 27, 32 vs the platform frame at ``P``, parallel to the base).

        Parameters
        ----------
        poses : array_like, shape (n, 2) or (2,)
            Platform points ``(x, z)``, m.
        variant : {"corrected", "printed"}
            DH tree evaluated (the joint values are always those of :meth:`dh_values` on the corrected tree).

        Returns
        -------
        dict of str to float
            ``"parallelogram"`` (largest entry difference of the transforms, m or dimensionless) and
            ``"platform_{f}_position"`` (m), ``"platform_{f}_rotation"`` (rad) for frames
            ``f`` = 11, 16, 27, 32; maxima over the poses.

        Raises
        ------
        ValidationError
            As :meth:`inverse_geometry`, or if ``variant`` is unknown (as :meth:`dh_tree`).
        KinematicsError
            As :meth:`inverse_geometry`.
        """
        from robots.clearance.kinematics import rotation_vector

        P = np.atleast_2d(np.asarray(poses, float))
        tree = self.dh_tree(variant)
        vals = self.dh_values(P)
        W = tree.world_transforms(vals, len(P))
        Pw = np.stack([P[:, 0], np.zeros(len(P)), P[:, 1]], 1)
        out = {"parallelogram": float(max(np.abs(W["5"] - W["2"]).max(), np.abs(W["21"] - W["18"]).max()))}
        for f in ("11", "16", "27", "32"):
            out[f"platform_{f}_position"] = float(np.linalg.norm(W[f][:, :3, 3] - Pw, axis=1).max())
            out[f"platform_{f}_rotation"] = float(np.linalg.norm(rotation_vector(W[f][:, :3, :3]), axis=1).max())
        return out

    def parallel_singularity(self, poses) -> np.ndarray:
        """Type-2 singularity measure ``sin(psi_1 - psi_2)`` (0 when the equivalent distal links
        are parallel, eq. II.38 / Fig. II.9).

        Parameters
        ----------
        poses : array_like, shape (n, 2) or (2,)
            Platform points ``(x, z)``, m.

        Returns
        -------
        ndarray, shape (n,)
            ``sin(psi_1 - psi_2)``, dimensionless.

        Raises
        ------
        ValidationError, KinematicsError
            As :meth:`inverse_geometry`.
        """
        g = self.inverse_geometry(poses)
        return np.sin(g["psi1"] - g["psi2"])

    def serial_singularity(self, poses) -> np.ndarray:
        """Type-1 measure ``min_i |sin(q_i - psi_i)|`` (0 at the workspace boundary, eq. II.37).

        Parameters
        ----------
        poses : array_like, shape (n, 2) or (2,)
            Platform points ``(x, z)``, m.

        Returns
        -------
        ndarray, shape (n,)
            Type-1 measure, dimensionless, in [0, 1].

        Raises
        ------
        ValidationError, KinematicsError
            As :meth:`inverse_geometry`.
        """
        g = self.inverse_geometry(poses)
        return np.minimum(np.abs(np.sin(g["q1"] - g["psi1"])), np.abs(np.sin(g["q2"] - g["psi2"])))

    def reachable(self, poses) -> np.ndarray:
        """Boolean mask of the poses the inverse geometry can solve (no exception).

        Only the proximal condition of eqs. II.5-II.6 is tested, not the distal chains.

        Parameters
        ----------
        poses : array_like, shape (n, 2) or (2,)
            Platform points ``(x, z)``, m.

        Returns
        -------
        ndarray of bool, shape (n,)
            True where both legs reach.
        """
        P = np.atleast_2d(np.asarray(poses, float))
        ok = np.ones(len(P), bool)
        x, z = P[:, 0], P[:, 1]
        sb = np.sin(self.beta)
        for sgn in (-1.0, 1.0):
            wx = x - sgn * self.b + sgn * (self.p + self.a1 * sb)
            wz = z + self.e
            A, B = -2 * self.l1 * wx, 2 * self.l1 * wz
            C = wx ** 2 + wz ** 2 + self.l1 ** 2 - self.l2eq ** 2
            ok &= B ** 2 + A ** 2 - C ** 2 >= 0
        return ok

    # ------------------------------------------------------------------ clearance model
    def clearance_mechanism(self, *, parallelograms: bool = False, distal: ClearanceBounds | None = None,
                            actuated: ClearanceBounds | None = None, passive: ClearanceBounds | None = None) -> ClearanceMechanism:
        """The IRSBot-2 with joint clearances (Ch. V-VI).

        parallelograms=False: clearances in the distal module only (Sec. VI.1): four serial chains
        of four revolute joints from the (rigid) elbows to the platform, 16 joints, 96 screw
        variables, 18 loop equations -> the thesis's 78 variables. parallelograms=True (Sec. VI.2):
        the elbows become sub-end-effectors of the two parallelogram sub-robots (chains ``A_i-B_i``
        and ``D_i-C_i``), 24 joints -> 114 variables (eq. VI.38).

        Defaults: distal joints Tab. VI.3 (beta_xy 0.01 rad, beta_z 0.2 rad, 0.1 mm, 0.1 mm);
        parallelograms Tabs. VI.7-VI.9: actuated ``A_i`` beta_z = 0.001 rad, passive ``B_i, C_i, D_i``
        beta_z = 0.2 rad (the captions of Tabs. VI.8 and VI.9 are swapped in the thesis: the
        table indexed ``p,12,1`` -- leg 2's actuated joint -- has 0.001 rad).

        Parameters
        ----------
        parallelograms : bool
            Also model the clearances of the two parallelograms (Sec. VI.2).
        distal : ClearanceBounds or None
            Bounds of the 16 distal joints; None: Tab. VI.3 (0.01 rad, 0.2 rad, 0.1 mm, 0.1 mm).
        actuated : ClearanceBounds or None
            Bounds of the actuated joints ``A_i`` (with ``parallelograms``); None: 0.01 rad,
            0.001 rad, 0.1 mm, 0.1 mm.
        passive : ClearanceBounds or None
            Bounds of the passive parallelogram joints ``B_i, C_i, D_i``; None: as ``distal``.

        Returns
        -------
        ClearanceMechanism
            Spatial mechanism with end-effector ``P`` and pose names ``("x", "z")``.
        """
        distal = distal or ClearanceBounds(0.01, 0.2, 0.1 * MM, 0.1 * MM)
        actuated = actuated or ClearanceBounds(0.01, 0.001, 0.1 * MM, 0.1 * MM)
        passive = passive or ClearanceBounds(0.01, 0.2, 0.1 * MM, 0.1 * MM)
        joints, chains = [], []
        distal_frames = {("1", 1): ("7", "8", "9", "10", "11"), ("2", 1): ("12", "13", "14", "15", "16"),
                         ("1", 2): ("23", "24", "25", "26", "27"), ("2", 2): ("28", "29", "30", "31", "32")}
        bodies = {"P": "11"}
        for i in (1, 2):
            elbow = f"E{i}"
            if parallelograms:
                A, B_, D, C = (("1", "2", "3", "4") if i == 1 else ("17", "18", "19", "20"))
                cut = "5" if i == 1 else "21"
                joints += [Joint(f"A{i}", A, True, actuated), Joint(f"B{i}", B_, False, passive),
                           Joint(f"D{i}", D, False, passive), Joint(f"C{i}", C, False, passive)]
                bodies[elbow] = "6" if i == 1 else "22"
                chains += [Chain(f"p1{i}", "base", elbow, (f"A{i}", f"B{i}")),
                           Chain(f"p2{i}", "base", elbow, (f"D{i}", f"C{i}"), path_end=cut)]
            for j in ("1", "2"):
                f7, f8, f9, f10, fp = distal_frames[(j, i)]
                names = (f"E{j}{i}-{f7}", f"E{j}{i}-{f8}", f"F{j}{i}-{f9}", f"F{j}{i}-{f10}")
                joints += [Joint(nm, fr, False, distal) for nm, fr in zip(names, (f7, f8, f9, f10))]
                chains.append(Chain(f"d{j}{i}", elbow if parallelograms else "base", "P", names, path_end=fp))
        return ClearanceMechanism(name="IRSBot-2" + (" (distal + parallelograms)" if parallelograms else " (distal module)"),
                                  tree=self.dh_tree(), joints=joints, bodies=bodies, chains=chains, end_effector="P",
                                  joint_values=self.dh_values, planar=False, pose_names=("x", "z"))


def mirror_joint_map(mech: ClearanceMechanism) -> list[int]:
    """Joint ``k`` -> its mirror image under x -> -x: leg 1 <-> leg 2. :meth:`IRSBot2.clearance_mechanism`
    lists leg 2's joints in the same order as leg 1's, so the map swaps the two halves of the list;
    :func:`robots.clearance.symmetry.prove_mirror` proves (per pose pair) that it is a symmetry.

    Parameters
    ----------
    mech : ClearanceMechanism
        A mechanism from :meth:`IRSBot2.clearance_mechanism`.

    Returns
    -------
    list of int
        Index of the mirror joint of each joint.
    """
    n = len(mech.joints)
    return [(k + n // 2) % n for k in range(n)]


#: the Cartesian square of the error maps (Figs. VI.1/VI.3). The thesis's text does not give its
#: range; this square is centred on the z axis, inside the workspace of Tabs. VI.1-VI.2 and, like
#: the thesis's (Fig. VI.2), crossed by the parallel singularity.
MAP_WORKSPACE = Workspace(names=("x", "z"), low=(-30 * MM, -70 * MM), high=(30 * MM, -10 * MM), units=("m", "m"),
                          display_units=("mm", "mm"), display_scale=(1e3, 1e3))


# --------------------------------------------------------------------------- sub-workspaces
@dataclass(frozen=True)
class SubWorkspace:
    """A singularity-free rectangle of the x-z plane (SI units) and its Fig. VII.10 points.

    Parameters
    ----------
    area : float
        Area of the rectangle, m².
    x : tuple of float
        ``(x_min, x_max)``, m.
    z : tuple of float
        ``(z_min, z_max)``, m.
    step : float
        Grid step of the search, m.
    n_kept : int
        Number of grid points satisfying the criteria.
    """

    area: float                 # m²
    x: tuple[float, float]      # (x_min, x_max), m
    z: tuple[float, float]      # (z_min, z_max), m
    step: float                 # grid step, m
    n_kept: int                 # kept grid points

    @property
    def points(self) -> np.ndarray:
        """Right-down corner, centre and left-up corner (Fig. VII.10), shape (3, 2) [x, z] in m."""
        (x0, x1), (z0, z1) = self.x, self.z
        return np.array([[x1, z0], [(x0 + x1) / 2, (z0 + z1) / 2], [x0, z1]])


def singularity_free_rectangle(robot: IRSBot2, *, n: int = 161, margin_deg: float = 2.0,
                               below_elbows: bool = False) -> SubWorkspace:
    """Largest rectangle of the x-z plane below the base (z < -e) in which the robot is assembled in
    its working mode, on the V side of the Type 2 singularity (sin(psi_1 - psi_2) < 0) and at least
    ``margin_deg`` away from both singularity types, by discretising the reachable region with
    n x n points -- the "cuboid-shaped sub-workspace" of Deng 2012 Sec. VII.2.1 ([BPC10]).
    ``below_elbows``: also require the platform below both elbows (a stricter variant).

    Parameters
    ----------
    robot : IRSBot2
        The robot, in the elbows-out mode ``(-1, -1)``.
    n : int
        Grid points per axis.
    margin_deg : float
        Minimum distance to both singularity types, deg (as the sine of the angles).
    below_elbows : bool
        Also require the platform below both elbows.

    Returns
    -------
    SubWorkspace
        The rectangle (area 0 and zero ranges if no grid point qualifies).

    Raises
    ------
    ValidationError
        If ``robot.modes`` is not ``(-1, -1)`` (from :meth:`IRSBot2.planar_legs`).
    """
    reach = robot.base_x + robot.l1 + robot.l2eq
    depth = robot.l1 + robot.l2eq
    xs = np.linspace(-reach, reach, n)
    zs = np.linspace(-depth - robot.e, -robot.e, n)
    step = max(xs[1] - xs[0], zs[1] - zs[0])
    X, Z = np.meshgrid(xs, zs)                                   # rows: z, columns: x
    g = robot.planar_legs(X, Z)
    s = math.sin(math.radians(margin_deg))
    keep = (g["reachable"] & (g["sin_t2"] <= -s) & (np.abs(g["sin_t1_1"]) >= s) & (np.abs(g["sin_t1_2"]) >= s)
            & (Z < -robot.e))
    if below_elbows:
        keep &= (np.sin(g["psi1"]) > 0) & (np.sin(g["psi2"]) > 0)
    area, r0, r1, c0, c1 = largest_rectangle(keep)
    if c1 < c0 or area == 0:
        return SubWorkspace(0.0, (0.0, 0.0), (0.0, 0.0), float(step), int(keep.sum()))
    dx, dz = xs[1] - xs[0], zs[1] - zs[0]
    return SubWorkspace(float(area * dx * dz), (float(xs[c0]), float(xs[c1])), (float(zs[r0]), float(zs[r1])),
                        float(step), int(keep.sum()))


def centred_singularity_free_rectangle(robot: IRSBot2, margin: float = 0.2, step: float = 1e-3, x_max: float = 0.2,
                                       z_range=(-0.3, 0.0)) -> dict[str, float]:
    """Largest rectangle ``[-w, w] x [z_low, z_high]`` (m) symmetric about x = 0 inside the reachable
    workspace with ``|sin(psi1 - psi2)| >= margin`` and ``min_i |sin(q_i - psi_i)| >= margin``, on a
    grid of ``step`` (the rectangle of Deng 2012 Figs. VI.4-VI.5, whose criterion the thesis does
    not state). Returns ``half_width``, ``z_low``, ``z_high`` and ``area`` (m, m²).

    Parameters
    ----------
    robot : IRSBot2
        The robot.
    margin : float
        Minimum of both singularity measures, dimensionless (a sine).
    step : float
        Grid step, m.
    x_max : float
        Largest half-width searched, m.
    z_range : tuple of float
        ``(z_min, z_max)`` searched, m.

    Returns
    -------
    dict of str to float
        ``"half_width"``, ``"z_low"``, ``"z_high"`` (m) and ``"area"`` (m²).

    Raises
    ------
    KinematicsError
        If no rectangle about ``x = 0`` satisfies the margins (or a reachable point fails a
        distal chain).
    """
    xs = np.arange(0.0, x_max + step / 2, step)
    zs = np.arange(z_range[0], z_range[1] + step / 2, step)
    X, Z = np.meshgrid(np.concatenate([-xs[:0:-1], xs]), zs)
    pts = np.stack([X.ravel(), Z.ravel()], 1)
    ok = robot.reachable(pts)
    good = np.zeros(len(pts), bool)
    if ok.any():
        q = pts[ok]
        good[np.nonzero(ok)[0]] = (np.abs(robot.parallel_singularity(q)) >= margin) & (robot.serial_singularity(q) >= margin)
    area, r0, r1, half = largest_centred_rectangle(good.reshape(X.shape), len(xs) - 1)
    if area == 0:
        raise KinematicsError(f"no rectangle about x = 0 with singularity margin {margin} in x <= {x_max} m, "
                              f"z in {tuple(z_range)} m", poses=pts[:0])
    return {"half_width": half * step, "z_low": zs[r0], "z_high": zs[r1], "area": (2 * half * step) * ((r1 - r0) * step)}
