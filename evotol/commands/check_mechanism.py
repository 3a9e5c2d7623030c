"""``evotol check-mechanism FILE``: what a mechanism description gives, and whether it is right.

Prints the joint variables (actuated and passive), the error sources it generated (name, group,
unit), the largest loop-closure residual of the Newton inverse geometry over Latin-hypercube poses
of the workspace, and the agreement of the first-order sensitivities with central finite
differences of the nonlinear closure (``robots.base.check_robot``). With a ``[clearance]`` table it
also prints the certified maximum pose error at the assembly pose. Exit status 1 when the
finite-difference agreement is worse than ``--rtol``.
"""
from __future__ import annotations

import json


def register(subparsers) -> None:
    p = subparsers.add_parser("check-mechanism", help="check a mechanism description: sources, loop closure, FD agreement",
                              description=__doc__.split("\n\n", 1)[1])
    p.add_argument("file", help="mechanism description (TOML), or the name of a shipped one (fivebar, irsbot2, ...)")
    p.add_argument("--poses", type=int, default=20, help="Latin-hypercube poses for the checks (default 20)")
    p.add_argument("--sources", default=None, help="comma-separated names/patterns overriding [tolerances] sources")
    p.add_argument("--rtol", type=float, default=1e-5, help="largest relative FD mismatch accepted (default 1e-5)")
    p.add_argument("--json", action="store_true", help="print the check as JSON")
    p.set_defaults(func=cmd_check_mechanism)


def check_mechanism(file, n_poses: int = 20, sources=None) -> dict:
    """The checks as a JSON-ready dict (also used by the ``mechanisms`` study)."""
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


def cmd_check_mechanism(args) -> int:
    srcs = [s.strip() for s in args.sources.split(",")] if args.sources else None
    out = check_mechanism(args.file, args.poses, srcs)
    ok = out["fd_rel_error"] is None or out["fd_rel_error"] <= args.rtol
    if args.json:
        print(json.dumps(out, indent=2))
        return 0 if ok else 1
    print(f"{out['name']}  ({out['file']}{', planar' if out['planar'] else ''})")
    print(f"  actuated joint variables: {', '.join(out['actuated']) or '-'}")
    print(f"  passive joint variables:  {', '.join(out['passive']) or '-'}")
    print(f"  {out['n_sources']} error sources:")
    for s in out["sources"]:
        print(f"    {s['name']:14s} {s['group']:9s} {s['unit']:4s} {s['description']}")
    print(f"  loop-closure residual over {out['n_poses']} poses: {out['closure_residual']:.3g} (m or rad)")
    print(f"  sensitivity vs central finite differences of the closure: {out['fd_rel_error']:.3g} relative "
          f"({'OK' if ok else 'FAILED, > %g' % args.rtol})")
    if "clearance_at_assembly" in out:
        c = out["clearance_at_assembly"]
        print(f"  clearance worst case at the assembly pose {c['pose']}: p_max {c['p_max_m'] * 1e3:.6g} mm "
              f"(bound {c['p_upper_m'] * 1e3:.6g}), r_max {c['r_max_rad']:.6g} rad (bound {c['r_upper_rad']:.6g})")
    print(f"  {out['seconds']:.2f} s")
    return 0 if ok else 1
