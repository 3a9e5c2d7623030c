"""Per-axis requirements: ``|δx| <= Lx``, ``|δy| <= Ly``, ``|δz| <= Lz`` (and per orientation component),
in the base or the tool frame, as an error model every measure and allocator already handles.

A designer often states accuracy per axis ("0.5 mm in x, y and z each"), not as the norm of the
position error. The norm requirement is stricter (a corner of the box is sqrt(3) times farther)
and so costs more (9.8 % on issue 33's PUMA). :class:`AxisErrorModel` wraps the robot so that
each *pose* of the problem is one (configuration, axis) pair: its position error is the scalar
error along that axis, in row 2 (z) of the error twist and nowhere else, scaled by ``L_ref / L_a``
where ``L_ref`` is the smallest limit of the component; the problem's requirement is then the norm
bound ``L_ref`` (:func:`axis_requirement`). Why this is exact:

* the worst case of a single row over a box of interval sources is ``Σ_j |J_a,j| t_j`` (linear in
  t), and :func:`evotol.measures.linear.directions_for` gives a one-row block the single direction z
  with covering angle 0, so the worst-case measure, the certified optimum and its lower bound
  are exact here (no direction grid, nothing to refine);
* RSS is ``sqrt(Σ_j (J_a,j t_j)^2)`` per axis; the yield measure gives ``P(|δ_a| <= L_a)`` per axis
  and pose (per axis, not jointly over the axes: documented in ``docs/mechanisms.md``);
* ``frame = "tool"``: the error is first rotated into the nominal tool frame at that pose,
  ``δ_tool = R^T δ`` (R the end-effector's nominal orientation), so the limits follow the tool.

A component given as a plain number stays the norm (rows 0-2 or 3-5 unchanged, repeated at every
axis slot). Values reported per pose are ``|δ_a| L_ref / L_a``: equal to the axis error when the
limits are equal; :func:`axis_errors` gives the errors in each axis's own unit and limit.

The parameters several definitions of this module share are described once, here.

Parameters
----------
component : {"position", "orientation"}
    The error component.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Mapping

import numpy as np

from evotol.errors import ValidationError
from evotol.robots.base import RobotErrorModel, Workspace
from evotol.robots.mechanism.description.expressions import Expression

AXES = ("x", "y", "z")
FRAMES = ("base", "tool")
#: the row of the error twist that carries one axis's scaled error (position z / orientation z)
ROW = {"position": 2, "orientation": 5}
#: keys of ``[requirement]`` this module reads besides :class:`evotol.core.requirement.Requirement`'s
AXIS_KEYS = ("frame",)


def _limit(raw, where: str) -> float:
    if isinstance(raw, bool) or not isinstance(raw, (int, float, str)):
        raise ValidationError(where, raw, "a positive limit (SI: m or rad) or an expression such as '0.5*mm'")
    e = Expression.parse(raw, where)
    if not e.is_constant:
        raise ValidationError(where, raw, f"a constant (names {sorted(e.names)} are not known here)")
    v = float(e({}))
    if not (np.isfinite(v) and v > 0):
        raise ValidationError(where, raw, "a positive limit (m for position, rad for orientation)")
    return v


@dataclass(frozen=True)
class AxisLimits:
    """Per-axis limits of the position and/or orientation error.

    Parameters
    ----------
    position : Mapping[str, float], optional
        Axis (``x``, ``y``, ``z``) -> limit on ``|δp_axis|`` (m); empty: not per axis.
    orientation : Mapping[str, float], optional
        Axis -> limit on ``|δθ_axis|`` (rad); empty: not per axis.
    frame : {"base", "tool"}, optional
        The frame the axes are those of (default the base frame).

    Raises
    ------
    evotol.errors.ValidationError
        An axis other than x, y, z, a limit that is not positive, another frame, or no axis at all.
    """

    position: Mapping[str, float] = field(default_factory=dict)
    orientation: Mapping[str, float] = field(default_factory=dict)
    frame: str = "base"

    def __post_init__(self):
        if self.frame not in FRAMES:
            raise ValidationError("requirement.frame", self.frame, "'base' (default) or 'tool': the frame of the axes")
        if not self.position and not self.orientation:
            raise ValidationError("requirement", {}, "a per-axis limit, e.g. position = { x = '0.5*mm', y = '0.5*mm' }")
        for comp in ("position", "orientation"):
            for ax, v in getattr(self, comp).items():
                if ax not in AXES:
                    raise ValidationError(f"requirement.{comp}.{ax}", v, f"an axis x, y or z (the {comp} error has no axis {ax!r})")
                if isinstance(v, bool) or not isinstance(v, (int, float)) or not (np.isfinite(v) and v > 0):
                    raise ValidationError(f"requirement.{comp}.{ax}", v, "a positive limit (m or rad)")

    def axes(self, component: str) -> tuple[str, ...]:
        """The axes limited for ``component`` (``"position"`` or ``"orientation"``), in x, y, z order.

        Returns
        -------
        tuple of str
            The limited axes.
        """
        return tuple(a for a in AXES if a in getattr(self, component))

    def reference(self, component: str) -> float | None:
        """The smallest limit of ``component`` (m or rad): the problem's norm bound; None if not per axis.

        Returns
        -------
        float or None
            ``min_a L_a``, or None.
        """
        lims = getattr(self, component)
        return float(min(lims.values())) if lims else None


def tool_rotation(robot, poses) -> np.ndarray:
    """The nominal end-effector orientation R (n, 3, 3) at the robot's poses (for ``frame = "tool"``).

    Parameters
    ----------
    robot : evotol.robots.base.RobotErrorModel
        A mechanism description (:class:`evotol.robots.mechanism.model.error_model.MechanismModel`) or its
        joint-space form (:class:`evotol.robots.mechanism.model.joint_space.JointSpaceModel`).
    poses : (n, workspace.dim) array_like
        The robot's poses (SI).

    Returns
    -------
    (n, 3, 3) ndarray
        Rotation of the end-effector frame in the base frame.

    Raises
    ------
    evotol.errors.ValidationError
        A robot whose tool orientation evotol does not know (not a mechanism description).
    """
    P = np.atleast_2d(np.asarray(poses, float))
    joints = robot.part_of("joint_space")            # poses are joint configurations: its own tool pose
    if joints is not None:
        return joints.tool_pose(P)[:, :3, :3]
    described = robot.described                      # task poses of the arm as described (parts keep them)
    if not described.joint_maps:
        raise ValidationError("requirement.frame", "tool", f"'base' for {robot.name} (the tool frame is known for a "
                                                           "mechanism description only)")
    kin, mech = described.kin, described.mechanism
    q = described.joint_values(P)
    return np.array(kin.state(q, len(P), twists=False).world[mech.end_effector][:, :3, :3])


def configurations(robot: RobotErrorModel, poses) -> tuple[RobotErrorModel, np.ndarray]:
    """The model and poses of a composition before its requirement's parts (per-axis limits, clearances).

    Parameters
    ----------
    robot : evotol.robots.base.RobotErrorModel
        A composed model (:data:`evotol.robots.base.PARTS`).
    poses : (n, workspace.dim) array_like
        Its poses (SI; with per-axis limits, one row per configuration and axis slot).

    Returns
    -------
    model : evotol.robots.base.RobotErrorModel
        The model inside the per-axis limits and the clearances.
    poses : (k, model.workspace.dim) ndarray
        Its configurations (one per configuration, SI).
    """
    model, P = robot, np.asarray(poses, float)
    while model.part in ("axis_limits", "clearances"):
        if model.part == "axis_limits":
            P = P[::model.slots, :-1]
        model = model.base
    return model, P


class AxisErrorModel(RobotErrorModel):
    """The robot seen per axis: one pose per (configuration, axis slot) (see the module docstring).

    Parameters
    ----------
    robot : evotol.robots.base.RobotErrorModel
        The robot (its poses are the configurations).
    limits : AxisLimits
        The per-axis limits and their frame.
    norm_components : collection of str, optional
        Components (``"position"``, ``"orientation"``) also constrained as a norm (a plain
        number next to a per-axis table): their rows are kept at every slot.

    Attributes
    ----------
    slots : int
        Axis slots per configuration: the largest number of limited axes of a component.
    """

    part = "axis_limits"

    def __init__(self, robot: RobotErrorModel, limits: AxisLimits, norm_components=()):
        self.base, self.limits = robot, limits
        self.norm_components = frozenset(norm_components)
        self.name, self.sources = robot.name, robot.sources
        self.slots = max(len(limits.axes("position")), len(limits.axes("orientation")))
        ws = robot.workspace
        self.workspace = Workspace(names=(*ws.names, "axis"), low=(*ws.low, 0.0), high=(*ws.high, float(self.slots - 1)),
                                   units=(*ws.units, "1"), display_units=(*ws.display_units, "1"),
                                   display_scale=(*ws.display_scale, 1.0))

    def rebuilt(self, inner: RobotErrorModel) -> "AxisErrorModel":
        """The same per-axis limits on another model of the robot.

        Returns
        -------
        AxisErrorModel
            ``inner`` seen per axis.
        """
        return AxisErrorModel(inner, self.limits, self.norm_components)

    def expand(self, poses) -> np.ndarray:
        """The problem's poses for the robot's: each configuration once per axis slot.

        Parameters
        ----------
        poses : (n, robot.workspace.dim) array_like
            The robot's poses (SI).

        Returns
        -------
        (n * slots, robot.workspace.dim + 1) ndarray
            Configuration-major: the slot index (0, 1, ...) as the last coordinate.
        """
        P = np.atleast_2d(np.asarray(poses, float))
        s = np.tile(np.arange(self.slots, dtype=float), len(P))
        return np.column_stack([np.repeat(P, self.slots, axis=0), s])

    def axis_of(self, component: str, slot: int) -> str | None:
        """The axis slot ``slot`` carries for ``component``, or None (norm, or no axis there).

        Parameters
        ----------
        slot : int
            The axis slot (last pose coordinate).

        Returns
        -------
        str or None
            ``"x"``, ``"y"``, ``"z"`` or None.
        """
        axes = self.limits.axes(component)
        return axes[slot] if axes and 0 <= slot < len(axes) else None

    @property
    def coordinate_labels(self) -> dict:
        """What each value of the ``axis`` coordinate means, for reports: ``{"axis": [label per slot]}``.

        Returns
        -------
        dict of str to list of str
            ``"x"``, ``"y"``, ``"z"`` per slot (``"position x, orientation z"`` when both
            components are per axis).
        """
        labels = []
        both = bool(self.limits.position) and bool(self.limits.orientation)
        for s in range(self.slots):
            p, o = self.axis_of("position", s), self.axis_of("orientation", s)
            if both:
                labels.append(", ".join(x for x in (p and f"position {p}", o and f"orientation {o}") if x))
            else:
                labels.append(p or o)
        return {"axis": labels}

    def _split(self, poses):
        P = self.check_poses(poses)
        return P[:, :-1], np.clip(np.rint(P[:, -1]), 0, self.slots - 1).astype(int)

    def _project(self, E: np.ndarray, base: np.ndarray, slot: np.ndarray, required) -> np.ndarray:
        """Per-axis rows of errors E (n, ..., 6, k) with the rotation into the tool frame."""
        if self.limits.frame == "tool":
            Rt = np.swapaxes(tool_rotation(self.base, base), 1, 2)          # (n, 3, 3): R^T
            extra = E.ndim - 3
            R = Rt.reshape(Rt.shape[:1] + (1,) * extra + (3, 3))
            E = np.concatenate([R @ E[..., 0:3, :], R @ E[..., 3:6, :]], axis=-2)
        out = np.zeros_like(E)
        for comp, rows in (("position", slice(0, 3)), ("orientation", slice(3, 6))):
            lims = getattr(self.limits, comp)
            if not lims:
                if comp in required:
                    out[..., rows, :] = E[..., rows, :]
                continue
            ref = self.limits.reference(comp)
            axes = self.limits.axes(comp)
            for s, ax in enumerate(axes):
                sel = slot == s
                r = rows.start + AXES.index(ax)
                out[sel, ..., ROW[comp], :] = E[sel, ..., r, :] * (ref / lims[ax])
        return out

    def sensitivity(self, poses) -> np.ndarray:
        """First-order map (n, 6, n_columns): at each (configuration, slot), the slot's axis row,
        scaled by ``L_ref / L_axis``, in row 2 (position) and row 5 (orientation).

        Parameters
        ----------
        poses : (n, robot.workspace.dim + 1) array_like
            Configurations with the axis slot as the last coordinate (:meth:`expand`).

        Returns
        -------
        (n, 6, n_columns) ndarray
            The projected, scaled sensitivities (m or rad per unit source error).

        Raises
        ------
        evotol.errors.ValidationError
            Poses of the wrong shape.
        evotol.errors.KinematicsError
            What the robot's ``sensitivity`` raises.
        """
        base, slot = self._split(poses)
        return self._project(np.asarray(self.base.sensitivity(base), float), base, slot, self.norm_components)

    def pose_error(self, poses, errors) -> np.ndarray:
        """Nonlinear errors (n, m, 6) projected and scaled as :meth:`sensitivity`.

        Parameters
        ----------
        poses : (n, robot.workspace.dim + 1) array_like
            Configurations with the axis slot.
        errors : (n, m, n_columns) array_like
            Source errors (m or rad).

        Returns
        -------
        (n, m, 6) ndarray
            The robot's nonlinear error, rotated into the tool frame if asked, axis row scaled.

        Raises
        ------
        NotImplementedError
            The robot has no nonlinear model.
        """
        base, slot = self._split(poses)
        E = np.asarray(self.base.pose_error(base, errors), float)         # (n, m, 6)
        return self._project(E[..., None], base, slot, self.norm_components)[..., 0]

    @property
    def has_nonlinear_model(self) -> bool:
        """True when the wrapped robot has a nonlinear model."""
        return self.base.has_nonlinear_model

    def notes(self) -> list[str]:
        """The statement a report carries: which axis each slot is, the limits and the frame.

        Returns
        -------
        list of str
            One line per per-axis component, plus the wrapped robot's notes.
        """
        lines = list(self.base.notes())
        for comp, unit, scale in (("position", "mm", 1e3), ("orientation", "mrad", 1e3)):
            axes = self.limits.axes(comp)
            if not axes:
                continue
            lims = getattr(self.limits, comp)
            ref = self.limits.reference(comp)
            parts = ", ".join(f"axis {s} = {a} (|δ{a}| <= {lims[a] * scale:g} {unit})" for s, a in enumerate(axes))
            lines.append(f"Per-axis {comp} requirement in the {self.limits.frame} frame: {parts}. Each pose is one "
                         f"configuration and axis; its {comp} value is |δ_axis| x {ref * scale:g} {unit} / limit_axis "
                         "(the axis error itself when the limits are equal).")
        return lines


def parse_axis_limits(table: Mapping) -> AxisLimits | None:
    """The per-axis limits of a ``[requirement]`` table, or None when both components are plain numbers.

    Parameters
    ----------
    table : Mapping
        The ``[requirement]`` table: ``position``/``orientation`` a number (the norm) or a table
        axis -> limit (SI or an expression such as ``"0.5*mm"``, ``"0.1*deg"``); ``frame``
        ``"base"`` or ``"tool"``.

    Returns
    -------
    AxisLimits or None
        The limits, or None for a norm requirement.

    Raises
    ------
    evotol.errors.ValidationError
        A ``frame`` with no per-axis limit, an axis that does not exist, a limit that is not
        positive or not a constant.
    """
    per = {c: table[c] for c in ("position", "orientation") if isinstance(table.get(c), Mapping)}
    if not per:
        if "frame" in table:
            raise ValidationError("requirement.frame", table["frame"], "nothing unless position or orientation is a table "
                                                                       "of per-axis limits (a norm has no axes)")
        return None
    vals = {}
    for comp, lims in per.items():
        bad = [a for a in lims if a not in AXES]
        if bad:
            raise ValidationError(f"requirement.{comp}.{bad[0]}", lims[bad[0]], f"an axis x, y or z (the {comp} error has "
                                                                                 f"no axis {bad[0]!r})")
        vals[comp] = {a: _limit(v, f"requirement.{comp}.{a}") for a, v in lims.items()}
        if not vals[comp]:
            raise ValidationError(f"requirement.{comp}", {}, "at least one axis limit, e.g. { z = '0.5*mm' }")
    return AxisLimits(position=vals.get("position", {}), orientation=vals.get("orientation", {}),
                      frame=table.get("frame", "base"))


def axis_requirement(robot: RobotErrorModel, poses, table: Mapping, clearances=None) -> tuple[RobotErrorModel, np.ndarray, dict]:
    """Rewrite a per-axis ``[requirement]`` as a robot, poses and norm requirement (module docstring).

    Parameters
    ----------
    robot : evotol.robots.base.RobotErrorModel
        The study's robot.
    poses : (n, robot.workspace.dim) array_like
        The study's poses (SI).
    table : Mapping
        The ``[requirement]`` table.
    clearances : object or None, optional
        The study's allocated joint clearances (``[clearances]``); per-axis limits are refused
        next to them (the certified clearance engine bounds norms).

    Returns
    -------
    robot : RobotErrorModel
        ``robot`` itself for a norm requirement, else an :class:`AxisErrorModel` around it.
    poses : ndarray
        ``poses``, or one per (configuration, axis slot).
    requirement : dict
        Keyword arguments of :class:`evotol.core.requirement.Requirement`: a per-axis component
        becomes its smallest limit; ``frame`` removed.

    Raises
    ------
    evotol.errors.ValidationError
        What :func:`parse_axis_limits` refuses, or per-axis limits next to clearances.
    """
    limits = parse_axis_limits(table)
    if limits is None:
        return robot, poses, dict(table)
    if clearances is not None:
        raise ValidationError("requirement.position", dict(table).get("position"), "a norm bound (a number) with "
                              "[clearances]: the certified clearance engine bounds the norm of the error")
    req = {k: v for k, v in table.items() if k not in AXIS_KEYS}
    model = AxisErrorModel(robot, limits, [c for c in ("position", "orientation")
                                           if req.get(c) is not None and not isinstance(req[c], Mapping)])
    for comp in ("position", "orientation"):
        if isinstance(req.get(comp), Mapping):
            req[comp] = limits.reference(comp)
    return model, model.expand(poses), req
