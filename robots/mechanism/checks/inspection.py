"""What ``evotol check-mechanism`` shows about the error model of a described arm (issue 23 item 6):
the sources with their nominal values, the workspace box and the joint limits, and the rank of
the sources' sensitivities stacked over the workspace with the blind and duplicated directions
(:mod:`evotol.robots.mechanism.model.identifiability`); for a URDF, the same against Pinocchio's placement
regressor. :func:`evotol.robots.mechanism.urdf.check.check_urdf_file` checks a bare URDF (``evotol check-mechanism
arm.urdf --tip tool0``) with these parts.
"""
from __future__ import annotations

from evotol.robots.mechanism.model.identifiability import analyse
from evotol.robots.mechanism.kinematics.placement import PLACEMENT_FIELDS


def sources_with_nominal(model) -> list[dict]:
    """Each source: name, group, unit, description and nominal value (a design parameter's value;
    0 for a placement error, a DH-entry offset or a joint offset, which are errors about the nominal).

    Returns
    -------
    list of dict
        One ``{"name", "group", "unit", "description", "nominal"}`` per source, in source order;
        ``unit`` is ``"m"`` or ``"rad"``, or ``"1"`` for a URDF mimic joint's ``J_multiplier``
        (a ratio); ``nominal`` in that unit.
    """
    params = model.mechanism.parameters
    mimic = {f"{j}_multiplier" for j in _mimic_joints(model)}
    return [{"name": s.name, "group": s.group, "unit": "1" if s.name in mimic else s.unit, "description": s.description
             + (" (a ratio: joint per unit of its leader; the model files it with the angles)" if s.name in mimic else ""),
             "nominal": float(params.get(s.name, 0.0))} for s in model.sources]


def _mimic_joints(model) -> list[str]:
    """Mimic joints of a URDF description (their ``J_multiplier`` parameters are ratios)."""
    if not model.mechanism.urdf:
        return []
    from evotol.robots.mechanism.urdf.reader import urdf_joints, _ident

    return [_ident(n) for n, w in urdf_joints(model.mechanism.urdf[0]).items() if w["mimic"]]


def limits_and_box(model) -> dict:
    """The workspace box (coordinates, SI) and the joint limits (rad or m; none: unlimited).

    Returns
    -------
    dict
        ``"workspace"``: a list of ``{name, unit, low, high}`` per pose coordinate (SI);
        ``"limits"``: a list of ``{name, unit, lower, upper}`` per joint variable (rad or m;
        ``None`` for an unlimited joint).
    """
    ws = model.workspace
    lim = model.mechanism.limits
    return {"workspace": [{"name": n, "unit": u, "low": float(lo), "high": float(hi)}
                          for n, u, lo, hi in zip(ws.names, ws.units, ws.low, ws.high)],
            "limits": [{"name": v, "unit": model.kin.joint_unit.get(v, "rad"), "lower": lim[v][0] if v in lim else None,
                        "upper": lim[v][1] if v in lim else None} for v in model.kin.variables]}


def rank_report(model, q: dict, where: str) -> dict:
    """Rank, blind and duplicated sources over the configurations ``q``; for a URDF arm also the
    rank of Pinocchio's placement regressor of the chain there and of both together.

    Parameters
    ----------
    q : dict of str to (n,) ndarray
        Every joint variable -> its values (rad or m) at ``n`` configurations.
    where : str
        What the configurations are (copied to ``"over"``), e.g. ``"20 Latin-hypercube poses"``.

    Returns
    -------
    dict
        ``"over"``, ``"n_configurations"`` and the result of
        :func:`evotol.robots.mechanism.model.identifiability.analyse` (``rank``, ``blind``, ``duplicated``,
        ``dependent``...); for a URDF arm also ``pinocchio_rank``, ``combined_rank``,
        ``rank_without_multipliers``, ``missing`` (placement directions no source reproduces)
        and ``pinocchio_reference``.
    """
    S = model.sensitivity_at_joints(q)
    # one name per column: a disk source (a callout's zone, issue 35) has two, "<name>[0]", "<name>[1]"
    columns = [s.name if s.dim == 1 else f"{s.name}[{k}]" for s in model.sources for k in range(s.dim)]
    out = {"over": where, "n_configurations": int(len(next(iter(q.values())))), **analyse(S, columns)}
    if model.mechanism.urdf:
        from evotol.robots.mechanism.urdf.reader import chain_joints, pinocchio_configuration, pinocchio_placement_regressor, urdf_frames

        info = urdf_frames(*model.mechanism.urdf)[3]
        mdl, fid = info["model"], info["tip_frame_id"]
        cols = [6 * (j - 1) + c for j in chain_joints(mdl, fid) for c in range(6)]
        R = pinocchio_placement_regressor(mdl, fid, pinocchio_configuration(mdl, q, info["mimic"]))[:, :, cols]
        own = [i for i, s in enumerate(columns) if not s.endswith("_multiplier")]
        names = [f"{mdl.names[j]}.{f}" for j in chain_joints(mdl, fid) for f in PLACEMENT_FIELDS]
        ref = analyse(S[:, :, own], [columns[i] for i in own], R, names)
        out["pinocchio_rank"], out["combined_rank"] = ref["reference_rank"], ref["combined_rank"]
        out["rank_without_multipliers"] = ref["rank"]      # the columns Pinocchio's placement regressor can hold
        out["missing"] = ref["missing"]       # placement directions of the chain that no source reproduces
        out["pinocchio_reference"] = "computeFrameKinematicRegressor (LOCAL_WORLD_ALIGNED) of the chain's joints"
    return out


def model_report(model, poses) -> dict:
    """The sources with nominal values, box and limits, and the rank over the workspace ``poses``
    (joint values from the inverse geometry), for :func:`evotol.robots.mechanism.checks.description.check_mechanism`.

    Parameters
    ----------
    poses : (n, n_coordinates) ndarray
        Workspace poses (SI: m, rad), e.g. Latin-hypercube ones.

    Returns
    -------
    dict
        ``"sources"`` (:func:`sources_with_nominal`), ``"workspace"`` and ``"limits"``
        (:func:`limits_and_box`), ``"urdf"`` (the description's URDF path and tip, or empty),
        ``"redundancy"`` (:attr:`MechanismModel.redundancy
        <evotol.robots.mechanism.model.error_model.MechanismModel.redundancy>`) and ``"identifiability"``
        (:func:`rank_report` over ``poses``).

    Raises
    ------
    evotol.errors.KinematicsError
        A pose the inverse geometry cannot reach (from ``model.joint_values``).
    """
    q = model.joint_values(poses)
    return {"sources": sources_with_nominal(model), **limits_and_box(model), "urdf": list(model.mechanism.urdf),
            "redundancy": model.redundancy,
            "identifiability": rank_report(model, q, f"{len(poses)} Latin-hypercube poses of the workspace")}
