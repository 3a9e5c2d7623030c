"""The Delta robot's legs as Khalil-Kleinfinger trees (Brahmia et al. 2023, Sec. 2, eqs. 1-2, 4, 6,
Tables 1-2): the branch end points of every leg with errors, the leg end points, and the paper's
open-chain points (eqs. 6-10).

* three legs ``i = 1, 2, 3`` at ``theta_i = 2 pi (i - 1) / 3`` about the base axis ``z0``;
* each leg is an actuated revolute (``q1``, axis tangent to the base circle of radius ``Ra``),
  an upper arm ``La``, and a parallelogram of two rods ``Lb`` whose bars have half-width ``d``;
  the platform centre ``P`` is at ``Rb`` from the lower bar's centre;
* each leg is written as a Khalil–Kleinfinger (KK) tree (Table 1 / Table 2): frame ``j`` with
  antecedent ``a(j)`` is ``Rot(z, gamma_j) Trans(z, b_j) Rot(x, alpha_j) Trans(x, d_j)
  Rot(z, q_j) Trans(z, r_j)`` (eq. 4). Branch 1 (rod 1) is ``A-1-2-3-4-5-E`` (eq. 1), branch 2
  (rod 2) is ``A-1-2-6-7-5-E`` (eq. 2);
* ``z0`` points from the base towards the platform (the paper's postures have ``z > 0``).

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

:class:`DeltaChains` is a mixin of :class:`evotol.robots.delta.model.DeltaRobot`, which supplies the
nominal ``geometry`` and the inverse kinematics. Units: metres and radians.
"""
from __future__ import annotations

import numpy as np

from evotol.robots.delta.parameters import _INDEX, _LEG_COL


# --- elementary KK operations on points (components kept apart for broadcasting) -----------------
def _rot_z(c, s, p):
    x, y, z = p
    return (c * x - s * y, s * x + c * y, z)


def _rot_x(c, s, p):
    x, y, z = p
    return (x, c * y - s * z, s * y + c * z)


def _kk_cs(p, cs_alpha, dx, cs_q, r, b=None):
    """Apply Rot(x, alpha) Trans(x, dx) Rot(z, q) Trans(z, r) (eq. 4), preceded by Trans(z, b),
    given ``cs_alpha = (cos alpha, sin alpha)`` and ``cs_q``: the two branches of a leg share most
    angles, so their cosines and sines are computed once per chain (issue 43)."""
    x, y, z = _rot_z(cs_q[0], cs_q[1], (p[0], p[1], p[2] + r))
    x, y, z = _rot_x(cs_alpha[0], cs_alpha[1], (x + dx, y, z))
    if b is not None:
        z = z + b
    return x, y, z


def _cs(angle):
    return np.cos(angle), np.sin(angle)


_CS0 = _cs(0.0)        # (cos 0, sin 0) as the numpy scalars np.cos(0.0), np.sin(0.0)

# the three legs' columns of a parameter are equally spaced: slices give views, not fancy-index copies
_LEG_SLICE = {p: slice(int(c[0]), int(c[-1]) + 1, int(c[1] - c[0])) for p, c in _LEG_COL.items()}
if not all(np.array_equal(np.arange(len(_INDEX))[s], _LEG_COL[p]) for p, s in _LEG_SLICE.items()):   # pragma: no cover
    raise ImportError("robots.delta.chains: leg parameter columns are no longer equally spaced")


class DeltaChains:
    """The KK chains of the Delta's legs with errors (mixin of :class:`evotol.robots.delta.model.DeltaRobot`)."""

    def _unpack(self, errors):
        """errors (..., 47) -> common (..., ) and per-leg (..., 3) error arrays."""
        e = {"Ra": errors[..., _INDEX["Ra"]][..., None], "Rb": errors[..., _INDEX["Rb"]][..., None]}
        for p, cols in _LEG_SLICE.items():
            e[p] = errors[..., cols]        # a view (equally spaced columns), read only by sums below
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
        cs5, csa5, cs2, cs1, csa1, csth = _cs(j5), _cs(a5), _cs(j2), _cs(j1), _cs(a1), _cs(th)
        out = []
        for jq, jr, aj, r5, b in ((j3, j4, a3, -d, None), (j6, j7, a6, d, -2 * d)):
            p = _kk_cs(pE, csa5, 0.0, cs5, r5)              # 5 (cut joint, antecedent 4 or 7)
            p = _kk_cs(p, _CS0, Lb, _cs(jr), 0.0)           # 4 or 7: rod end hinge
            p = _kk_cs(p, _cs(aj), 0.0, _cs(jq), 0.0, b)    # 3 or 6: rod start hinge (6: b = -2d)
            p = _kk_cs(p, _CS0, La, cs2, d)                 # 2: upper bar
            p = _kk_cs(p, csa1, Ra, cs1, 0.0)               # 1: actuated joint
            p = _rot_z(csth[0], csth[1], p)                 # A: leg on the base
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
