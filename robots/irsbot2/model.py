"""The IRSBot-2 robot (Deng 2012, Ch. II): geometry, inverse geometry (eqs. II.1-II.35), singularity
measures (eqs. II.37-II.38) and reachability; the DH tables come from
:class:`evotol.robots.irsbot2.dh_tables.IRSBot2DHTables`, the clearance model from
:class:`evotol.robots.irsbot2.clearance.IRSBot2Clearances`.

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
from evotol.robots.irsbot2.clearance import IRSBot2Clearances
from evotol.robots.irsbot2.dh_tables import IRSBot2DHTables
from evotol.robots.irsbot2.parameters import PI, THESIS_VI1, THESIS_VI4


@dataclass(frozen=True)
class IRSBot2(IRSBot2DHTables, IRSBot2Clearances):
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

    Notes
    -----
    The DH tables (``dh_tree``, ``dh_values``, ``loop_residual``) come from
    :class:`~evotol.robots.irsbot2.dh_tables.IRSBot2DHTables`, the clearance model
    (``clearance_mechanism``) from :class:`~evotol.robots.irsbot2.clearance.IRSBot2Clearances`.
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

    # ------------------------------------------------------------------ singularities and reach
    def parallel_singularity(self, poses) -> np.ndarray:
        """Type-2 singularity measure ``sin(psi_1 - psi_2)`` (0 when the equivalent distal links
        are parallel, eq. II.38 / Fig. II.9).

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
