"""A URDF chain checked against Pinocchio and finite differences, at joint values (no task box needed).

For the chain root -> ``tip`` of a URDF, at random configurations inside the joint limits:

* forward kinematics of the tip against Pinocchio's ``framesForwardKinematics``;
* every sensitivity column against central finite differences of the nonlinear model
  (:meth:`MechanismModel.pose_error_at_joints`, the placements perturbed as ``M exp(delta)``);
* the rank of the sources stacked over the configurations against the rank of Pinocchio's joint
  placement regressor (``computeFrameKinematicRegressor``, ``LOCAL_WORLD_ALIGNED``) of the same
  chain, and the rank of both together (equal ranks = the same span).

``tests/test_urdf_walk.py`` runs it over every URDF of ``example-robot-data``.
"""
from __future__ import annotations

import time
from pathlib import Path

import numpy as np

from evotol.robots.mechanism.model.identifiability import stacked_rank
from evotol.robots.mechanism.kinematics.placement import PLACEMENT_FIELDS
from evotol.robots.mechanism.urdf.reader import _pin, chain_joints, pinocchio_configuration, pinocchio_placement_regressor, urdf_frames

#: half range (m) of the random values of a prismatic joint without limits
UNLIMITED_PRISMATIC = 0.1


def random_joints(variables, limits, n: int, seed: int = 0, units=None) -> dict:
    """Uniform joint values inside the limits (a joint without limits: [-pi, pi] or [-0.1, 0.1] m).

    Parameters
    ----------
    variables : sequence of str
        The joint variables.
    limits : mapping of str to (float, float)
        Joint variable -> (lower, upper), rad or m.
    seed : int, optional
        Seed of the random generator (reproducible draws).
    units : mapping of str to str, optional
        Joint variable -> ``"rad"`` or ``"m"`` (``Kinematics.joint_unit``); a variable not in it
        is revolute.

    Returns
    -------
    dict of str to (n,) ndarray
        Joint variable -> ``n`` values drawn uniformly: a revolute joint from its limits
        intersected with ``[-pi, pi]`` rad (all of it without limits), a prismatic joint from
        its limits (m), or ``[-0.1, 0.1]`` m without limits; a range of zero width gives its
        lower value.
    """
    rng = np.random.default_rng(seed)
    units = units or {}
    out = {}
    for v in variables:
        if units.get(v, "rad") == "m":
            lo, hi = limits.get(v, (-UNLIMITED_PRISMATIC, UNLIMITED_PRISMATIC))
        else:
            lo, hi = limits.get(v, (-np.pi, np.pi))
            lo, hi = max(lo, -np.pi), min(hi, np.pi)
        out[v] = rng.uniform(lo, hi, n) if hi > lo else np.full(n, lo)
    return out


def check_urdf_chain(robot, n: int = 8, seed: int = 0, step: float = 1e-6) -> dict:
    """Pinocchio and finite-difference agreement of a URDF description at random joint values.

    Parameters
    ----------
    robot : MechanismModel
        Built from a description with ``urdf`` and ``tip``.
    n : int
        Number of random configurations (inside the joint limits).
    seed : int
        Seed of the random configurations (:func:`random_joints`).
    step : float
        Central-difference step (m or rad).

    Returns
    -------
    dict
        ``fk_vs_pinocchio`` (largest ``|T - T_pin|``), ``fd_rel_error`` (largest ``|FD - S|`` / largest ``|S|``),
        ``n_sources``, ``rank`` (the sources), ``pinocchio_rank`` (the chain's placement regressor),
        ``combined_rank`` (both together) and the same three with the tip's placement
        (``rank_with_tip`` ...), ``n_joints``.
    """
    pin = _pin()
    path, tip = robot.mechanism.urdf
    info = urdf_frames(path, tip)[3]
    model, fid = info["model"], info["tip_frame_id"]
    kin = robot.kin
    q = random_joints(kin.variables, robot.mechanism.limits, n, seed, units=kin.joint_unit)
    T = kin.state(q, n, twists=False).world[robot.mechanism.end_effector]
    Qp = pinocchio_configuration(model, {v: q[v] for v in kin.variables}, info["mimic"])
    data = model.createData()
    Tp = []
    for qi in Qp:
        pin.framesForwardKinematics(model, data, qi)
        Tp.append(data.oMf[fid].homogeneous)
    fk = float(np.abs(T - np.array(Tp)).max())
    S = robot.sensitivity_at_joints(q)
    k = robot.n_columns
    E = np.zeros((n, 2 * k, k))
    E[:, np.arange(k), np.arange(k)] = step
    E[:, k + np.arange(k), np.arange(k)] = -step
    D = robot.pose_error_at_joints(q, E)
    fd = np.swapaxes((D[:, :k] - D[:, k:]) / (2 * step), 1, 2)
    fd_rel = float(np.abs(fd - S).max() / max(np.abs(S).max(), 1e-300))
    # span against Pinocchio: the chain's joints only (their columns), our placement twists + offsets
    chain_cols = [6 * (j - 1) + c for j in chain_joints(model, fid) for c in range(6)]
    R = pinocchio_placement_regressor(model, fid, Qp, with_tip=True)
    Rj, Rt = R[:, :, chain_cols], R[:, :, list(chain_cols) + list(range(R.shape[2] - 6, R.shape[2]))]
    own = [i for i, s in enumerate(robot.source_names) if not s.endswith("_multiplier")]
    Sj = S[:, :, own]
    tip_model = type(robot)(robot.mechanism, sources=list(robot.mechanism.sources) + [f"{info['tip']}.{f}" for f in PLACEMENT_FIELDS])
    St = tip_model.sensitivity_at_joints(q)[:, :, [i for i, s in enumerate(tip_model.source_names) if not s.endswith("_multiplier")]]
    return {"fk_vs_pinocchio": fk, "fd_rel_error": fd_rel, "n_sources": k, "n_joints": len(info["joints"]),
            "rank": stacked_rank(Sj), "pinocchio_rank": stacked_rank(Rj), "combined_rank": stacked_rank(np.concatenate([Sj, Rj], 2)),
            "rank_with_tip": stacked_rank(St), "pinocchio_rank_with_tip": stacked_rank(Rt),
            "combined_rank_with_tip": stacked_rank(np.concatenate([St, Rt], 2))}


def check_urdf_file(path, tip: str, n_poses: int = 20, sources=None) -> dict:
    """``evotol check-mechanism arm.urdf --tip tool0`` as a JSON-ready dict (SI).

    Parameters
    ----------
    tip : str
        The end-effector link or frame.
    n_poses : int
        Random configurations inside the joint limits (at least 20 for the rank).
    sources : list of str, optional
        Names or patterns; default: the URDF arm's default sources.

    Returns
    -------
    dict
        ``name, file, tip, sources`` (with nominal values), ``parameters``, ``assembly`` (zero
        configuration clipped into the limits, and the tip pose there), ``workspace`` (box of
        the tip positions over the configurations), ``limits``, ``identifiability`` (rank, blind,
        duplicated, Pinocchio's rank), ``fk_vs_pinocchio``, ``fd_rel_error``, ``seconds``.

    Raises
    ------
    ValidationError
        Not a URDF Pinocchio reads, an unknown tip, a floating or planar joint on the chain.
    """
    from evotol.robots.mechanism.checks.description import end_effector_pose
    from evotol.robots.mechanism.description.reader import mechanism_from_dict
    from evotol.robots.mechanism.checks.inspection import limits_and_box, rank_report, sources_with_nominal
    from evotol.robots.mechanism.model.error_model import MechanismModel

    t0 = time.perf_counter()
    box = {"coordinates": [{"name": a, "axis": a, "low": -1.0, "high": 1.0} for a in "xyz"]}
    mech = mechanism_from_dict({"name": Path(path).stem, "urdf": str(Path(path).resolve()), "tip": tip, "end_effector": box})
    model = MechanismModel(mech, sources=sources)
    kin = model.kin
    n = max(int(n_poses), 20)
    q = random_joints(kin.variables, mech.limits, n, seed=0, units=kin.joint_unit)
    q0 = {v: float(np.clip(0.0, *mech.limits.get(v, (-np.inf, np.inf)))) for v in kin.variables}
    T = kin.state(q, n, twists=False).world[mech.end_effector][:, :3, 3]
    chk = check_urdf_chain(model, n=min(n, 8))
    ee = end_effector_pose(model, q0)
    return {"name": mech.name, "file": str(path), "tip": tip, "sources": sources_with_nominal(model), "n_sources": model.n_columns,
            "parameters": [{"name": k, "value": float(v), "unit": "m" if k in mech.lengths else "rad"}
                           for k, v in mech.parameters.items()],
            "assembly": {"joints": [{"name": v, "unit": kin.joint_unit.get(v, "rad"), "declared": None, "solved": q0[v]}
                                    for v in kin.variables],
                         "pose": [{"name": a, "value": float(x), "unit": "m"} for a, x in zip("xyz", ee["position"])]},
            "end_effector": ee,
            "workspace": [{"name": a, "unit": "m", "low": float(T[:, i].min()), "high": float(T[:, i].max())}
                          for i, a in enumerate("xyz")],
            "limits": limits_and_box(model)["limits"],
            "identifiability": rank_report(model, q, f"{n} random configurations inside the joint limits"),
            "fk_vs_pinocchio": chk["fk_vs_pinocchio"], "fd_rel_error": chk["fd_rel_error"],
            "seconds": time.perf_counter() - t0}
