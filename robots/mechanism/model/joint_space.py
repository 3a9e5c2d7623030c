"""Poses given as joint configurations: a serial arm's error model whose "workspace" is its joint space.

A designer often knows the configurations at which the arm must be accurate (a textbook's
``[10, 10, -100, -20, 30, -60] deg``), not the tool poses. The inverse geometry would then have to
find them again from the tool pose, and may land on another elbow or wrist branch (issue 33).
:class:`JointSpaceModel` avoids that: its poses *are* the joint values (in the mechanism's joint
order, rad or m), its ``sensitivity`` and ``pose_error`` are the mechanism's at those joints
(:meth:`MechanismModel.sensitivity_at_joints
<evotol.robots.mechanism.model.error_model.MechanismModel.sensitivity_at_joints>`), and no inverse geometry runs, so
the requirement holds at exactly the configurations given.

:func:`joint_configurations` reads them as a study file writes them (``[poses] joints = [[...],
...]`` in the joint order, or ``[{q1 = "30*deg", ...}, ...]`` by name; numbers in SI, or
expressions such as ``"30*deg"``) and checks them before any work: one value per joint, inside the
joint limits, a serial arm (with closed loops the passive joints are not free to choose).

In a composed error model (:data:`evotol.robots.base.PARTS`) the joint-space poses are the part after the
source transforms (callouts): the model keeps every joint map of the model it wraps, so a
calibration or a callout comparison finds them on it.

The parameters several definitions of this module share are described once, here.

Parameters
----------
q : dict or (n, n_variables) array_like
    Joint values (rad, m).
errors : (n, m, n_columns) array_like
    Source errors (m or rad).
"""
from __future__ import annotations

from typing import Mapping, Sequence

import numpy as np

from evotol.errors import ValidationError
from evotol.robots.base import RobotErrorModel, Workspace, dropped_line
from evotol.robots.mechanism.description.expressions import Expression

#: the reach of a revolute joint without limits in the joint-space box (rad): one turn each way
FREE_REVOLUTE = 2 * np.pi


class JointSpaceModel(RobotErrorModel):
    """A serial :class:`~evotol.robots.mechanism.model.error_model.MechanismModel` evaluated at joint configurations.

    Parameters
    ----------
    model : evotol.robots.mechanism.model.error_model.MechanismModel
        The serial arm (no loops).
    span : (n_variables, 2) array_like or None, optional
        Range of each joint variable for the box (rad or m) where the description has no limit;
        None: one turn each way for a revolute joint, ±1 m for a prismatic one.
    where : str, optional
        The field named in errors (default ``"poses.joints"``).

    Raises
    ------
    evotol.errors.ValidationError
        A model that is not a mechanism description, or one with closed loops.
    """

    part = "joint_space"
    joint_maps = True

    def __init__(self, model, span=None, where: str = "poses.joints"):
        if not isinstance(model, RobotErrorModel) or not model.joint_maps:
            raise ValidationError(where, getattr(model, "name", model), "a mechanism description "
                                  "(robot.mechanism or robot.urdf): joint configurations need its joint variables")
        mech, kin = model.mechanism, model.kin
        self._span, self._where = span, where
        if mech.loops:
            raise ValidationError(where, mech.name, "a serial arm: with closed loops the passive joints are "
                                  "not free (give tool poses: grid, latin_hypercube or list)")
        self.base = model
        self.name = model.name
        self.sources = model.sources
        self.variables = tuple(kin.variables)
        units = tuple(kin.joint_unit.get(v, "rad") for v in self.variables)
        low, high = [], []
        for i, (v, u) in enumerate(zip(self.variables, units)):
            if v in mech.limits:
                lo, hi = mech.limits[v]
            elif span is not None:
                lo, hi = (float(x) for x in np.asarray(span, float)[i])
            else:
                lo, hi = (-FREE_REVOLUTE, FREE_REVOLUTE) if u == "rad" else (-1.0, 1.0)
            low.append(float(lo))
            high.append(float(hi))
        self.workspace = Workspace(names=self.variables, low=tuple(low), high=tuple(high), units=units,
                                   display_units=tuple("deg" if u == "rad" else "mm" for u in units),
                                   display_scale=tuple(180 / np.pi if u == "rad" else 1e3 for u in units))

    def rebuilt(self, inner) -> "JointSpaceModel":
        """The same joint-space poses on another model of the arm (e.g. its callouts under boxes).

        Returns
        -------
        JointSpaceModel
            ``inner`` evaluated at joint configurations.
        """
        return JointSpaceModel(inner, self._span, self._where)

    @property
    def kin(self):
        """The arm's kinematics (:class:`evotol.robots.mechanism.kinematics.tree.Kinematics`)."""
        return self.base.kin

    @property
    def mechanism(self):
        """The arm's description (:class:`evotol.robots.mechanism.description.mechanism.Mechanism`)."""
        return self.base.mechanism

    def joint_values(self, poses) -> dict:
        """The joint values of joint-space poses: the poses themselves, by joint variable.

        Parameters
        ----------
        poses : (n, n_variables) array_like
            Joint values in the mechanism's joint order (rad, m).

        Returns
        -------
        dict
            Joint variable -> (n,) values (rad, m).
        """
        Q = self.check_poses(poses)
        return {v: Q[:, i] for i, v in enumerate(self.variables)}

    def sensitivity_at_joints(self, q) -> np.ndarray:
        """The arm's first-order map at joint values (its base model's).

        Returns
        -------
        (n, 6, n_columns) ndarray
            End-effector error twist per unit of each source column.
        """
        return self.base.sensitivity_at_joints(q)

    def pose_error_at_joints(self, q, errors) -> np.ndarray:
        """The arm's nonlinear error at joint values (its base model's).

        Returns
        -------
        (n, m, 6) ndarray
            ``[dp (m); rotation vector (rad)]`` of the end-effector.
        """
        return self.base.pose_error_at_joints(q, errors)

    def sensitivity(self, poses) -> np.ndarray:
        """First-order map (n, 6, n_columns) at joint configurations (no inverse geometry).

        Parameters
        ----------
        poses : (n, n_variables) array_like
            Joint values in the mechanism's joint order (rad, or m for a prismatic joint).

        Returns
        -------
        (n, 6, n_columns) ndarray
            End-effector error twist ``[dp (m); dphi (rad)]`` per unit of each source, base frame.

        Raises
        ------
        evotol.errors.ValidationError
            Poses of the wrong shape or not finite.
        evotol.errors.KinematicsError
            A configuration outside the joint box (the limits).
        """
        return self.base.sensitivity_at_joints(self.check_poses(poses))

    def pose_error(self, poses, errors) -> np.ndarray:
        """Nonlinear end-effector error (n, m, 6) at joint configurations for source errors (n, m, n_columns).

        Parameters
        ----------
        poses : (n, n_variables) array_like
            Joint values (rad, m).
        errors : (n, m, n_columns) array_like
            Source errors (m or rad).

        Returns
        -------
        (n, m, 6) ndarray
            ``[dp (m); rotation vector (rad)]`` of the end-effector relative to the nominal.

        Raises
        ------
        evotol.errors.ValidationError
            Poses or errors of the wrong shape.
        evotol.errors.KinematicsError
            A configuration outside the joint box.
        """
        return self.base.pose_error_at_joints(self.check_poses(poses), errors)

    def clearance_mechanism(self):
        """Refused: the clearance engine solves the mechanism at task poses, not at joint configurations.

        Raises
        ------
        evotol.errors.ValidationError
            Always, in one line naming ``[clearances]`` and ``[poses] joints``.
        """
        raise ValidationError("clearances", self.name, "a robot with joint clearances posed by task poses: the "
                              "clearance engine solves the mechanism at task poses, and [poses] joints gives joint "
                              "configurations (docs/combinations.md)")

    def tool_pose(self, poses) -> np.ndarray:
        """The nominal end-effector transform at joint configurations (forward kinematics).

        Parameters
        ----------
        poses : (n, n_variables) array_like
            Joint values (rad, m).

        Returns
        -------
        (n, 4, 4) ndarray
            Homogeneous transform of the end-effector in the base frame (position in m).
        """
        Q = np.atleast_2d(np.asarray(poses, float))
        kin = self.base.kin
        st = kin.state({v: Q[:, i] for i, v in enumerate(self.variables)}, len(Q), twists=False)
        return np.array(st.world[self.base.mechanism.end_effector])

    def notes(self) -> list[str]:
        """What a report should say about these poses.

        Returns
        -------
        list of str
            The poses are joint configurations, held exactly (no inverse geometry: the arm's posture and
            redundancy notes do not apply); and the configurations dropped as unreachable, if any.
        """
        dropped = self.described.dropped_poses
        return [f"Poses are joint configurations ({', '.join(self.variables)}): the requirement holds at exactly "
                "these configurations; no inverse geometry is solved."] + ([dropped_line(dropped)] if dropped else [])


def _value(raw, where: str, unit: str) -> float:
    if isinstance(raw, bool) or not isinstance(raw, (int, float, str)):
        raise ValidationError(where, raw, "a number (SI: rad or m) or an expression such as '30*deg'")
    e = Expression.parse(raw, where)
    if not e.is_constant:
        raise ValidationError(where, raw, f"a constant (names {sorted(e.names)} are not known here)")
    v = float(e({}))
    if unit == "rad" and not isinstance(raw, str) and abs(v) > 2 * np.pi:
        raise ValidationError(where, raw, f"an angle in radians within ±2π, or written with its unit: did you mean '{raw}*deg'?")
    return v


def joint_configurations(model, joints, where: str = "poses.joints") -> tuple[JointSpaceModel, np.ndarray]:
    """Joint configurations as a study file writes them, checked, and the model that takes them.

    Parameters
    ----------
    model : evotol.robots.mechanism.model.error_model.MechanismModel
        A serial arm.
    joints : sequence of sequence or sequence of Mapping
        One entry per configuration: the joint values in the mechanism's joint order, or a table
        joint variable -> value; each value a number (SI: rad or m) or an expression
        (``"30*deg"``, ``"250*mm"``).
    where : str, optional
        The field named in errors.

    Returns
    -------
    model : JointSpaceModel
        The error model whose poses are joint configurations.
    poses : (n, n_variables) ndarray
        The configurations (rad, m), in the mechanism's joint order.

    Raises
    ------
    evotol.errors.ValidationError
        No configuration, the wrong number of values, an unknown or missing joint name, a value
        that is not a constant (or a plain number beyond 2π for a revolute joint), a value outside
        the joint's limits, or a mechanism with closed loops (names the configuration and joint).
    """
    jm = JointSpaceModel(model, where=where)
    names, units = jm.variables, jm.workspace.units
    if not isinstance(joints, Sequence) or isinstance(joints, str) or not joints:
        raise ValidationError(where, joints, f"a list of joint configurations, each [{', '.join(names)}] or a table by name")
    rows = []
    for k, cfg in enumerate(joints):
        w = f"{where}[{k}]"
        if isinstance(cfg, Mapping):
            unknown = [n for n in cfg if n not in names]
            if unknown:
                raise ValidationError(f"{w}.{unknown[0]}", cfg[unknown[0]], f"a joint variable of {jm.name}: {list(names)}")
            missing = [n for n in names if n not in cfg]
            if missing:
                raise ValidationError(w, dict(cfg), f"a value for every joint {list(names)}; missing {missing}")
            vals = [cfg[n] for n in names]
        elif isinstance(cfg, Sequence) and not isinstance(cfg, str):
            if len(cfg) != len(names):
                raise ValidationError(w, list(cfg), f"{len(names)} joint values, one per joint {list(names)} (got {len(cfg)})")
            vals = list(cfg)
        else:
            raise ValidationError(w, cfg, f"a list of {len(names)} joint values or a table by joint name")
        rows.append([_value(v, f"{w}.{n}", u) for v, n, u in zip(vals, names, units)])
    Q = np.array(rows, float)
    limits = model.mechanism.limits
    for i, n in enumerate(names):
        if n not in limits:
            continue
        lo, hi = limits[n]
        bad = np.flatnonzero((Q[:, i] < lo - 1e-12) | (Q[:, i] > hi + 1e-12))
        if bad.size:
            k = int(bad[0])
            scale, unit = (180 / np.pi, "deg") if units[i] == "rad" else (1e3, "mm")
            raise ValidationError(f"{where}[{k}].{n}", f"{Q[k, i] * scale:.6g} {unit}",
                                  f"a value inside the joint limits [{lo * scale:.6g}, {hi * scale:.6g}] {unit}")
    # joints without limits: the box reaches at least one turn (or ±1 m) and every value given
    span = np.array([[min(lo, Q[:, i].min()), max(hi, Q[:, i].max())]
                     for i, (lo, hi) in enumerate(zip(jm.workspace.low, jm.workspace.high))])
    return JointSpaceModel(model, span=span), Q
