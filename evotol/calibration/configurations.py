"""The calibration configurations of a plan: joint values at which the instrument measures the tool.

From a :class:`~evotol.calibration.plan.CalibrationPlan`: given joint values (checked against the
joint limits), workspace poses (solved by the model's inverse geometry), or a count drawn by a
Latin hypercube over the workspace box or over the joint limits (serial arms). What is returned
is always joint values, so the identification and the simulated calibration use the same robot
configurations.

The cell. A configuration that puts a joint origin or the tool below the plan's floor (``z < floor``
in the base frame; by default the mounting plane ``z = 0``) or inside one of its obstacle boxes is
not in the plan: given joints or poses are refused naming the configuration and the frame; a drawn
plan keeps the admissible configurations of its Latin hypercube and draws further hypercubes
(seeds ``seed + 1``, ``seed + 2``, ...) until it has ``count`` of them (at most ``MAX_DRAWS``).
"""
from __future__ import annotations

import numpy as np

from evotol.errors import KinematicsError, ValidationError

#: Latin hypercubes drawn at most to find ``count`` configurations inside the cell
MAX_DRAWS = 50


def cell_violations(robot, joints, plan) -> list:
    """For each configuration, the first frame below the floor or inside an obstacle, else None.

    Parameters
    ----------
    robot : evotol.robots.mechanism.model.error_model.MechanismModel
        A described mechanism (its joint frames and tool frame).
    joints : (n, n_variables) ndarray
        Joint values (rad, m).
    plan : evotol.calibration.plan.CalibrationPlan
        The plan (``floor`` in m or None, ``obstacles``: (min, max) boxes in m).

    Returns
    -------
    list of (str, ndarray) or None
        Per configuration: ``(frame name, its origin (3,) m)`` of the first offending frame, or None.
    """
    Q = np.asarray(joints, float)
    n = len(Q)
    if plan.floor is None and not plan.obstacles:
        return [None] * n
    kin = robot.kin
    st = kin.state({v: Q[:, i] for i, v in enumerate(kin.variables)}, n, twists=False)
    frames = [f for f in list(kin.variables) + [robot.mechanism.end_effector] if f in st.world]
    P = np.stack([np.asarray(st.world[f], float).reshape(n, 4, 4)[:, :3, 3] for f in frames], 1)   # (n, F, 3)
    bad = P[..., 2] < plan.floor - 1e-9 if plan.floor is not None else np.zeros(P.shape[:2], bool)
    for lo, hi in plan.obstacles:
        bad |= np.all((P >= lo) & (P <= hi), axis=2)
    return [(frames[int(np.argmax(b))], P[i, int(np.argmax(b))]) if b.any() else None for i, b in enumerate(bad)]


def _refuse_outside_cell(robot, Q, plan, field: str) -> None:
    """One line naming the first given configuration outside the cell."""
    for i, v in enumerate(cell_violations(robot, Q, plan)):
        if v is not None:
            where = f"below the floor z = {plan.floor:g} m" if plan.floor is not None and v[1][2] < plan.floor - 1e-9 \
                else "inside an obstacle"
            raise ValidationError(f"calibration.{field}[{i}]", np.round(Q[i], 6).tolist(), f"a configuration inside the "
                                  f"cell ({v[0]} at z = {v[1][2]:.4g} m is {where})")


def _draw_inside(robot, plan, draw) -> np.ndarray:
    """``plan.count`` joint configurations of successive draws ``draw(seed)`` that stay inside the cell."""
    kept = []
    for d in range(MAX_DRAWS):
        Q = draw(plan.seed + d)
        kept += [q for q, v in zip(Q, cell_violations(robot, Q, plan)) if v is None]
        if len(kept) >= plan.count:
            return np.asarray(kept[:plan.count], float)
    raise ValidationError("calibration.floor", plan.floor, f"a cell in which {plan.count} configurations can be drawn "
                          f"({len(kept)} of {MAX_DRAWS} Latin hypercubes stay above the floor and out of the obstacles)")


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
    return bool(robot.joint_maps)


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

            return _draw_inside(robot, plan, lambda s: lo + qmc.LatinHypercube(d=len(lo), seed=s).random(int(plan.count)) * (hi - lo))
        out = (Q < lo - 1e-9) | (Q > hi + 1e-9)
        if out.any():
            i, j = (int(a[0]) for a in np.nonzero(out))
            raise ValidationError(f"calibration.joints[{i}]", Q[i].tolist(),
                                  f"joint values inside the limits ({kin.variables[j]} = {Q[i, j]:.6g} outside "
                                  f"[{lo[j]:.6g}, {hi[j]:.6g}])")
        _refuse_outside_cell(robot, Q, plan, "joints")
        return np.asarray(Q, float)
    if plan.poses is not None:
        Q = _joints_of(robot, calibration_poses(robot, plan))
        _refuse_outside_cell(robot, Q, plan, "poses")
        return Q
    return _draw_inside(robot, plan, lambda s: _joints_of(robot, robot.workspace.latin_hypercube(int(plan.count), seed=s)))


def _joints_of(robot, P) -> np.ndarray:
    """Joint values (n, n_variables) of workspace poses P, or one line naming the poses."""
    try:
        q = robot.joint_values(P)
    except KinematicsError as exc:
        raise ValidationError("calibration.poses", P.tolist()[:3], f"poses the robot reaches inside its joint limits ({exc})") from None
    return np.stack([np.asarray(q[v], float) for v in robot.kin.variables], axis=1)


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


def pose_error_of_robots(robot, Q, E) -> np.ndarray:
    """Nonlinear error (n_conf, m, 6) of ``m`` robots at every configuration: robot ``k`` has the source
    errors ``E[k]`` (m or rad) at each joint configuration of ``Q`` (rad or m).

    The errors are passed as a read-only broadcast view (the same rows at every configuration), not a
    copy: a compiled serial arm then builds each robot's operations once for all configurations
    (``serial_montecarlo.pose_error_shared``, the same arithmetic per pose-sample as the per-pose kernel).

    Parameters
    ----------
    robot : evotol.robots.base.RobotErrorModel
        A model with ``pose_error_at_joints``.
    Q : (n_conf, n_variables) ndarray
        Joint configurations (rad or m).
    E : (m, n_columns) ndarray
        Each robot's source errors (m or rad).

    Returns
    -------
    (n_conf, m, 6) ndarray
        ``[dp (m); rotation vector (rad)]`` of the tool of each robot at each configuration.
    """
    return robot.pose_error_at_joints(Q, np.broadcast_to(E, (len(Q),) + E.shape))
