"""The calibration configurations of a plan: joint values at which the instrument measures the tool.

From a :class:`~evotol.calibration.plan.CalibrationPlan`: given joint values (checked against the
joint limits), workspace poses (solved by the model's inverse geometry), or a count drawn by a
Latin hypercube over the workspace box or over the joint limits (serial arms). What is returned
is always joint values, so the identification and the simulated calibration use the same robot
configurations.
"""
from __future__ import annotations

import numpy as np

from evotol.errors import KinematicsError, ValidationError


def is_described(robot) -> bool:
    """True for a model with joint-space maps (:class:`evotol.robots.mechanism.model.error_model.MechanismModel`).

    Parameters
    ----------
    robot : evotol.robots.base.RobotErrorModel
        Any error model.

    Returns
    -------
    bool
        The model has ``sensitivity_at_joints``, ``pose_error_at_joints`` and ``joint_values``.
    """
    return bool(getattr(robot, "joint_maps", False))


def _joint_limits(robot) -> tuple[np.ndarray, np.ndarray]:
    """(lower, upper) per joint variable (rad, m); +-inf where the description gives none."""
    lim = robot.mechanism.limits
    lo = np.array([lim.get(v, (-np.inf, np.inf))[0] for v in robot.kin.variables], float)
    hi = np.array([lim.get(v, (-np.inf, np.inf))[1] for v in robot.kin.variables], float)
    return lo, hi


def calibration_joints(robot, plan) -> np.ndarray | None:
    """Joint values (n, n_variables) of the plan's configurations, or None for a model without joint maps.

    Parameters
    ----------
    robot : evotol.robots.base.RobotErrorModel
        The error model; joint values need a described mechanism (:func:`is_described`).

    Returns
    -------
    (n, n_variables) ndarray or None
        Joint values (rad, m) in the order of ``robot.kin.variables``; None when the model has no
        joint maps (then :func:`calibration_poses` gives the configurations).

    Raises
    ------
    evotol.errors.ValidationError
        Joint values without one column per joint variable or outside the joint limits (names the
        configuration and the joint); joints or ``over = "joints"`` on a model without joint maps
        or with closed loops; a joint-space draw with a joint that has no limits; a pose out of
        reach.
    """
    if not is_described(robot):
        if plan.joints is not None or (plan.count is not None and plan.over == "joints"):
            raise ValidationError("calibration.joints", robot.name, "a described mechanism (joint values need its joint maps); "
                                  "give poses = [[...]] or count = n over the workspace")
        return None
    kin = robot.kin
    lo, hi = _joint_limits(robot)
    if plan.joints is not None or (plan.count is not None and plan.over == "joints"):
        if robot.mechanism.loops:
            raise ValidationError("calibration.joints", robot.name, "a serial arm (a closed-loop mechanism's joints must close "
                                  "its loops): give poses = [[...]] or count = n over the workspace")
        if plan.joints is not None:
            Q = plan.joints
            if Q.shape[1] != len(kin.variables):
                raise ValidationError("calibration.joints", Q.shape, f"(n, {len(kin.variables)}) columns {kin.variables}")
        else:
            if not (np.all(np.isfinite(lo)) and np.all(np.isfinite(hi))):
                j = kin.variables[int(np.nonzero(~(np.isfinite(lo) & np.isfinite(hi)))[0][0])]
                raise ValidationError("calibration.over", "joints", f"joint limits for every joint ({j} has none): "
                                      "add them under [limits], or draw over the workspace")
            from scipy.stats import qmc

            Q = lo + qmc.LatinHypercube(d=len(lo), seed=plan.seed).random(int(plan.count)) * (hi - lo)
        out = (Q < lo - 1e-9) | (Q > hi + 1e-9)
        if out.any():
            i, j = (int(a[0]) for a in np.nonzero(out))
            raise ValidationError(f"calibration.joints[{i}]", Q[i].tolist(),
                                  f"joint values inside the limits ({kin.variables[j]} = {Q[i, j]:.6g} outside "
                                  f"[{lo[j]:.6g}, {hi[j]:.6g}])")
        return np.asarray(Q, float)
    P = calibration_poses(robot, plan)
    try:
        q = robot.joint_values(P)
    except KinematicsError as exc:
        raise ValidationError("calibration.poses", P.tolist()[:3], f"poses the robot reaches inside its joint limits ({exc})") from None
    return np.stack([np.asarray(q[v], float) for v in kin.variables], axis=1)


def calibration_poses(robot, plan) -> np.ndarray:
    """Workspace poses (n, dim) of the plan's configurations (given, or a Latin hypercube of the box).

    Parameters
    ----------
    robot : evotol.robots.base.RobotErrorModel
        The error model (its workspace).
    plan : evotol.calibration.plan.CalibrationPlan
        A plan with ``poses`` or ``count`` over the workspace.

    Returns
    -------
    (n, dim) ndarray
        Poses (SI: m, rad).

    Raises
    ------
    evotol.errors.ValidationError
        Poses of the wrong width, or outside the workspace box.
    """
    if plan.poses is not None:
        P = plan.poses
        if P.shape[1] != robot.workspace.dim:
            raise ValidationError("calibration.poses", P.shape, f"(n, {robot.workspace.dim}) columns {robot.workspace.names}")
        inside = robot.workspace.contains(P)
        if not inside.all():
            i = int(np.nonzero(~inside)[0][0])
            raise ValidationError(f"calibration.poses[{i}]", P[i].tolist(), f"a pose inside the workspace "
                                  f"{list(zip(robot.workspace.low, robot.workspace.high))}")
        return P
    return robot.workspace.latin_hypercube(int(plan.count), seed=plan.seed)
