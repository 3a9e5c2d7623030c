"""Process-selection and assembly-function benchmark (issue 14). Prints measured numbers:

* GA cost / exact optimum and GA seconds on every shipped process-selection problem
  (target: ratio <= 1.01 in under 10 s each);
* branch and bound vs. full enumeration on stacks with >= 10^4 process combinations: convex
  solves of each (enumeration: every combination whose tightest design can hold the requirement;
  target: >= 10x fewer for branch and bound);
* sensitivities of a 20-dimension assembly function at 10^4 points (target: under 1 s), and their
  agreement with central differences;
* cost-vs-yield NSGA-II fronts against the exact 3-sigma optimum (for one response, yield >=
  2 Phi(3) - 1 is RSS <= L, so the RSS optimum is the exact cheapest design at that yield), with
  the CPU seconds of each front (load-independent-ish; print `uptime` beside it).

    python benchmarks/bench_process.py
"""
import os

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import time  # noqa: E402
import warnings  # noqa: E402

import numpy as np  # noqa: E402
import pandas as pd  # noqa: E402

from evotol.allocators.optimum import allocate_optimum  # noqa: E402
from evotol.allocators.process import allocate_process_ga, allocate_process_optimum  # noqa: E402
from evotol.allocators.process import assembly_problem, process_front  # noqa: E402
from evotol.studies._process_benchmarks import MM, clutch_problem, process, stack_problem  # noqa: E402
from evotol.studies.process_stack import enumeration_solves  # noqa: E402
from evotol.robots.assembly import AssemblyFunction, LinearStack  # noqa: E402


def ga_vs_optimum():
    print("== GA vs. exact optimum on the shipped process-selection problems (defaults: pop 60, 100 generations, seed 0) ==")
    print(f"{'problem':28s} {'combos':>7s} {'optimum':>10s} {'GA':>10s} {'GA/opt':>9s} {'GA s':>6s} {'B&B s':>6s}  target")
    for label, make in (("clutch, worst case", lambda: clutch_problem("worst_case")), ("clutch, RSS", lambda: clutch_problem("rss")),
                        ("stack, worst case", lambda: stack_problem("worst_case")), ("stack, RSS", lambda: stack_problem("rss"))):
        pp = make()
        opt = allocate_process_optimum(pp)
        ga = allocate_process_ga(pp, seed=0)
        ratio = ga.cost / opt.cost
        ok = ratio <= 1.01 and ga.seconds < 10 and ga.feasible
        print(f"{label:28s} {pp.n_combinations:7d} {opt.cost:10.5f} {ga.cost:10.5f} {ratio:9.6f} {ga.seconds:6.2f} {opt.seconds:6.2f}  "
              f"{'met' if ok else 'MISSED'}")


def lever_stack(n_dims, limit_mm, measure, names):
    """A stack with lever ratios 0.5/1/1.5 and part sizes 0.3..1.5: optima mix processes."""
    coef = {f"d{i}": (1 if i == 0 else -1) * (0.5 + 0.5 * (i % 3)) for i in range(n_dims)}
    size = {f"d{i}": 0.3 + 0.4 * (i % 4) for i in range(n_dims)}
    asm = LinearStack(coef, {"gap": limit_mm * MM})
    return assembly_problem(asm, processes={d: [process(p, size[d]) for p in names] for d in coef}, measure=measure)


def bb_vs_enumeration():
    print("\n== branch and bound vs. full enumeration (convex solves) ==")
    for label, pp in (("10-dim lever stack x 3 processes, worst case, +-0.2 mm", lever_stack(10, 0.2, "worst_case", ("turn", "grind", "hone"))),
                      ("10-dim lever stack x 3 processes, RSS, +-0.1 mm", lever_stack(10, 0.1, "rss", ("turn", "grind", "hone"))),
                      ("8-dim lever stack x 4 processes, RSS, +-0.4 mm", lever_stack(8, 0.4, "rss", ("mill", "turn", "grind", "hone"))),
                      ("8-dim lever stack x 4 processes, worst case, +-0.05 mm", lever_stack(8, 0.05, "worst_case", ("mill", "turn", "grind", "hone")))):
        t0 = time.perf_counter()
        n_enum = enumeration_solves(pp)
        t_count = time.perf_counter() - t0
        bb = allocate_process_optimum(pp)
        # time a sample of enumeration's convex solves, to estimate what enumerating all would take
        rng = np.random.default_rng(0)
        sample = [rng.integers(0, k, size=20) for k in pp.n_processes]
        t1 = time.perf_counter()
        solved = 0
        for choice in np.array(sample).T:
            if pp.normalised_error(pp.lo[np.arange(pp.n_sources), choice])[0] <= 1:
                allocate_optimum(pp.subproblem(choice))
                solved += 1
        per_solve = (time.perf_counter() - t1) / max(solved, 1)
        ratio = n_enum / bb.n_convex_solves
        print(f"{label}: {pp.n_combinations} combinations; enumeration needs {n_enum} convex solves "
              f"(~{n_enum * per_solve:.0f} s at {per_solve * 1e3:.0f} ms each; feasibility count {t_count:.1f} s); "
              f"branch and bound: {bb.n_convex_solves} solves, {bb.n_nodes} nodes, {bb.seconds:.2f} s, cost {bb.cost:.5f}, "
              f"processes {dict(sorted(pd.Series(list(bb.processes.values())).value_counts().items()))}; ratio {ratio:.0f}x ({'met' if ratio >= 10 else 'MISSED'})")


def jacobian_speed():
    print("\n== sensitivities of a 20-dimension assembly function at 10^4 points ==")
    names = [f"x{i}" for i in range(20)]

    def f(**x):
        X = np.stack([x[n] for n in names], axis=-1)
        w = np.arange(1, 21) / 20
        return np.arctan(X @ w) + np.sqrt(1 + (X ** 2).sum(axis=-1)), np.prod(1 + 0.1 * X, axis=-1)

    asm = AssemblyFunction(f, {n: 0.1 for n in names}, {"y1": 1.0, "y2": 1.0}, name="20-dim function")
    P = np.random.default_rng(0).uniform(-1, 1, size=(10_000, 20))
    def best_of_3(fn):
        times = []
        for _ in range(3):
            t0 = time.perf_counter()
            out = fn(P)
            times.append(time.perf_counter() - t0)
        return out, min(times)

    J, t_cs = best_of_3(asm.jacobian)              # includes the check that every response is finite
    F, t_fd = best_of_3(asm.central_differences)
    err = float(np.max(np.abs(J - F)) / np.max(np.abs(J)))
    print(f"complex step (best of 3): {t_cs:.3f} s for {J.shape} ({'met' if t_cs < 1 else 'MISSED'} < 1 s); central differences "
          f"{t_fd:.3f} s (ratio {t_fd / t_cs:.2f}); max relative difference {err:.2e}; method {asm.derivative_method!r}")


def yield_fronts():
    from scipy.stats import norm

    y3 = 2 * norm.cdf(3) - 1
    print("\n== cost vs. yield fronts (NSGA-II pop 60, 100 generations, seed 0; normal, t = 3 sigma) ==")
    for label, make in (("clutch", clutch_problem), ("stack", stack_problem)):
        pp = make("rss")
        opt = allocate_process_optimum(pp)
        c0 = time.process_time()
        df = process_front(pp, objective="yield", seed=0).table
        cpu = time.process_time() - c0
        at = df[df["yield"] >= y3 - 1e-12]
        best = float(at.cost.min()) if len(at) else float("nan")
        print(f"{label}: {len(df)} front points, yield {df['yield'].min():.3f}..{df['yield'].max():.6f}; exact optimum at "
              f"yield {y3:.4f}: {opt.cost:.4f}; cheapest front point there {best:.4f} ({best / opt.cost - 1:+.2%}); "
              f"front CPU {cpu:.2f} s")


if __name__ == "__main__":
    warnings.simplefilter("ignore")
    yield_fronts()
    jacobian_speed()
    bb_vs_enumeration()
    ga_vs_optimum()
