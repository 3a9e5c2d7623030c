"""A described mechanism whose joint seats carry drawing callouts (issue 35, ``docs/callouts.md``).

:class:`CalloutModel` is the error model of :class:`evotol.robots.mechanism.model.error_model.MechanismModel` with
each callout's zone in place of the raw placement errors it covers: the zone's member sources
(:func:`evotol.robots.mechanism.callouts.zones.zone_members`) are linear maps ``C`` onto the placement errors,
so the first-order map is ``S_base C`` and the nonlinear error is the base model's at the
placement errors ``C e`` (``placement * exp(C e)``, exact to first order; the axis lands off the
sampled zone point by a second-order ``~ t^2/L``, ``tests/test_callouts.py``). A callout with
several members (a position zone's two end discs, a box rule's four intervals) is **one
tolerance**: ``tied_sources`` names the group, which :func:`evotol.core.variables.tolerance_variables`
makes one variable costed once.

The parameters several definitions of this module share are described once, here.

Parameters
----------
q : dict or (n, n_variables) array_like
    Joint values (rad, m).
"""
from __future__ import annotations

import numpy as np

from evotol.errors import ValidationError
from evotol.robots.base import RobotErrorModel, SourceSpec, Workspace
from evotol.robots.mechanism.callouts.table import callouts_from_tables, dh_placement_fields, joint_seat
from evotol.robots.mechanism.callouts.zones import ORIENTATION_KINDS, ZONE_MODELS, Callout, replaced_fields, zone_members
from evotol.robots.mechanism.description.reader import load_mechanism
from evotol.robots.mechanism.description.mechanism import Mechanism
from evotol.robots.mechanism.model.error_model import MechanismModel
from evotol.robots.mechanism.kinematics.placement import PLACEMENT_FIELDS


def zone_per_t(robot: RobotErrorModel) -> dict:
    """Member source -> its zone per unit of its callout's value (:attr:`CalloutModel.zone_per_t`) in a
    composed model; empty without callouts.

    Parameters
    ----------
    robot : evotol.robots.base.RobotErrorModel
        A composed model (:data:`evotol.robots.base.PARTS`).

    Returns
    -------
    dict of str to float
        Source name -> zone per unit t (0.5 for a position zone's end discs and a face).
    """
    callouts = robot.part_of("callouts")
    return callouts.zone_per_t if callouts is not None else {}


class CalloutModel(RobotErrorModel):
    """A mechanism's error model with drawing callouts as sources (module docstring).

    Parameters
    ----------
    mechanism : Mechanism or str or Path
        The description or its TOML file.
    callouts : sequence of evotol.robots.mechanism.callouts.zones.Callout
        The callouts (checked by :func:`evotol.robots.mechanism.callouts.table.callouts_from_tables`).
    sources : sequence of str or None
        Raw source names/patterns as for :class:`MechanismModel`; the placement errors a callout
        covers are dropped from them.
    zones : {"exact", "boxes"}
        Exact zones (default) or the independent-box rule (the comparison of ``docs/callouts.md``).
    workspace : evotol.robots.base.Workspace or None
        Override of the description's box.

    Raises
    ------
    evotol.errors.ValidationError
        A callout on an unknown joint or a fixed frame, a raw placement source of a callout's
        joint that the callout covers only in part (list the sources explicitly), or what
        :class:`MechanismModel` refuses.
    """

    part = "callouts"
    joint_maps = True

    def __init__(self, mechanism, callouts, sources=None, zones: str = "exact", workspace: Workspace | None = None):
        mech = mechanism if isinstance(mechanism, Mechanism) else load_mechanism(mechanism)
        self.callouts = tuple(callouts)
        self.zones = zones
        self.seats = {c.joint: joint_seat(mech, c.joint) for c in self.callouts}
        by_joint: dict[str, list[Callout]] = {}
        for c in self.callouts:
            by_joint.setdefault(c.joint, []).append(c)
        members = {}
        for c in self.callouts:
            refined = c.kind == "position" and any(o.kind in ORIENTATION_KINDS for o in by_joint[c.joint])
            members[c.name] = zone_members(c, self.seats[c.joint]["axis"], refined, zones)
        #: member source -> its zone's half-width (radius) per unit of the callout's value t, where it
        #: is not t: a position zone's ends are discs of radius t/2, a face's zone is ±t/2 (the
        #: tolerance tables show the member's own zone; the drawing table states the callout's t)
        self.zone_per_t = {m.name: 0.5 for c in self.callouts for m in members[c.name]
                           if c.kind == "axial" or (c.kind == "position" and (m.name == c.name or m.name.endswith(
                               (".end1", ".end2", ".shift_e1", ".shift_e2"))))}
        raw = MechanismModel(mech, sources, workspace)
        names = list(raw.source_names)
        needed = []
        for c in self.callouts:
            rows = np.any([np.abs(m.matrix).max(axis=1) > 1e-15 for m in members[c.name]], axis=0)
            needed += [f"{c.joint}.{PLACEMENT_FIELDS[i]}" for i in np.flatnonzero(rows)]
        extra = [n for n in dict.fromkeys(needed) if n not in names]
        self.base = MechanismModel(mech, names + extra, workspace) if extra else raw
        self._build(names, members, by_joint)

    def _build(self, names, members, by_joint) -> None:
        base = self.base
        index = {n: j for j, n in enumerate(base.source_names)}
        covered = {j: replaced_fields(cs, self.seats[j]["axis"]) for j, cs in by_joint.items()}
        keep, specs, cols, tied = [], [], [], {}
        placed = set()

        def add_callouts(joint):
            for c in by_joint[joint]:
                ms = members[c.name]
                for m in ms:
                    C = np.zeros((base.n_columns, m.dim))
                    for i, f in enumerate(PLACEMENT_FIELDS):
                        if np.abs(m.matrix[i]).max() > 1e-15:
                            C[index[f"{joint}.{f}"]] = m.matrix[i]
                    cols.append(C)
                    specs.append(SourceSpec(m.name, m.dim, "m", c.kind, f"{c.text()} over {c.length * 1e3:g} mm "
                                            f"({self.zones} zone) on the seat of {joint}, datums {c.datums}"))
                if len(ms) > 1:
                    tied[c.name] = tuple(m.name for m in ms)
            placed.add(joint)

        dh = {n: (j, f) for j in by_joint for n, f in dh_placement_fields(base.mechanism, base.kin.uses, j).items()}
        for n in names:
            j, f = dh[n] if n in dh else n.split(".", 1) if "." in n else (n, "")   # a DH entry: its seat direction
            if j in by_joint and j not in placed and (f in PLACEMENT_FIELDS or n == self.seats[j]["variable"]):
                add_callouts(j)
            if j in by_joint and f in PLACEMENT_FIELDS:
                u = np.zeros(6)
                u[PLACEMENT_FIELDS.index(f)] = 1.0
                share = float(np.linalg.norm(covered[j].T @ u))
                if share > 1 - 1e-9:
                    continue                      # the callout's zone holds this direction
                if share > 1e-9:
                    raise ValidationError(f"source {n}", n, f"a placement error along or across the axis of {j} "
                                          "(its callouts cover part of it: list the sources explicitly)")
            col = np.zeros((base.n_columns, 1))
            col[index[n]] = 1.0
            cols.append(col)
            specs.append(base.sources[index[n]])
        for j in by_joint:
            if j not in placed:
                add_callouts(j)
        self.C = np.concatenate(cols, axis=1)
        self.sources = tuple(specs)
        self._ties = tied
        self.name = base.name
        self.workspace = base.workspace

    @property
    def tied_sources(self) -> dict:
        """Callout name -> its member sources (a position zone's two end discs, ...): one tolerance each."""
        return self._ties

    # --- the joint maps of the arm the callouts are drawn on (joint_maps = True), declared, not forwarded
    @property
    def mechanism(self):
        """The arm's description (:class:`evotol.robots.mechanism.description.mechanism.Mechanism`)."""
        return self.base.mechanism

    @property
    def kin(self):
        """The arm's kinematics (:class:`evotol.robots.mechanism.kinematics.tree.Kinematics`)."""
        return self.base.kin

    @property
    def redundancy(self) -> dict | None:
        """The arm's redundancy (:attr:`MechanismModel.redundancy
        <evotol.robots.mechanism.model.error_model.MechanismModel.redundancy>`): callouts do not change it."""
        return self.base.redundancy

    def joint_values(self, poses) -> dict:
        """All joint variables at task poses (SI): the arm's inverse geometry (callouts do not move nominal joints).

        Returns
        -------
        dict of str to (n,) ndarray
            Every joint variable (rad, or m for a prismatic joint).
        """
        return self.base.joint_values(poses)

    def closure_residual(self, poses=None) -> float:
        """The arm's loop-closure residual (m) at poses (:meth:`MechanismModel.closure_residual
        <evotol.robots.mechanism.model.error_model.MechanismModel.closure_residual>`).

        Returns
        -------
        float
            The largest residual (m).
        """
        return self.base.closure_residual(poses)

    def with_zones(self, zones: str) -> "CalloutModel":
        """The same mechanism and callouts under another zone model (``"exact"`` or ``"boxes"``).

        Returns
        -------
        CalloutModel
            A new model (the base model is rebuilt only if it lacks a placement error).
        """
        raw = [s.name for s in self.sources if s.group not in {c.kind for c in self.callouts}]
        return CalloutModel(self.base.mechanism, self.callouts, raw, zones, self.base.workspace)

    def callout_of(self, source: str) -> Callout | None:
        """The callout a member source belongs to (None for a raw source).

        Parameters
        ----------
        source : str
            A source name.

        Returns
        -------
        Callout or None
            Its callout.
        """
        for c in self.callouts:
            if source == c.name or source.startswith(c.name + "."):
                return c
        return None

    def sensitivity(self, poses) -> np.ndarray:
        """First-order map (n, 6, n_columns) ``S_base C`` (module docstring).

        Parameters
        ----------
        poses : (n, n_coordinates) array_like
            Workspace poses (SI).

        Returns
        -------
        (n, 6, n_columns) ndarray
            End-effector error twist per unit of each source column (m or rad per m or rad).

        Raises
        ------
        evotol.errors.ValidationError
            Bad poses.
        evotol.errors.KinematicsError
            A pose out of reach or singular.
        """
        return self.base.sensitivity(poses) @ self.C

    def sensitivity_at_joints(self, q) -> np.ndarray:
        """:meth:`MechanismModel.sensitivity_at_joints` times ``C``.

        Returns
        -------
        (n, 6, n_columns) ndarray
            End-effector error twist per unit of each source column.
        """
        return self.base.sensitivity_at_joints(q) @ self.C

    def _base_errors(self, errors) -> np.ndarray:
        errors = np.asarray(errors, float)
        if errors.ndim != 3 or errors.shape[2] != self.n_columns:
            raise ValidationError("errors shape", errors.shape, f"(n, n_samples, {self.n_columns})")
        return errors @ self.C.T

    def pose_error(self, poses, errors) -> np.ndarray:
        """Nonlinear end-effector error (n, m, 6): the base model's at placement errors ``C e``.

        Parameters
        ----------
        poses : (n, n_coordinates) array_like
            Workspace poses (SI).
        errors : (n, m, n_columns) array_like
            Source errors (m or rad).

        Returns
        -------
        (n, m, 6) ndarray
            ``[dp (m); rotation vector (rad)]`` of the end-effector frame.

        Raises
        ------
        evotol.errors.ValidationError
            Bad poses or errors shape.
        """
        return self.base.pose_error(poses, self._base_errors(errors))

    def pose_error_at_joints(self, q, errors) -> np.ndarray:
        """:meth:`pose_error` at given joint values (no inverse geometry).

        Parameters
        ----------
        errors : (n, m, n_columns) array_like
            Source errors (m or rad).

        Returns
        -------
        (n, m, 6) ndarray
            ``[dp (m); rotation vector (rad)]`` of the end-effector frame.

        Raises
        ------
        evotol.errors.ValidationError
            Bad joint values or errors shape.
        """
        return self.base.pose_error_at_joints(q, self._base_errors(errors))

    def describe_callouts(self) -> list[dict]:
        """The callouts as understood, for ``evotol check-mechanism`` and the drawing table.

        Returns
        -------
        list of dict
            Per callout: ``name``, ``joint``, ``part``, ``kind``, ``symbol``, ``length`` (m),
            ``offset`` (m), ``ends`` (m, m), ``datums``, ``axis`` (list, placement frame),
            ``members`` (source names), ``zones``.
        """
        out = []
        for c in self.callouts:
            seat = self.seats[c.joint]
            out.append({"name": c.name, "joint": c.joint, "part": seat["part"], "kind": c.kind, "symbol": c.symbol,
                        "length": c.length, "offset": c.offset, "ends": list(c.ends), "datums": c.datums,
                        "axis": [round(float(v), 12) + 0.0 for v in seat["axis"]], "zones": self.zones,
                        "members": list(self.tied_sources.get(c.name, (c.name,))),
                        "joint_type": seat["joint"]})
        return out


def with_callouts(model: MechanismModel, entries=None, zones: str = "exact", sources=None):
    """A model with the drawing callouts of its description or of a study's ``[[robot.callouts]]``.

    Parameters
    ----------
    model : evotol.robots.mechanism.model.error_model.MechanismModel
        The model of the description (its ``[[callouts]]``, if any, are in ``mechanism.callouts``).
    entries : list of dict or None, optional
        A study file's ``[[robot.callouts]]`` tables (:mod:`evotol.robots.mechanism.callouts.table`); when
        given they replace the description's callouts.
    sources : sequence of str or None, optional
        Raw source names/patterns, as given to the model.

    Returns
    -------
    MechanismModel or CalloutModel
        ``model`` itself when there is no callout, else the :class:`CalloutModel`.

    Raises
    ------
    evotol.errors.ValidationError
        A bad callout or ``zones``.
    """
    if zones not in ZONE_MODELS:
        raise ValidationError("robot.zones", zones, f"one of {ZONE_MODELS}")
    mech = model.mechanism
    callouts = callouts_from_tables(entries, mech) if entries is not None else list(mech.callouts)
    if not callouts:
        return model
    return CalloutModel(mech, callouts, sources, zones, model.workspace)
