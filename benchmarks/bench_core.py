"""Core benchmark: the 3-UCR GA of Yao 2013 (population 100, 200 generations) and the speed-up of
vectorised population evaluation over an element-wise Python loop. Prints measured numbers.

    python benchmarks/bench_core.py
"""
import os

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import time  # noqa: E402

import numpy as np  # noqa: E402

from evotol.allocators import allocate_ga, allocate_optimum  # noqa: E402
from evotol.measures.constraints import ConstraintRows  # noqa: E402
from evotol.studies.yao2013 import yao2013_problem  # noqa: E402


def loop_rss_fitness(problem, T):
    """The same penalty fitness as the GA's, one design / pose / source at a time."""
    out = []
    for t in T:
        cost = 0.0
        for j, n in enumerate(problem.names):
            cost += float(problem.tolerances[n].cost.cost(t[j]))
        worst = 0.0
        for p in range(problem.n_poses):
            ss = 0.0
            for j in range(problem.n_sources):
                ss += (t[j] * problem.sensitivities["position"][p, j]) ** 2
            worst = max(worst, ss ** 0.5)
        out.append(cost + (1e3 if worst > problem.requirement.position else 0.0))
    return np.array(out)


def main():
    print("== evotol core benchmark (3-UCR, Yao et al. 2013; 726 poses, 12 sources) ==")
    for variant in ("paper", "verified"):
        P = yao2013_problem(variant, "rss")
        opt = allocate_optimum(P)
        t0 = time.perf_counter()
        ga = allocate_ga(P, pop_size=100, n_gen=200, seed=0)
        dt = time.perf_counter() - t0
        print(f"GA pop 100 x 200 gen, {variant:8s} model, RSS: {dt:6.2f} s  cost {ga.cost:.5f}  "
              f"optimum {opt.cost:.5f}  GA/optimum - 1 = {100 * (ga.cost / opt.cost - 1):.4f} %")
    P = yao2013_problem("verified", "rss")
    rows = ConstraintRows(P)
    T = np.random.default_rng(0).uniform(1e-6, 1e-4, (100, 12))
    t0 = time.perf_counter()
    for _ in range(20):
        vec = P.cost(T) + 1e3 * (rows.violation(T) > 0)
    t_vec = (time.perf_counter() - t0) / 20
    t0 = time.perf_counter()
    loop = loop_rss_fitness(P, T)
    t_loop = time.perf_counter() - t0
    assert np.allclose(vec, loop)
    print(f"population of 100 evaluated: vectorised {1e3 * t_vec:.3f} ms, element-wise loop {1e3 * t_loop:.1f} ms, "
          f"speed-up {t_loop / t_vec:.0f}x (same fitness values)")
    Pw = yao2013_problem("verified", "worst_case")
    t0 = time.perf_counter()
    Pw.evaluate(T[:10])
    dt = time.perf_counter() - t0
    print(f"exact worst case (600 directions + refinement) at 726 poses: {1e3 * dt / 10:.1f} ms per design")


if __name__ == "__main__":
    main()
