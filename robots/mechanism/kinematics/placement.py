"""Placement errors of a frame as a local twist: three small translations along, and three small
rotations about, the axes of the frame's placement (no singularity at any nominal angle).

A frame's **placement** is the frame itself for a ``fixed`` row, and for a joint row the frame just
before its joint motion, ``T_a(j) Rot(z,gamma) Trans(z,b) Rot(x,alpha) Trans(x,d)`` (its ``z`` is the
joint axis). An error ``delta = [shift; tilt]`` (m; rad) moves it to ``placement * exp(delta)``,
the convention of Pinocchio's placement regressor (``M_i exp(delta)``, ``delta = [v; omega]`` in the
local frame; ``pinocchio.computeFrameKinematicRegressor``). The sources are named
``"<frame>.shift_x"`` ... ``"<frame>.tilt_z"``; for a URDF arm the frame of a joint's origin carries
the joint's name, so ``shoulder_lift_joint.tilt_x`` tilts that joint's axis about the origin's x.

Unlike roll/pitch/yaw of the origin (kept as design parameters ``J_roll, J_pitch, J_yaw``), the six
twists span every small motion of the placement at any nominal orientation: at pitch = pi/2, roll
and yaw turn about the same axis and one tilt direction has no source (issue 23).
"""
from __future__ import annotations

import numpy as np

from evotol.robots.clearance.kinematics import exp_screw

SHIFT_FIELDS = ("shift_x", "shift_y", "shift_z")
TILT_FIELDS = ("tilt_x", "tilt_y", "tilt_z")
PLACEMENT_FIELDS = SHIFT_FIELDS + TILT_FIELDS


def placement_error(errors: dict, n: int) -> np.ndarray:
    """``exp(delta)`` (n, 4, 4) for placement errors ``{field: (n,) array}`` (fields missing are 0).

    Parameters
    ----------
    errors : dict of str to (n,) ndarray or float
        Placement field (``"shift_x"`` ... ``"tilt_z"``) -> its error: shifts in m, tilts in rad,
        in the placement's local axes.

    Returns
    -------
    (n, 4, 4) ndarray
        The homogeneous transform ``exp(delta)`` that right-multiplies the nominal placement.

    Raises
    ------
    ValueError
        A key that is not a placement field (from ``tuple.index``).
    """
    s = np.zeros((n, 6))                       # exp_screw order: [rotation; translation]
    for k, v in errors.items():
        i = PLACEMENT_FIELDS.index(k)
        s[:, i - 3 if i >= 3 else i + 3] = v
    return exp_screw(s)


def placement_twists(T: np.ndarray) -> dict:
    """Spatial twists ``[omega; v0]`` (n, 6) of a unit placement error of each field, for the
    placement's world transform T (n, 4, 4): a rotation about axis ``k`` through the origin ``p``
    is ``[R e_k; p x R e_k]``, a translation ``[0; R e_k]``.

    Parameters
    ----------
    T : (n, 4, 4) ndarray
        World transform of the placement (position in m).

    Returns
    -------
    dict of str to (n, 6) ndarray
        Placement field -> spatial twist ``[omega (rad); v0 (m)]`` at the base origin per unit
        error (per m for a shift, per rad for a tilt).
    """
    R, p = T[:, :3, :3], T[:, :3, 3]
    zero = np.zeros_like(p)
    out = {}
    for k in range(3):
        a = R[:, :, k]
        out[SHIFT_FIELDS[k]] = np.concatenate([zero, a], axis=1)
        out[TILT_FIELDS[k]] = np.concatenate([a, np.cross(p, a)], axis=1)
    return out
