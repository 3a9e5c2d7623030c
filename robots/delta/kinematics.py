"""Nominal kinematics of the Delta robot (Brahmia et al. 2023, eqs. 3 and 11): the closed-form inverse
kinematics (joint variables ``Q_k``) and the closed-form forward kinematics of the error-free robot
(intersection of three spheres), an independent check of the former.

:class:`DeltaNominalKinematics` is a mixin of :class:`evotol.robots.delta.model.DeltaRobot`, which
supplies the nominal ``geometry`` and ``check_poses``. Units: metres and radians.
"""
from __future__ import annotations

import numpy as np

from evotol.errors import KinematicsError


class DeltaNominalKinematics:
    """Nominal inverse and forward kinematics (mixin of :class:`evotol.robots.delta.model.DeltaRobot`)."""

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
