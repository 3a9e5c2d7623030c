"""Yield benchmark (issue 10): the first-order ``yield`` measure evaluates a GA population of 100
designs at 1 000 workspace poses of the 3-UCR (12 sources, normal, t = 3σ) -- target under 1 s on
2 cores -- against a 10^5-sample Monte Carlo of the same quantity (the per-pose miss probability
of the same linear model). The Monte Carlo is timed on a subset (2 designs × 50 poses, one sample set per design shared by its poses) and scaled
linearly to the full population (its cost is linear in designs × poses × samples); the subset also
shows that both estimate the same number (difference in Monte Carlo standard errors).

    python benchmarks/bench_yield.py
"""
import os

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import time  # noqa: E402

import numpy as np  # noqa: E402

from evotol.cost_models import ExponentialCost  # noqa: E402
from evotol.measures.statistical.distributions import draw, uniforms  # noqa: E402
from evotol.core.problem import Requirement, Tolerance, ToleranceProblem  # noqa: E402
from evotol.robots.ucr3 import UCR3  # noqa: E402


def main():
    robot = UCR3(variant="verified")
    tol = {s.name: Tolerance(ExponentialCost(1.9, 0.5, scale=1e-5), 1e-6, 2e-4, distribution="normal")
           for s in robot.sources}
    poses = robot.workspace.latin_hypercube(1000, seed=0)
    P = ToleranceProblem(robot, tol, Requirement(position=5e-5, measure="yield", probability=0.9973), poses)
    rng = np.random.default_rng(0)
    T = rng.uniform(5e-6, 3e-5, (100, P.n_sources))
    t0 = time.perf_counter()
    P.evaluate(T)                                   # first call also builds the cached moments
    t_first = time.perf_counter() - t0
    reps = 3
    t0 = time.perf_counter()
    for _ in range(reps):
        ev = P.evaluate(T)
    t_yield = (time.perf_counter() - t0) / reps
    miss = 1 - ev.probability
    print(f"== yield measure: 100 designs x {P.n_poses} poses, {P.n_sources} sources (3-UCR, normal t = 3 sigma) ==")
    print(f"analytic (sphere quadrature): {t_yield:.3f} s per population (first call {t_first:.3f} s), "
          f"target < 1 s: {'met' if t_yield < 1 else 'MISSED'}; miss probabilities {miss.min():.2e} .. {miss.max():.2e}")

    n, sub_d, sub_p = 100_000, 2, 50
    dims = [s.dim for s in robot.sources]
    t0 = time.perf_counter()
    mc = np.empty((sub_d, sub_p))
    for i in range(sub_d):
        Z = draw(uniforms(n, sum(dims), "mc", i), dims, P.distributions)   # shared by the poses
        E = np.concatenate([z * tj for z, tj in zip(Z, T[i])], axis=1)
        for p in range(sub_p):
            mc[i, p] = np.mean(np.linalg.norm(E @ P.jacobian[p, 0:3].T, axis=1) > 5e-5)
    t_mc_sub = time.perf_counter() - t0
    t_mc = t_mc_sub * (T.shape[0] * P.n_poses) / (sub_d * sub_p)
    se = np.sqrt(np.maximum(miss[:sub_d, :sub_p] * (1 - miss[:sub_d, :sub_p]), 1e-12) / n)
    z = np.abs(mc - miss[:sub_d, :sub_p]) / se
    print(f"Monte Carlo 1e5 samples: {t_mc_sub:.2f} s for {sub_d} x {sub_p} (design, pose) pairs -> "
          f"{t_mc:.0f} s for the population (linear scaling)")
    print(f"speed-up analytic / Monte Carlo: {t_mc / t_yield:.0f}x; on the subset |MC - analytic| <= "
          f"{z.max():.2f} MC standard errors (same quantity)")


if __name__ == "__main__":
    main()
