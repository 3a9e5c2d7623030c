"""A described mechanism's joint clearances as a clearance model for the certified engine (Deng 2012 Ch. III-V).

The ``[clearance]`` table of a description (:class:`evotol.robots.mechanism.description.parts.ClearanceSpec`: bodies,
chains of joints with clearance, bounds) becomes a :class:`evotol.robots.clearance.model.ClearanceMechanism`
whose DH tree is the description's and whose joint values come from the Newton inverse geometry
(:mod:`evotol.robots.mechanism.posture.inverse_geometry`); ``evotol.robots.clearance.max_pose_error`` computes its
certified largest end-effector error. :meth:`evotol.robots.mechanism.model.error_model.MechanismModel.clearance_mechanism`
calls it.
"""
from __future__ import annotations

from typing import Sequence

import numpy as np

from evotol.errors import ValidationError
from evotol.robots.clearance.kinematics import DH_FIELDS, DHFrame, DHTree
from evotol.robots.clearance.model import ClearanceMechanism, Joint
from evotol.robots.mechanism.kinematics.tree import Kinematics
from evotol.robots.mechanism.description.mechanism import Mechanism


def clearance_mechanism(mech: Mechanism, kin: Kinematics, name: str, pose_names: Sequence[str]) -> ClearanceMechanism:
    """The description's joint clearances as a :class:`ClearanceMechanism
    <evotol.robots.clearance.model.ClearanceMechanism>` (Deng 2012 Ch. III-V); joint values come from the
    Newton inverse geometry.

    DH entries that use a joint variable become named variables ``"<frame>.<field>"`` of the
    clearance tree; the others are evaluated with the nominal parameters. A joint's bounds are
    those under its frame name, else under ``actuated``/``passive``, else ``default``.

    Parameters
    ----------
    mech : evotol.robots.mechanism.description.mechanism.Mechanism
        The description, with its ``[clearance]`` table.
    kin : evotol.robots.mechanism.kinematics.tree.Kinematics
        Its kinematics (parsed DH entries, joint variables, inverse geometry).
    name : str
        Name of the clearance model (the error model's name).
    pose_names : sequence of str
        Names of the workspace coordinates (SI: m, rad).

    Returns
    -------
    evotol.robots.clearance.model.ClearanceMechanism
        The clearance model (bounds: ``beta_xy``, ``beta_z`` in rad, ``b_xy``, ``b_z`` in m).

    Raises
    ------
    evotol.errors.ValidationError
        No ``[clearance]`` table, a chain joint that is not a revolute or prismatic frame, or a
        joint without bounds.
    """
    spec = mech.clearance
    if spec is None:
        raise ValidationError(f"{name} clearance", None, "a [clearance] table in the description")
    rows = []
    variable_entries = []
    for f in mech.frames:
        kw = {}
        for k in DH_FIELDS:
            e = kin.expr[(f.name, k)]
            if e.is_constant or not (e.names & set(kin.variables)):
                kw[k] = float(np.real(e(mech.parameters)))
            else:
                kw[k] = f"{f.name}.{k}"
                variable_entries.append((f.name, k))
        rows.append(DHFrame(f.name, f.antecedent, sigma=f.sigma, mu=int(f.actuated), **kw))
    tree = DHTree(rows)

    def joint_values(poses):
        poses = np.atleast_2d(np.asarray(poses, float))
        q = kin.inverse_geometry(poses)
        env = kin.env(q, len(poses))
        return {f"{fr}.{k}": np.broadcast_to(np.real(kin.expr[(fr, k)](env)), (len(poses),)) for fr, k in variable_entries}

    frames = mech.frame
    names = []
    for ch in spec.chains:
        for j in ch.joints:
            if j not in frames or frames[j].joint == "fixed":
                raise ValidationError(f"clearance chain {ch.name!r} joint", j, "a revolute or prismatic frame")
            if j not in names:
                names.append(j)
    joints = []
    for j in names:
        f = frames[j]
        b = spec.bounds.get(j) or spec.bounds.get("actuated" if f.actuated else "passive") or spec.bounds.get("default")
        if b is None:
            raise ValidationError(f"clearance.bounds.{j}", None, "bounds for the joint (or 'actuated'/'passive'/'default')")
        joints.append(Joint(j, j, f.actuated, b))
    chains = list(spec.chains)
    return ClearanceMechanism(name=name, tree=tree, joints=joints, bodies=dict(spec.bodies), chains=chains,
                              end_effector=spec.end_effector, joint_values=joint_values, planar=mech.planar,
                              pose_names=pose_names)
