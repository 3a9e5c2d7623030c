"""``[poses] joints``: a study file's poses given as joint configurations of a serial arm (issue 33).

The hook the study-file reader calls; the configurations are read and checked by
:func:`robots.mechanism.joint_space.joint_configurations`.
"""
from __future__ import annotations

from evotol.errors import ValidationError
from robots.mechanism.joint_space import joint_configurations


def joint_poses(robot, poses_table: dict):
    """The joint-space model and the configurations of ``[poses] joints``.

    Parameters
    ----------
    robot : robots.base.RobotErrorModel
        The study's robot: a mechanism description of a serial arm.
    poses_table : dict
        The ``[poses]`` table; ``joints`` is a list of configurations (a list in the joint order
        or a table by joint name; SI numbers or expressions such as ``"30*deg"``).

    Returns
    -------
    model : robots.mechanism.joint_space.JointSpaceModel
        The arm, evaluated at joint configurations.
    poses : (n, n_joints) ndarray
        The configurations (rad, m).

    Raises
    ------
    evotol.errors.ValidationError
        ``joints`` next to ``grid``, ``latin_hypercube``, ``list`` or ``refine``, and everything
        :func:`~robots.mechanism.joint_space.joint_configurations` refuses.
    """
    other = [k for k in ("grid", "latin_hypercube", "list", "refine") if k in poses_table]
    if other:
        raise ValidationError(f"poses.{other[0]}", poses_table[other[0]], "nothing next to poses.joints (the poses are "
                                                                          "exactly the joint configurations given)")
    return joint_configurations(robot, poses_table["joints"])
