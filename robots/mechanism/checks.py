"""What a mechanism description gives, and whether it is right: the checks behind
``evotol check-mechanism FILE`` and the ``mechanisms`` study (issue 12 items 8-9).

Joint variables, generated error sources, the largest loop-closure residual of the Newton inverse
geometry over Latin-hypercube poses, the agreement of the first-order sensitivities with central
finite differences of the nonlinear closure (:func:`robots.base.check_robot`) and, with a
``[clearance]`` table, the certified maximum pose error at the assembly pose.
"""
from __future__ import annotations


def check_mechanism(file, n_poses: int = 20, sources=None) -> dict:
    """The checks of description ``file`` as a JSON-ready dict (lengths in m, angles in rad)."""
    import time

    import numpy as np

    from robots.base import check_robot
    from robots.mechanism.model import MechanismModel, resolve_description

    t0 = time.perf_counter()
    model = MechanismModel(resolve_description(file), sources=sources)
    poses = model.workspace.latin_hypercube(n_poses, seed=0)
    residual = model.closure_residual(poses)
    rep = check_robot(model, poses, rtol=np.inf)   # report the mismatch, do not raise
    out = {"name": model.name, "file": str(model.mechanism.path), "planar": model.mechanism.planar,
           "actuated": list(model.kin.actuated), "passive": list(model.kin.passive),
           "sources": [{"name": s.name, "group": s.group, "unit": s.unit, "description": s.description} for s in model.sources],
           "n_sources": len(model.sources), "n_poses": len(poses), "closure_residual": residual,
           "fd_rel_error": rep.get("fd_relative_mismatch"), "max_sensitivity": float(np.abs(model.sensitivity(poses)).max())}
    if model.mechanism.clearance is not None:
        from robots.clearance import max_pose_error

        x0, _ = model.kin.assembly()
        res = max_pose_error(model.clearance_mechanism(), x0[None])
        out["clearance_at_assembly"] = {"pose": x0.tolist(), "p_max_m": float(res.p_max[0]), "p_upper_m": float(res.p_upper[0]),
                                        "r_max_rad": float(res.r_max[0]), "r_upper_rad": float(res.r_upper[0])}
    out["seconds"] = time.perf_counter() - t0
    return out
