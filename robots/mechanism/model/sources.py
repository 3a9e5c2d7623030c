"""The error sources of a described mechanism: which toleranced names it has, and what each one moves.

Sources (intervals) are generated from the description by name or pattern
(:meth:`Mechanism.select_sources <evotol.robots.mechanism.description.mechanism.Mechanism.select_sources>`): a
**design parameter** of ``[lengths]``/``[angles]`` (its error enters every DH entry that uses it --
one shared tolerance, e.g. ``L0`` moves both base joints of the 5-bar), an **actuator offset** (an
actuated joint variable), a **DH entry** ``"<frame>.<gamma|b|alpha|d|theta|r>"`` (``"A.theta"`` of
an actuated frame is the actuator offset / encoder error), or a **placement error**
``"<frame>.<shift|tilt>_<x|y|z>"`` (:mod:`evotol.robots.mechanism.kinematics.placement`). Each becomes a column of
the first-order maps (:meth:`Kinematics.frame_jacobian
<evotol.robots.mechanism.kinematics.tree.Kinematics.frame_jacobian>`) and a :class:`evotol.robots.base.SourceSpec`
(unit, group, description) of :class:`evotol.robots.mechanism.model.error_model.MechanismModel`.
"""
from __future__ import annotations

from evotol.errors import ValidationError
from evotol.robots.base import SourceSpec
from evotol.robots.mechanism.kinematics.tree import Kinematics
from evotol.robots.mechanism.description.mechanism import Mechanism
from evotol.robots.mechanism.description.parts import LENGTH_FIELDS
from evotol.robots.mechanism.kinematics.placement import PLACEMENT_FIELDS, SHIFT_FIELDS

OUT_OF_PLANE_FIELDS = ("b", "alpha", "r")


def source_columns(mech: Mechanism, kin: Kinematics, sources=None) -> tuple[list, list[SourceSpec]]:
    """The toleranced sources of a description: their Jacobian columns and their specs.

    Parameters
    ----------
    mech : evotol.robots.mechanism.description.mechanism.Mechanism
        The description.
    kin : evotol.robots.mechanism.kinematics.tree.Kinematics
        Its kinematics (joint variables, actuated ones, which DH entries use each name).
    sources : sequence of str or None, optional
        Source names/patterns (default: the description's ``[tolerances] sources``, else every
        design parameter and every actuator offset).

    Returns
    -------
    columns : list of str or (str, str)
        Per source, in order: the name (a design parameter or an actuated joint variable) or the
        DH entry / placement error ``(frame, field)``.
    specs : list of evotol.robots.base.SourceSpec
        Per source: name, unit (m or rad), group (``"actuator"``, ``"length"``, ``"angle"``) and a
        one-line description.

    Raises
    ------
    evotol.errors.ValidationError
        A pattern that matches nothing, no toleranced source, a parameter no DH entry uses, or
        in a planar mechanism an out-of-plane parameter or entry or a placement error.
    """
    act = kin.actuated
    if sources is None and not mech.sources:
        names = list(mech.parameters) + act
    else:
        names = mech.select_sources(sources, act)
    if not names:
        raise ValidationError(f"{mech.name} sources", names, "at least one toleranced parameter or DH entry")
    columns, specs = [], []
    frames = mech.frame
    for alias in names:
        nm = mech.aliases.get(alias, alias)     # a standard-DH base/tool entry: base.d -> parameter base_d
        if nm in act:
            unit = "m" if any(frames[fr].joint == "prismatic" for fr, k in kin.uses[nm]) else "rad"
            columns.append(nm)
            specs.append(SourceSpec(nm, 1, unit, "actuator", f"actuator offset / encoder error of joint variable {nm}"))
        elif nm in mech.parameters:
            unit = "m" if nm in mech.lengths else "rad"
            fields = {k for fr, k in kin.uses.get(nm, ())}
            if not fields:
                raise ValidationError(f"{mech.name} source", nm, "a parameter used by at least one DH entry")
            if mech.planar and fields & set(OUT_OF_PLANE_FIELDS):
                raise ValidationError(f"{mech.name} source", nm, "a parameter of in-plane entries only (gamma, d, theta) "
                                                                 "in a planar mechanism")
            columns.append(nm)
            specs.append(SourceSpec(alias, 1, unit, "length" if unit == "m" else "angle", f"design parameter {alias}"))
        elif nm.split(".")[1] in PLACEMENT_FIELDS:
            fr, k = nm.split(".")
            if mech.planar:
                raise ValidationError(f"{mech.name} source", nm, "a parameter or DH entry (placement errors are 3-D; "
                                                                 "in a planar mechanism use the in-plane entries gamma, d, theta)")
            unit = "m" if k in SHIFT_FIELDS else "rad"
            columns.append((fr, k))
            specs.append(SourceSpec(nm, 1, unit, "length" if unit == "m" else "angle",
                                    f"placement error of frame {fr}: {'translation along' if unit == 'm' else 'rotation about'} its {k[-1]} axis"))
        else:
            fr, k = nm.split(".")
            if mech.planar and k in OUT_OF_PLANE_FIELDS:
                raise ValidationError(f"{mech.name} source", nm, "an in-plane entry (gamma, d, theta) in a planar "
                                                                 "mechanism: out-of-plane errors open its over-constrained loops")
            unit = "m" if k in LENGTH_FIELDS else "rad"
            f = frames[fr]
            group = "actuator" if f.actuated and k == f.joint_field else ("length" if unit == "m" else "angle")
            columns.append((fr, k))
            specs.append(SourceSpec(nm, 1, unit, group, f"{'actuator offset of' if group == 'actuator' else k + ' of'} frame {fr}"))
    return columns, specs
