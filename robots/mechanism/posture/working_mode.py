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

A serial chain (no loop) whose ``[assembly]`` gives both the pose and every joint must have them
agree (issue 33: the typed joints were moved by 12.6 deg in silence and the typed pose printed
back): Newton may move a declared revolute joint by at most :data:`SERIAL_MAX_ANGLE` and a
prismatic one by :data:`SERIAL_MAX_LENGTH_FRACTION` of the length scale (round-off of joints
typed to a few decimals); farther is an error naming both (:func:`check_reached`). With only some
joints, or only the pose, the joints seed the inverse geometry, whose postures and limits are
:mod:`evotol.robots.mechanism.kinematics.tree`' (issue 23) and :mod:`evotol.robots.mechanism.posture.held`'s.
"""
from __future__ import annotations

import numpy as np

from evotol.errors import KinematicsError, ValidationError

#: How far Newton may move a declared ``[assembly]`` joint while closing the loops: a revolute
#: joint by 0.5 rad (29 deg), a prismatic one by 20 % of the description's length scale (its
#: largest length parameter).
ASSEMBLY_MAX_ANGLE = 0.5
ASSEMBLY_MAX_LENGTH_FRACTION = 0.2
#: How far Newton may move a declared joint of a serial arm whose [assembly] also gives the pose:
#: 0.5 deg (rad) for a revolute joint, 0.1 % of the length scale for a prismatic one.
SERIAL_MAX_ANGLE = np.radians(0.5)
SERIAL_MAX_LENGTH_FRACTION = 1e-3


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
        residual at the declared joints (m, rad); for a serial arm whose pose and every joint are
        declared, the first joint Newton moves beyond :data:`SERIAL_MAX_ANGLE` /
        :data:`SERIAL_MAX_LENGTH_FRACTION`, with the pose and where the declared joints put the
        end-effector.
    """
    if not kin.mech.loops:
        _check_serial(kin, pose, q0, q)
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


def _check_serial(kin, pose: np.ndarray, q0: dict, q: dict) -> None:
    """A serial arm's declared ``[assembly]`` pose and joints agree (module docstring)."""
    m = kin.mech
    if not m.assembly_pose or set(m.assembly_joints) != set(kin.variables):
        return          # only a seed (some joints, or no pose): the inverse geometry decides
    for x, v in m.assembly_joints.items():
        unit = kin.joint_unit.get(x, "rad")
        d = float(q[x][0] - v)
        if unit == "rad":
            d = float(np.arctan2(np.sin(d), np.cos(d)))
            limit, shown = SERIAL_MAX_ANGLE, (lambda a: f"{np.degrees(a):.4g} deg")
        else:
            limit, shown = SERIAL_MAX_LENGTH_FRACTION * kin.length_scale, (lambda a: f"{a * 1e3:.4g} mm")
        if abs(d) <= limit:
            continue
        at = kin.state({k: np.atleast_1d(np.asarray(val, float)) for k, val in q0.items()}, 1, twists=False)
        p = at.world[m.end_effector][0, :3, 3]
        names = [c.name for c in m.coordinates]
        raise KinematicsError(f"{m.name}: [assembly] pose ({', '.join(f'{n} = {float(v):.6g}' for n, v in zip(names, pose[0]))}, "
                              f"SI) and joints disagree: the declared joints put the end-effector at "
                              f"({', '.join(f'{c * 1e3:.6g}' for c in p)}) mm, and reaching the pose moves {x} from "
                              f"{shown(v)} to {shown(q[x][0])}. Give the joints of that pose (evotol check-mechanism "
                              "prints them), or only one of the two", poses=pose)
