"""Speed of the Delta model (Brahmia et al. 2023) and of the brahmia2023-delta study.

Prints, in one run:
* forward kinematics with errors (loop closure, chord Newton): pose-samples per second, and the
  closure residual reached;
* first-order map (complex step + implicit function theorem): poses per second;
* one solve of problem (12)-(13) with trust-constr (average over a few runs);
* optionally (``--study``) the full study wall time against the 2-minute target.

Run: ``python benchmarks/bench_delta.py [--study]``
"""
import os

os.environ.setdefault("OMP_NUM_THREADS", "1")
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import sys
import tempfile
import time
from pathlib import Path

import numpy as np

from evotol.studies import brahmia2023_delta as study
from evotol.robots.delta import DeltaRobot, cylinder_poses


def best_of(f, repeat=3):
    best, out = np.inf, None
    for _ in range(repeat):
        t0 = time.perf_counter()
        out = f()
        best = min(best, time.perf_counter() - t0)
    return best, out


def main():
    robot = DeltaRobot()
    poses = cylinder_poses(100, seed=1)
    rng = np.random.default_rng(0)
    E = rng.uniform(-1, 1, (100, 1000, 47)) * study.paper_bounds()
    t, P = best_of(lambda: robot.forward_kinematics(poses, E))
    res = robot.closure_residual(poses[:10], E[:10, :100]).max() * 1e3
    print(f"FK with errors: {E.shape[0] * E.shape[1] / t:,.0f} pose-samples/s "
          f"(100 poses x 1000 samples in {t:.2f} s); closure residual {res:.2e} mm")
    dense = cylinder_poses(1000, seed=2)
    t, _ = best_of(lambda: robot.sensitivity(dense))
    print(f"first-order map: {len(dense) / t:,.0f} poses/s (1000 poses in {t:.2f} s)")
    pose = study.postures_m(["P6"])[0]
    times = []
    for d in ((0, 0.2e-3, 0), (0, 0, 0.2e-3), (0.2e-3, 0, 0)):
        t0 = time.perf_counter()
        out = study.solve_displacement(robot, pose, np.array(d), min_magnitude=study.inferred_min_magnitude(), maxiter=80)
        times.append(time.perf_counter() - t0)
    print(f"problem (12)-(13), closed loop: {np.mean(times):.2f} s per solve (last: {out['nit']} iterations)")
    if "--study" in sys.argv:
        with tempfile.TemporaryDirectory() as tmp:
            t0 = time.perf_counter()
            s = study.run(Path(tmp), quick=False)
            wall = time.perf_counter() - t0
        print(f"full study: {wall:.1f} s (target < 120 s, ratio {wall / 120:.2f}); parts: {s['timing_s']}")


if __name__ == "__main__":
    main()
