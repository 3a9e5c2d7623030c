"""Joint limits of a described mechanism: the range of each joint variable (rad or m).

They come from a URDF's ``<limit lower upper>`` (:func:`evotol.robots.mechanism.urdf.reader.urdf_joints`; a
continuous joint has none, a mimic joint's range becomes one of its leader) and from a
description's ``[limits]`` table (``q1 = ["-170*deg", "170*deg"]``), which overrides the URDF. The
assembly configuration and every pose the inverse geometry solves are checked: a joint outside its
range is a :class:`KinematicsError` that names the pose and the joint; poses out of reach are named
together (:func:`unreachable_message`, issue 33).

The parameters several definitions of this module share are described once, here.

Parameters
----------
limits : mapping
    Joint variable -> (lower, upper), rad or m.
"""
from __future__ import annotations

import numpy as np

from evotol.errors import KinematicsError, ValidationError

#: a joint may exceed its range by this much (rad or m) before it counts as outside (round-off of the Newton solve)
LIMIT_SLACK = 1e-9


def check_limit_names(limits, variables) -> None:
    """Every ``[limits]`` key is a joint variable of the description.

    Parameters
    ----------
    variables : sequence of str
        The description's joint variables.

    Raises
    ------
    ValidationError
        ``limits.<name>`` when a key is not one of ``variables``.
    """
    for k in limits:
        if k not in variables:
            raise ValidationError(f"limits.{k}", list(limits[k]), f"a joint variable: {list(variables)}")


def check_joint_limits(name: str, limits, q: dict, poses: np.ndarray, coordinates, what: str = "pose") -> None:
    """Raise when a joint variable leaves its range at some pose.

    Parameters
    ----------
    name : str
        The mechanism's name (for the message).
    q : dict
        Joint variable -> (n,) values at ``poses``.
    poses : ndarray (n, n_coordinates)
        The poses, SI.
    coordinates : sequence of str
        Names of the pose coordinates.
    what : str
        ``"pose"`` or ``"assembly pose"``.

    Raises
    ------
    KinematicsError
        Naming the first pose and joint outside the range, with the value and the range.
    """
    for var, (lo, hi) in limits.items():
        if var not in q:
            continue
        v = np.asarray(q[var], float)
        bad = (v < lo - LIMIT_SLACK) | (v > hi + LIMIT_SLACK)
        if bad.any():
            i = int(np.flatnonzero(bad)[0])
            raise KinematicsError(f"{name}: the {what} {np.asarray(poses)[i].tolist()} ({', '.join(coordinates)}, SI) needs joint "
                                  f"{var} = {v[i]:.6g}, outside its limits [{lo:.6g}, {hi:.6g}] (rad or m)",
                                  poses=np.asarray(poses)[bad])


def unreachable_message(mech, poses: np.ndarray, bad: np.ndarray, residual: np.ndarray) -> str:
    """One line naming every pose the inverse geometry could not reach (how many, the first few).

    Parameters
    ----------
    mech : evotol.robots.mechanism.description.mechanism.Mechanism
        The description (name, coordinates, loops).
    poses : (n, n_coordinates) ndarray
        The poses (SI).
    bad : (n,) ndarray of bool
        The poses not reached.
    residual : (n,) ndarray
        The scaled residual at each pose.

    Returns
    -------
    str
        ``"<name>: k of n poses out of reach or singular ... : #i (x = ..), ..."``; for a mechanism
        with loops "the loops cannot close", for a serial arm "out of reach"; with the option
        that drops them (``[poses] drop_unreachable = true``).
    """
    idx = np.flatnonzero(bad)
    names = [c.name for c in mech.coordinates]
    shown = "; ".join(f"#{int(i)} ({', '.join(f'{n} = {v:.6g}' for n, v in zip(names, poses[i]))})" for i in idx[:5])
    what = "the loops cannot close (out of reach or singular)" if mech.loops else "out of reach or singular"
    return (f"{mech.name}: {len(idx)} of {len(poses)} poses: {what}, SI, largest scaled residual "
            f"{float(np.max(residual[idx])):.2g}: {shown}{' ...' if len(idx) > 5 else ''}. Shrink the task box, or drop "
            "them with [poses] drop_unreachable = true")
