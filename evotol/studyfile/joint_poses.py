"""``[poses] joints`` and ``[poses] drop_unreachable``: a serial arm's poses as the designer means them (issue 33).

The hooks the study-file reader calls: joint configurations, read and checked by
:func:`evotol.robots.mechanism.model.joint_space.joint_configurations`; and the option to drop the poses of a
grid or list that the arm cannot reach (out of reach, singular, outside the joint limits, on
another branch), reported together instead of stopping at the first.
"""
from __future__ import annotations

import numpy as np

from evotol.errors import KinematicsError, ValidationError
from evotol.robots.mechanism.model.joint_space import joint_configurations


def joint_poses(robot, poses_table: dict):
    """The joint-space model and the configurations of ``[poses] joints``.

    Parameters
    ----------
    robot : evotol.robots.base.RobotErrorModel
        The study's robot: a mechanism description of a serial arm.
    poses_table : dict
        The ``[poses]`` table; ``joints`` is a list of configurations (a list in the joint order
        or a table by joint name; SI numbers or expressions such as ``"30*deg"``).

    Returns
    -------
    model : evotol.robots.mechanism.model.joint_space.JointSpaceModel
        The arm, evaluated at joint configurations.
    poses : (n, n_joints) ndarray
        The configurations (rad, m).

    Raises
    ------
    evotol.errors.ValidationError
        ``joints`` next to ``grid``, ``latin_hypercube``, ``list`` or ``refine``, and everything
        :func:`~evotol.robots.mechanism.model.joint_space.joint_configurations` refuses.
    """
    other = [k for k in ("grid", "latin_hypercube", "list", "refine", "drop_unreachable") if k in poses_table]
    if other:
        raise ValidationError(f"poses.{other[0]}", poses_table[other[0]], "nothing next to poses.joints (the poses are "
                                                                          "exactly the joint configurations given)")
    return joint_configurations(robot, poses_table["joints"])


def drop_unreachable(robot, poses, poses_table: dict):
    """The poses the robot reaches, when ``[poses] drop_unreachable = true``; else ``poses`` unchanged.

    Parameters
    ----------
    poses : (n, workspace.dim) ndarray
        The poses of the grid, Latin hypercube or list (SI).
    poses_table : dict
        The ``[poses]`` table.

    Returns
    -------
    (k, workspace.dim) ndarray
        The poses kept; the dropped ones are counted in the robot's notes (``dropped_poses``).

    Raises
    ------
    evotol.errors.ValidationError
        ``drop_unreachable`` not a bool, or no reachable pose left.
    """
    flag = poses_table.get("drop_unreachable", False)
    if not isinstance(flag, bool):
        raise ValidationError("poses.drop_unreachable", flag, "true or false")
    poses = np.asarray(poses, float)
    if not flag:
        return poses
    keep = np.ones(len(poses), bool)
    for _ in range(4):              # each refusal names every pose of its kind; a second kind may follow
        try:
            robot.sensitivity(poses[keep])
            break
        except KinematicsError as exc:
            if exc.poses is None:
                raise
            bad = np.atleast_2d(np.asarray(exc.poses, float))
            hit = (np.abs(poses[:, None, :] - bad[None]) <= 0).all(axis=2).any(axis=1)
            if not (hit & keep).any():
                raise
            keep &= ~hit
            if not keep.any():
                raise ValidationError("poses", f"{len(poses)} poses", "at least one pose the arm reaches "
                                      "(drop_unreachable dropped them all)") from None
    dropped = int((~keep).sum())
    if dropped:
        robot.described.dropped_poses = (dropped, len(poses), poses[~keep][:5].tolist())   # its notes say so
    return poses[keep]
