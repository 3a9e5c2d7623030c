"""The IRSBot-2's modified DH tables II.1-II.2 (Deng 2012, Ch. II): the tree, the values of its
joint variables at a pose, and the closure check of every loop on it.

:class:`IRSBot2DHTables` is a mixin of :class:`evotol.robots.irsbot2.model.IRSBot2`: it reads the
robot's dimensions (``alpha_d, beta, a1, a2, p, l1, l2, d, b, e``) and its
:meth:`~evotol.robots.irsbot2.model.IRSBot2.inverse_geometry`.

Correction to the printed tables (checked by closing all loops in
:meth:`IRSBot2DHTables.loop_residual`): row 28 has ``alpha = -alpha_d`` (see :meth:`IRSBot2DHTables.dh_tree`).

Units: metres and radians; poses are ``(x, z)`` in metres.
"""
from __future__ import annotations

import numpy as np

from evotol.errors import KinematicsError, ValidationError
from evotol.robots.clearance.kinematics import DHFrame, DHTree
from evotol.robots.irsbot2.parameters import PI


class IRSBot2DHTables:
    """Modified DH tables II.1-II.2 of the IRSBot-2 and their loop closure (mixin of
    :class:`evotol.robots.irsbot2.model.IRSBot2`, which supplies the dimensions and the inverse geometry).
    """

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
        from evotol.robots.clearance.kinematics import rot_x, rot_z, trans

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

    def loop_residual(self, poses, variant: str = "corrected") -> dict[str, float]:
        """Largest closure error of every loop on the DH tree (m for positions, rad for
        orientations): parallelograms (frame 5 vs 2, 21 vs 18) and the four distal chains
        (frames 11, 16, 27, 32 vs the platform frame at ``P``, parallel to the base).

        Parameters
        ----------
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
        from evotol.robots.clearance.kinematics import rotation_vector

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
