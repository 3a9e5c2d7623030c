"""What a mechanism description gives, and whether it is right: the checks behind
``evotol check-mechanism FILE`` and the ``mechanisms`` study (issue 12 items 8-9, issue 27 item 1).

The model as understood (design parameters, the assembly joints as declared and as solved by
Newton, the end-effector pose there), joint variables, generated error sources, the largest
loop-closure residual of the Newton inverse geometry over Latin-hypercube poses, the agreement of
the first-order sensitivities with central finite differences of the nonlinear closure
(:func:`evotol.robots.base.check_robot`) and, with a ``[clearance]`` table, the certified maximum pose
error at the assembly pose.
"""
from __future__ import annotations

import time

import numpy as np


def end_effector_pose(model, q: dict) -> dict:
    """Position (m) and Z-Y-X Euler angles (rad: yaw about z, pitch about y, roll about x; ``R =
    Rz(yaw) Ry(pitch) Rx(roll)``) of the end-effector frame at joint values ``q`` (scalars).

    Parameters
    ----------
    model : evotol.robots.mechanism.model.error_model.MechanismModel
        The mechanism's error model (its kinematics and description).
    q : dict of str to float
        Every joint variable -> its value (rad, or m for a prismatic joint), in the base frame
        ``"0"``.

    Returns
    -------
    dict
        ``{"frame": name, "position": [x, y, z] (m), "yaw_pitch_roll": [yaw, pitch, roll] (rad)}``
        of the end-effector frame, in the base frame.
    """
    kin = model.kin
    st = kin.state({k: np.atleast_1d(v) for k, v in q.items()}, 1, twists=False)
    T = st.world[model.mechanism.end_effector][0]
    R = T[:3, :3]
    yaw, pitch, roll = np.arctan2(R[1, 0], R[0, 0]), np.arcsin(-np.clip(R[2, 0], -1, 1)), np.arctan2(R[2, 1], R[2, 2])
    return {"frame": model.mechanism.end_effector, "position": T[:3, 3].tolist(), "yaw_pitch_roll": [float(yaw), float(pitch), float(roll)]}


def understood(model) -> dict:
    """What evotol read from the description (SI): parameters with their units, and the assembly:
    pose, joints as declared and as solved, and the end-effector pose there. Raises the
    assembly's KinematicsError (declared joints far from the solved ones, issue 27).

    Returns
    -------
    dict
        ``"parameters"``: a list of ``{name, value, unit}`` (m or rad); ``"assembly"``:
        ``{"pose": [{name, value, unit}], "joints": [{name, unit, declared, solved}]}``
        (``declared`` None when the description gives none); ``"end_effector"``: see
        :func:`end_effector_pose`.

    Raises
    ------
    evotol.errors.KinematicsError
        The loops do not close at the assembly pose, the solved joints are far from the
        declared ones (other working mode), or a joint is outside its limits
        (:meth:`evotol.robots.mechanism.posture.inverse_geometry.InverseGeometry.assembly`).
    evotol.errors.ValidationError
        An ``[assembly] joints`` key that is not a joint variable.
    """
    mech, kin = model.mechanism, model.kin
    x0, q = kin.assembly()
    return {"parameters": [{"name": k, "value": float(v), "unit": "m" if k in mech.lengths else "rad"}
                           for k, v in mech.parameters.items()],
            "assembly": {"pose": [{"name": n, "value": float(v), "unit": u}
                                  for n, v, u in zip(model.workspace.names, x0, model.workspace.units)],
                         "joints": [{"name": x, "unit": kin.joint_unit.get(x, "rad"), "declared": mech.assembly_joints.get(x),
                                     "solved": q[x]} for x in kin.variables]},
            "end_effector": end_effector_pose(model, q)}


def check_mechanism(file, n_poses: int = 20, sources=None) -> dict:
    """The checks of description ``file`` as a JSON-ready dict (lengths in m, angles in rad).

    Parameters
    ----------
    file : str or Path
        A description file or the name of a shipped one.
    n_poses : int
        Latin-hypercube poses of the workspace for the closure and finite-difference checks.
    sources : list of str, optional
        Names or patterns overriding the description's ``[tolerances] sources``.

    Returns
    -------
    dict
        ``name, file, planar, parameters, assembly, end_effector, actuated, passive, sources,
        n_sources, n_poses, closure_residual, fd_rel_error, max_sensitivity, seconds`` (and
        ``clearance_at_assembly`` with a ``[clearance]`` table).

    Raises
    ------
    ValidationError
        A mistake in the description (names the field).
    KinematicsError
        The loops do not close at the assembly, or close far from the declared joints.
    """
    from evotol.robots.base import check_robot
    from evotol.robots.mechanism.checks.inspection import model_report
    from evotol.robots.mechanism.callouts.model import with_callouts
    from evotol.robots.mechanism.model.error_model import MechanismModel, resolve_description

    t0 = time.perf_counter()
    model = with_callouts(MechanismModel(resolve_description(file), sources=sources), sources=sources)   # [[callouts]]: issue 35
    seen = understood(model)
    poses = model.workspace.latin_hypercube(n_poses, seed=0)
    residual = model.closure_residual(poses)
    rep = check_robot(model, poses, rtol=np.inf)   # report the mismatch, do not raise
    out = {"name": model.name, "file": str(model.mechanism.path), "planar": model.mechanism.planar, **seen,
           "actuated": list(model.kin.actuated), "passive": list(model.kin.passive),
           "sources": [{"name": s.name, "group": s.group, "unit": s.unit, "description": s.description} for s in model.sources],
           "n_sources": len(model.sources), "n_poses": len(poses), "closure_residual": residual,
           "fd_rel_error": rep.get("fd_relative_mismatch"), "max_sensitivity": float(np.abs(model.sensitivity(poses)).max())}
    callouts = model.part_of("callouts")        # a description with its own drawing callouts
    if callouts is not None:
        out["callouts"] = callouts.describe_callouts()
    out.update(model_report(model, poses))     # issue 23: nominal values, box and limits, rank (robots/mechanism/checks/inspection.py)
    if model.mechanism.clearance is not None:
        from evotol.robots.clearance import max_pose_error

        x0, _ = model.kin.assembly()
        res = max_pose_error(model.clearance_mechanism(), x0[None])
        out["clearance_at_assembly"] = {"pose": x0.tolist(), "p_max_m": float(res.p_max[0]), "p_upper_m": float(res.p_upper[0]),
                                        "r_max_rad": float(res.r_max[0]), "r_upper_rad": float(res.r_upper[0])}
    out["seconds"] = time.perf_counter() - t0
    return out
