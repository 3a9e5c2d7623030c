"""The declared working mode of a closed-loop mechanism (issue 27 item 1): the ``[assembly]``
joints say which assembly is meant, and Newton must close the loops near them.

* Every joint variable of a mechanism with loops is declared (:func:`check_declared`): Newton from
  all-zero joints lands on any working mode -- a 3-RPR with a negative stroke of -0.226 m in the
  issue's example.
* Newton closes the loops within :data:`ASSEMBLY_MAX_ANGLE` of every declared revolute joint
  (compared modulo a full turn) and :data:`ASSEMBLY_MAX_LENGTH_FRACTION` of the length scale of
  every declared prismatic one (:func:`check_reached`); farther is another working mode, or a
  description that does not mean what was written (a length in mm written as metres, a loop
  closed to the wrong frame). Measured on the shipped descriptions, the declared joints are
  within 0.16 rad (IRSBot-2's ``t9``) and 2.8 mm (3-UCR's ``l1``) of the solved ones.

A serial chain (no loop) is not checked here: its joints seed the inverse geometry, whose
postures and limits are :mod:`robots.mechanism.kinematics`' (issue 23).
"""
from __future__ import annotations

import numpy as np

from evotol.errors import KinematicsError, ValidationError

#: How far Newton may move a declared ``[assembly]`` joint while closing the loops: a revolute
#: joint by 0.5 rad (29 deg), a prismatic one by 20 % of the description's length scale (its
#: largest length parameter).
ASSEMBLY_MAX_ANGLE = 0.5
ASSEMBLY_MAX_LENGTH_FRACTION = 0.2


def check_declared(kin) -> None:
    """Every joint variable of a closed-loop mechanism is declared in ``[assembly] joints``.

    Parameters
    ----------
    kin : Kinematics
        The mechanism's kinematics (its ``mech``, ``variables``).

    Raises
    ------
    ValidationError
        ``assembly`` (no table) or ``assembly.joints`` (naming the missing joints).
    """
    if not kin.mech.loops:
        return
    declared = kin.mech.assembly_joints
    if not declared:
        raise ValidationError("assembly", None, f"an [assembly] table for the closed-loop mechanism {kin.mech.name!r}: "
                                                f"pose and approximate joints {{{', '.join(kin.variables)}}} of the "
                                                "intended working mode (Newton from all-zero joints picks any)")
    missing = [x for x in kin.variables if x not in declared]
    if missing:
        raise ValidationError("assembly.joints", sorted(declared), f"a value for every joint variable of the closed "
                                                                   f"loops; missing: {', '.join(missing)}")


def check_reached(kin, pose: np.ndarray, q0: dict, q: dict) -> None:
    """Newton closed the loops near the declared joints (see the module docstring).

    Parameters
    ----------
    kin : Kinematics
        The mechanism's kinematics.
    pose : ndarray, shape (1, n_coordinates)
        The assembly pose (SI).
    q0, q : dict
        Joint variables as declared (Newton's start) and as solved, (1,) arrays (rad or m).

    Raises
    ------
    KinematicsError
        Naming the joint farthest beyond its bound, its declared and reached values and the loop
        residual at the declared joints (m, rad).
    """
    if not kin.mech.loops:
        return
    declared = kin.mech.assembly_joints
    worst, worst_ratio = None, 1.0
    for x in kin.variables:
        if x not in declared:
            continue
        unit = kin.joint_unit.get(x, "rad")
        d = float(q[x][0] - declared[x])
        if unit == "rad":
            d = float(np.arctan2(np.sin(d), np.cos(d)))     # a full turn is the same posture
            limit = ASSEMBLY_MAX_ANGLE
        else:
            limit = ASSEMBLY_MAX_LENGTH_FRACTION * kin.length_scale
        if abs(d) / limit > worst_ratio:
            worst, worst_ratio = (x, unit, limit), abs(d) / limit
    if worst is None:
        return
    x, unit, limit = worst
    loop = kin.loop_residual(kin.state(q0, 1, twists=False))[0]        # the loops at the declared joints
    rows = kin.loop_row_is_length()
    res_m = float(np.abs(loop[rows]).max()) if rows.any() else 0.0
    res_rad = float(np.abs(loop[~rows]).max()) if (~rows).any() else 0.0
    raise KinematicsError(f"{kin.mech.name}: assembly.joints.{x} = {declared[x]:.6g} {unit} was declared, but Newton "
                          f"closed the loops at {x} = {q[x][0]:.6g} {unit} (more than {limit:.3g} {unit} away); the loop "
                          f"residual at the declared joints is {res_m:.3g} m, {res_rad:.3g} rad. Check the units of the "
                          "lengths and angles (250 is 250 m: write '250*mm'; 90 is 90 rad: write '90*deg'), the frames "
                          "and loops, or declare the joints of the intended assembly", poses=pose)
