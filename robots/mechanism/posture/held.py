"""The posture a serial arm holds over its task: stated, kept, and shown.

Issue 33: continued from the assembly configuration, the inverse geometry of a PUMA 560 reached
one pose on another wrist branch (q5 of the other sign, q4 and q6 turned by half a turn) and the
study certified a design for that posture, silently. For a task with as many equations as joint
variables (a 6-joint arm with a 6-D task: position and orientation), the branch is the sign of
``det J`` of the task Jacobian (``d(task residual)/dq``): it changes exactly where the continuation
passes through a singularity (elbow stretched, wrist axes aligned, wrist centre on the shoulder
axis), and every inverse-geometry branch of such an arm is separated from the others by one.

* :func:`check_branch` refuses a pose whose ``det J`` has the other sign than at the assembly
  configuration (the path from the assembly crossed a singularity: another elbow, shoulder or wrist
  branch), naming the pose; and returns the poses that are *near* a singularity (smallest singular
  value of the scaled Jacobian below :data:`NEAR_SINGULAR` times its largest) for a warning.
* :func:`wrapped` gives the joint values of revolute joints in (-180°, 180°] (``(-π, π]``), as the
  JSON and the page show them.

Redundant arms (more joint variables than task equations) have no branch sign: their inverse
geometry takes the configuration nearest to the assembly (``docs/mechanisms.md``, Redundant arms).
"""
from __future__ import annotations

import warnings

import numpy as np

from evotol.errors import KinematicsError
from evotol.robots.base import RobotErrorModel, dropped_line
from evotol.robots.mechanism.kinematics.serial import SERIAL_COMPILED, SerialChain

#: relative smallest singular value of the scaled task Jacobian below which a pose counts as near a singularity
NEAR_SINGULAR = 1e-3
#: samples of the joint-space path from the assembly joints to a solution (det J sign along it)
PATH_SAMPLES = 24
#: path samples (configurations) whose Jacobians the general path holds at once: its poses are checked in
#: blocks of ``PATH_BLOCK // PATH_SAMPLES``, so the check's memory does not grow with the poses (issue 43
#: item 4: 103 823 UR5 poses at once took 2.3 GB; the compiled path stores no Jacobian)
PATH_BLOCK = 1 << 15


def wrapped(kin, q: dict) -> dict:
    """Joint values with every revolute joint wrapped into (-π, π] (prismatic ones unchanged).

    Parameters
    ----------
    kin : evotol.robots.mechanism.kinematics.tree.Kinematics
        The kinematics (``joint_unit``: rad or m per joint variable).
    q : dict of str to array_like
        Joint variable -> values (rad or m).

    Returns
    -------
    dict of str to ndarray
        The same keys; revolute values in (-π, π].
    """
    out = {}
    for k, v in q.items():
        v = np.asarray(v, float)
        out[k] = np.pi - np.mod(np.pi - v, 2 * np.pi) if kin.joint_unit.get(k, "rad") == "rad" else v
    return out


def _task_jacobian(kin, q: dict, poses: np.ndarray, chain=None) -> np.ndarray | None:
    """Scaled square task Jacobian (n, m, m), or None when the system is not square (redundant).

    ``chain``: the compiled serial chain (:class:`evotol.robots.mechanism.kinematics.serial.SerialChain`) built with
    the joint variables as columns: its end-effector Jacobian gives the same rows, faster."""
    if chain is None or kin.mech.loops:
        Rt = kin._target_orientation(poses)
        _, J, is_len = kin._ig_system(q, poses, Rt)
    else:
        Je = chain.sensitivity(chain.joints_array(q))                  # (n, 6, n_variables)
        rows = [ax for _, ax in kin.coord_axes] + ([3, 4, 5] if kin.orientation else [])
        J = Je[:, rows]
        is_len = np.array([r < 3 for r in rows])
    if J.shape[1] != J.shape[2]:
        return None
    w = np.where(is_len, 1.0 / kin.length_scale, 1.0)
    return J * w[None, :, None]


def _path_determinants(kin, chain, q0: dict, diff: dict, S: np.ndarray):
    """(det J (samples, n), J at the last sample (n, m, m)) of :func:`check_branch`'s paths by the
    compiled kernel (:func:`evotol.robots.mechanism.kinematics.serial_newton.path_determinants`)."""
    from evotol.robots.mechanism.kinematics import serial_newton

    D = np.ascontiguousarray(np.stack([diff[v] for v in chain.variables], axis=1), float)
    return serial_newton.path_determinants(*chain._args(), np.array([q0[v] for v in chain.variables], float), D, S,
                                           bool(kin.orientation), np.array([ax for _, ax in kin.coord_axes], np.int64),
                                           *chain._joint_stages(), float(kin.length_scale))


def _relative_smallest_singular_value(J: np.ndarray, det: np.ndarray) -> np.ndarray:
    """``sigma_min / sigma_max`` of each square J (n, m, m) where it may be below :data:`NEAR_SINGULAR`,
    else a lower bound of it that is not: ``|det J| / U^m`` with ``U^2 >= sigma_max^2`` (Gershgorin's
    circles of ``J^T J``), since ``sigma_min >= |det J| / sigma_max^(m-1)``. The SVD runs only where
    the bound does not decide (on the UR5's task box: nowhere; it was a quarter of the check)."""
    U2 = np.abs(np.einsum("nki,nkj->nij", J, J)).sum(axis=2).max(axis=1)
    rel = np.abs(det) / np.maximum(U2, 1e-300) ** (J.shape[1] / 2)
    low = np.flatnonzero(~(rel >= NEAR_SINGULAR))
    if low.size:
        sv = np.linalg.svd(J[low], compute_uv=False)
        rel[low] = sv[:, -1] / np.maximum(sv[:, 0], 1e-300)
    return rel


def check_branch(kin, poses: np.ndarray, q: dict, names, chain=None) -> np.ndarray:
    """Refuse poses reached on another branch than the assembly's; report those near a singularity.

    The joint-space path from the assembly joints ``q0`` to each solution ``q`` (revolute
    differences wrapped into (-π, π], so a full turn is no change) is sampled at
    :data:`PATH_SAMPLES` points: where ``det J`` changes sign along it, the solution lies across a
    singularity from the assembly posture (an end-point check alone misses two crossings, e.g.
    elbow and wrist both flipped).

    Parameters
    ----------
    kin : evotol.robots.mechanism.kinematics.tree.Kinematics
        The kinematics of a mechanism without loops.
    poses : (n, n_coordinates) ndarray
        The poses (SI).
    q : dict of str to (n,) ndarray
        The joint values the inverse geometry found there (rad or m).
    names : sequence of str
        The pose coordinates' names (for the message).
    chain : evotol.robots.mechanism.kinematics.serial.SerialChain or None, optional
        The compiled chain with the joint variables as columns (faster Jacobians), or None.

    Returns
    -------
    (k,) ndarray of int
        Indices of the poses near a singularity (see :data:`NEAR_SINGULAR`); empty for a
        redundant arm or one with loops.

    Raises
    ------
    evotol.errors.KinematicsError
        A pose whose path from the assembly crosses ``det J = 0`` (names the pose, the joints at
        the assembly and there, wrapped to (-180, 180] deg).
    """
    if kin.mech.loops or len(poses) == 0:
        return np.zeros(0, int)
    x0, q0 = kin.assembly()
    J0 = _task_jacobian(kin, {k: np.array([v]) for k, v in q0.items()}, x0[None], chain)
    if J0 is None:
        return np.zeros(0, int)
    sign0 = np.sign(np.linalg.det(J0[0]))
    n = len(poses)
    diff = {k: np.asarray(q[k], float) - q0[k] for k in kin.variables}
    diff = {k: (wrapped(kin, {k: d})[k]) for k, d in diff.items()}
    S = np.linspace(0.0, 1.0, PATH_SAMPLES + 1)[1:]
    scale = np.abs(np.linalg.det(J0[0])) if np.linalg.det(J0[0]) != 0 else 1.0
    if chain is not None:           # compiled: det J at every sample, no Jacobian stored (issue 43 item 1)
        det, J_end = _path_determinants(kin, chain, q0, diff, S)
        rel_end = _relative_smallest_singular_value(J_end, det[-1])
        crossed = ((np.sign(det) != sign0) & (np.abs(det) > 1e-12 * scale)).any(axis=0)
    else:                           # every sample of the paths of a block of poses in one batch
        rel_end, crossed = np.empty(n), np.empty(n, dtype=bool)
        step = max(1, PATH_BLOCK // len(S))
        for b in range(0, n, step):
            sl = slice(b, min(n, b + step))
            qs = {k: (q0[k] + S[:, None] * diff[k][None, sl]).ravel() for k in kin.variables}
            J = _task_jacobian(kin, qs, np.tile(poses[sl], (len(S), 1)), chain).reshape(len(S), sl.stop - b,
                                                                                       *J0.shape[1:])
            det = np.linalg.det(J)                                  # (samples, poses of the block)
            rel_end[sl] = _relative_smallest_singular_value(J[-1], det[-1])
            crossed[sl] = ((np.sign(det) != sign0) & (np.abs(det) > 1e-12 * scale)).any(axis=0)
    near = np.flatnonzero(rel_end < NEAR_SINGULAR)
    other = np.flatnonzero(crossed & ~(rel_end < NEAR_SINGULAR))
    if other.size:
        i = int(other[0])
        qa, qi = wrapped(kin, q0), wrapped(kin, {k: v[i] for k, v in q.items()})
        raise KinematicsError(f"{kin.mech.name}: pose {i} ({', '.join(f'{n} = {v:.6g}' for n, v in zip(names, poses[i]))}, SI) "
                              f"is on another branch than the assembly posture: from the assembly joints ({_shown(kin, qa)}) "
                              f"to the solution there ({_shown(kin, qi)}) det J changes sign (a singularity lies between: "
                              "another elbow, shoulder or wrist). Give the poses as joint values ([poses] joints), or a task "
                              "set that stays on the assembly's branch", poses=poses[other])
    return near


def _shown(kin, q: dict) -> str:
    return ", ".join(f"{k} = {np.degrees(float(q[k])):.1f} deg" if kin.joint_unit.get(k, "rad") == "rad"
                     else f"{k} = {float(q[k]) * 1e3:.1f} mm" for k in kin.variables)


class PostureWarning(UserWarning):
    """A pose of the task set lies near a singularity of the arm (names the pose)."""


def check_posture(model, poses: np.ndarray, q: dict) -> None:
    """:func:`check_branch` for a mechanism model's inverse geometry, once per pose set; a pose
    near a singularity is a :class:`PostureWarning` and a line of :func:`posture_notes`.

    Parameters
    ----------
    model : evotol.robots.mechanism.model.error_model.MechanismModel
        The model (its ``kin`` and ``workspace``); the poses near a singularity are remembered on
        it (``_near_singular``).
    poses : (n, n_coordinates) ndarray
        The poses (SI).
    q : dict of str to (n,) ndarray
        The joint values found there (rad or m).

    Raises
    ------
    evotol.errors.KinematicsError
        A pose on another branch than the assembly (:func:`check_branch`).
    """
    poses = np.atleast_2d(np.asarray(poses, float))
    seen = model.__dict__.setdefault("_posture_checked", set())
    key = poses.tobytes()
    if key in seen:
        return
    if "_posture_chain" not in model.__dict__:     # the compiled chain over the joint variables (None: general path)
        model._posture_chain = SerialChain.build(model.kin, list(model.kin.variables)) if SERIAL_COMPILED else None
    near = check_branch(model.kin, poses, q, model.workspace.names, model._posture_chain)
    store = model.__dict__.setdefault("_near_singular", {})
    for i in near:
        pose = tuple(float(v) for v in poses[i])
        if pose not in store:
            store[pose] = {k: float(v[i]) for k, v in q.items()}
            warnings.warn(f"{model.name}: pose {pose} (SI) is near a singularity of the arm (smallest singular value of "
                          f"the task Jacobian below {NEAR_SINGULAR:g} of the largest); its errors there are those of "
                          "this posture", PostureWarning, stacklevel=4)
    if len(seen) > 64:
        seen.clear()
    seen.add(key)


def posture_notes(model) -> list[str]:
    """The report lines about the posture: poses found near a singularity so far.

    Parameters
    ----------
    model : evotol.robots.mechanism.model.error_model.MechanismModel
        The model (after its inverse geometry ran).

    Returns
    -------
    list of str
        A line on the poses dropped as unreachable (``dropped_poses``, set by the study-file
        reader) and one listing up to five poses near a singularity (SI), or nothing.
    """
    out = []
    kin = model.kin
    if not kin.mech.loops and model.__dict__.get("_posture_checked"):     # a cache the posture check fills
        x0, q0 = kin.assembly()
        J0 = _task_jacobian(kin, {k: np.array([v]) for k, v in q0.items()}, x0[None])
        if J0 is not None:
            out.append("Posture held: every pose is solved on the branch of the assembly configuration ("
                       + _shown(kin, wrapped(kin, q0)) + "); a pose on another elbow, shoulder or wrist branch is "
                       "refused (robots/mechanism/posture/held.py); the joints used are in the table 'Joints used at every pose'.")
    if model.dropped_poses:
        out.append(dropped_line(model.dropped_poses))
    near = model.__dict__.get("_near_singular", {})
    if not near:
        return out
    shown = "; ".join(str(list(np.round(p, 6))) for p in list(near)[:5])
    return out + [f"{len(near)} pose(s) near a singularity of the arm (smallest singular value of the task Jacobian below "
            f"{NEAR_SINGULAR:g} of the largest): {shown}{' ...' if len(near) > 5 else ''}."]


def joints_at(robot, poses) -> dict:
    """The joint values a mechanism model uses at its poses (empty for other robots).

    Parameters
    ----------
    robot : evotol.robots.base.RobotErrorModel
        A :class:`~evotol.robots.mechanism.model.joint_space.JointSpaceModel` (the poses are the joints), a
        :class:`~evotol.robots.mechanism.model.error_model.MechanismModel` (its inverse geometry, posture held) or
        another robot.
    poses : (n, workspace.dim) ndarray
        The robot's poses (SI).

    Returns
    -------
    dict of str to (n,) ndarray
        Joint variable -> values (rad or m), not wrapped; empty when the robot has no joint
        variables.
    """
    poses = np.atleast_2d(np.asarray(poses, float))
    # the first part of the composition that maps joint values (a calibrated robot keeps its poses;
    # joint-space poses are their own joint values)
    robot = next((m for m in robot.parts() if m.joint_maps), None) if isinstance(robot, RobotErrorModel) else None
    if robot is None:
        return {}
    return {k: np.asarray(v, float) for k, v in robot.joint_values(poses).items()}


def joint_table(robot, poses) -> dict:
    """The joints used at every pose as a report shows them: revolute joints wrapped to (-π, π].

    Parameters
    ----------
    robot : evotol.robots.base.RobotErrorModel
        As :func:`joints_at`.
    poses : (n, workspace.dim) ndarray
        The robot's poses (SI).

    Returns
    -------
    dict
        ``{"variables": [...], "units": ["rad" | "m", ...], "values": {variable: [n values]}}``
        (SI, wrapped); empty for a robot without joint variables.
    """
    q = joints_at(robot, poses)
    described = robot.described
    kin = described.kin if described.joint_maps else None
    if not q or kin is None:
        return {}
    return {"variables": list(q), "units": [kin.joint_unit.get(v, "rad") for v in q],
            "values": {k: v.tolist() for k, v in wrapped(kin, q).items()}}

