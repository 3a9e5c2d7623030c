"""The UR5 study (``reports/studies/ur5_urdf.toml``) with the old and the new URDF error sources (issue 23 item 1).

Old: each joint origin's x, y, z, roll, pitch, yaw and the joint offset (42 sources, rank 24 at random
configurations). New (the default since issue 23): each origin's six placement twists less the rotation
about the joint's own axis, plus the joint offset (36 sources, rank 26 = Pinocchio's placement regressor).
Prints: the old optimum; the directions the old sources miss (least-squares residual against all placement
twists); the old optimum's worst-case error once those tilts get the tolerance of their seat's pitch; the
old sources plus those tilts re-allocated; the new optimum. ``python benchmarks/compare_ur5_sources.py``.
"""
from __future__ import annotations

import time
import tomllib
from pathlib import Path

import numpy as np

from evotol.allocators import allocate_optimum
from evotol.studyfile import load_problem
from evotol.robots.mechanism.model.identifiability import analyse

ROOT = Path(__file__).resolve().parents[1]
STUDY = ROOT / "reports" / "studies" / "ur5_urdf.toml"
JOINTS = ["shoulder_pan_joint", "shoulder_lift_joint", "elbow_joint", "wrist_1_joint", "wrist_2_joint", "wrist_3_joint"]
OLD = [f"*_joint_{k}" for k in ("x", "y", "z", "roll", "pitch", "yaw")] + ["*_joint"]
TWISTS = [f"{j}.{k}_{a}" for j in JOINTS for k in ("shift", "tilt") for a in "xyz"]


def problem(sources):
    spec = tomllib.loads(STUDY.read_text())
    spec["robot"]["sources"] = sources
    return load_problem(spec, STUDY.parent)


def main() -> None:
    t0 = time.perf_counter()
    old = problem(OLD)
    r_old = allocate_optimum(old)
    print(f"old sources ({old.model.n_columns}): optimum cost {r_old.cost:.4f}, "
          f"max position error {r_old.max_error() * 1e3:.4f} mm")
    full = problem(TWISTS)
    Q = np.random.default_rng(0).uniform(-np.pi, np.pi, (200, 6))
    a = analyse(old.model.sensitivity_at_joints(Q), old.model.source_names,
                full.model.sensitivity_at_joints(Q), full.model.source_names)
    missing = [n for n, _ in a["missing"]]
    print(f"old rank {a['rank']}, placement-twist rank {a['reference_rank']}; duplicated {len(a['duplicated'])} pairs "
          f"(e.g. {a['duplicated'][0]}); missing: {a['missing']}")
    aug = problem(OLD + missing)
    t = dict(r_old.tolerances)
    for n in missing:
        t[n] = t[n.split(".")[0] + "_pitch"]                 # the tolerance of the seat's pitch
    ev = aug.evaluate(aug.as_array(t))
    err = float(ev.position.max())
    print(f"old optimum with {missing} at their seat's pitch tolerance: max position error {err * 1e3:.4f} mm "
          f"(requirement {aug.requirement.position * 1e3:g} mm)")
    r_aug = allocate_optimum(aug)
    print(f"old sources + those tilts re-allocated: cost {r_aug.cost:.4f} ({(r_aug.cost / r_old.cost - 1) * 100:+.2f} %)")
    new = problem(None)
    r_new = allocate_optimum(new)
    print(f"new default sources ({new.model.n_columns}): optimum cost {r_new.cost:.4f} ({(r_new.cost / r_old.cost - 1) * 100:+.2f} % "
          f"vs old), max position error {r_new.max_error() * 1e3:.4f} mm; {time.perf_counter() - t0:.1f} s")


if __name__ == "__main__":
    main()
