"""Speed and sampling quality of the planar 5R clearance model (Lara-Molina et al. 2019).

Prints, in one run:
* pose-samples per second of the full model (link lengths + actuator errors + four joint
  clearances, exact loop closure), sampling included and excluded, MC and LHS (target >= 1e6/s
  on one core);
* the LHS vs plain-MC convergence (error variance ratio at equal sample size);
* the sensitivity map throughput.

Run: ``python benchmarks/bench_planar5r.py``
"""
import os

os.environ.setdefault("OMP_NUM_THREADS", "1")
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import time

import numpy as np

from evotol.robots.planar5r import Planar5R
from evotol.robots.planar5r import uncertainty as U


def best_of(f, repeat=5):
    best = np.inf
    for _ in range(repeat):
        t0 = time.perf_counter()
        f()
        best = min(best, time.perf_counter() - t0)
    return best


def main():
    robot = Planar5R("b")
    d = robot.design
    poses = robot.miw_poses()                       # 17 poses
    model = U.UncertaintyModel(clearance=U.DEFAULT_CLEARANCE)
    print(f"planar5r benchmark: case b, {len(poses)} poses, {model.n_dims} random variables, one core")
    for n in (10_000, 100_000):
        for method in ("mc", "lhs"):
            unit = U.unit_samples(n, model.n_dims, method, seed=0)
            t_eval = best_of(lambda: U.position_deviations(poses, d.r1, d.r2, d.r3, model, unit))
            t_all = best_of(lambda: U.sample_deviations(poses, d.r1, d.r2, d.r3, model, n, method, seed=0))
            ps = len(poses) * n
            print(f"  {method:3s} n={n:>7d}: {ps / t_eval:12.3e} pose-samples/s (evaluation), "
                  f"{ps / t_all:12.3e} pose-samples/s (sampling + evaluation)  [{t_all * 1e3:7.1f} ms]")
    target = len(poses) * 100_000 / best_of(lambda: U.sample_deviations(poses, d.r1, d.r2, d.r3, model, 100_000, "lhs"))
    print(f"  target >= 1e6 pose-samples/s: {'met' if target >= 1e6 else 'NOT met'} ({target:.2e}/s)")

    P = robot.miw_poses(rings=(0.2, 0.4, 0.6, 0.7), n_per_ring=250)
    t = best_of(lambda: robot.sensitivity(P))
    print(f"  sensitivity map: {len(P) / t:.3e} poses/s ({len(P)} poses, {t * 1e3:.1f} ms)")

    from evotol.studies._laramolina2019_5r_allocation import _from_variables, allocation_problem

    AP = allocation_problem("b", 1024, 0)
    T = _from_variables(AP, np.tile([[20e-6, 20e-6, 3e-4]], (64, 1)))
    t = best_of(lambda: AP.evaluate(T), repeat=3)
    print(f"  allocation: core nonlinear yield (64 designs x 17 poses x 1024 samples): "
          f"{T.shape[0] * 17 * 1024 / t:.3e} pose-samples/s")

    t0 = time.perf_counter()
    conv = U.convergence_study(robot.evaluation_poses(), d.r1, d.r2, d.r3, model, sizes=(16, 64, 256, 1024),
                               n_rep=100, n_reference=2 ** 17, seed=0)
    print(f"  LHS vs MC convergence (9 poses, 100 replications, {time.perf_counter() - t0:.1f} s):")
    print("      N  " + "  ".join(f"{k} (rms error; MC/LHS variance ratio)" for k in conv["variance_ratio"]))
    for i, N in enumerate(conv["sizes"]):
        print(f"  {N:5d}  " + "  ".join(f"MC {conv['mc'][k][i]:.2e} LHS {conv['lhs'][k][i]:.2e} (x{conv['variance_ratio'][k][i]:.1f})"
                                         for k in conv["variance_ratio"]))


if __name__ == "__main__":
    main()
