"""Drawing callouts against the equivalent placement sources, in one run (issue 35 item 7).

The same UR5 study twice: ``reports/studies/ur5_callouts.toml`` (per joint a position callout --
two disk sources tied to one tolerance -- and an axial callout, plus the joint offsets) and the same
task, requirement, poses and methods with the placement errors those callouts cover as raw
sources (``reports/studies/ur5_urdf.toml``'s 36 sources: per joint three shifts, two tilts and the
offset). Printed per step (CPU seconds of this process, the fastest of three calls; wall seconds
beside them) and the ratio callouts / placement sources; the target (<= 1.2) is on the whole
study, the steps of ``evotol run``: building the problem, the sensitivity rule, the certified
optimum, the study's GA (80 x 150) and its Monte Carlo check (300 samples, nonlinear model).
Diagnostics: the sensitivities at 1 000 poses (``S_base C``), the worst-case measure of 2 000
designs at every pose and at the poses that can hold the maximum (what the GA evaluates), and the
time of the exact-zones comparison that the callout study adds to its report.

``python benchmarks/bench_callouts.py [--quick]``.
"""
from __future__ import annotations

import argparse
import os
import time
import tomllib
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]


def timed(f):
    c0, w0 = time.process_time(), time.perf_counter()
    out = f()
    return out, time.process_time() - c0, time.perf_counter() - w0


def best(f, repeat: int = 3):
    """(result, cpu, wall) of the fastest of ``repeat`` calls."""
    runs = [timed(f) for _ in range(repeat)]
    k = int(np.argmin([r[1] for r in runs]))
    return runs[k]


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="one call per step instead of the fastest of three")
    args = ap.parse_args(argv)
    repeat = 1 if args.quick else 3

    from evotol.allocators import allocate_ga, allocate_optimum, allocate_sensitivity
    from evotol.studyfile import load_problem
    from evotol.studyfile.callouts import zone_comparison
    from evotol.verification.montecarlo import verify

    studies = ROOT / "reports" / "studies"
    spec_c = tomllib.loads((studies / "ur5_callouts.toml").read_text())
    spec_p = tomllib.loads((studies / "ur5_urdf.toml").read_text())
    # the same cost per source kind: the placement study prices its shifts/tilts as the callouts
    print(f"load average at start: {os.getloadavg()[0]:.1f} ({os.cpu_count()} cores)")
    rows = []
    probs = {}
    for key, spec in (("callouts", spec_c), ("placement sources", spec_p)):
        probs[key] = best(lambda: load_problem(spec, studies), repeat)
    Pc, Pp = probs["callouts"][0], probs["placement sources"][0]
    print(f"callouts: {Pc.n_sources} sources ({Pc.model.n_columns} columns), {Pc.n_variables} variables; "
          f"placement sources: {Pp.n_sources} sources, {Pp.n_variables} variables")
    study = [("build the problem (27 poses)", probs["callouts"][1:], probs["placement sources"][1:])]
    study.append(("sensitivity rule", best(lambda: allocate_sensitivity(Pc), repeat)[1:],
                  best(lambda: allocate_sensitivity(Pp), repeat)[1:]))
    oc, op = best(lambda: allocate_optimum(Pc), repeat), best(lambda: allocate_optimum(Pp), repeat)
    study.append(("certified optimum", oc[1:], op[1:]))
    study.append(("GA 80 x 150 (the study's)",
                  best(lambda: allocate_ga(Pc, pop_size=80, n_gen=150, seed=0, progress=False), repeat)[1:],
                  best(lambda: allocate_ga(Pp, pop_size=80, n_gen=150, seed=0, progress=False), repeat)[1:]))
    study.append(("Monte Carlo check, 300 samples (nonlinear)",
                  best(lambda: verify(Pc, oc[0].tolerances, n_samples=300, seed=0), repeat)[1:],
                  best(lambda: verify(Pp, op[0].tolerances, n_samples=300, seed=0), repeat)[1:]))
    poses = Pc.model.workspace.latin_hypercube(1000, seed=0)
    rng = np.random.default_rng(0)
    Xc = Pc.full(rng.uniform(5e-6, 5e-5, (2000, Pc.n_variables)))
    Xp = Pp.full(rng.uniform(5e-6, 5e-5, (2000, Pp.n_variables)))
    parts = [("sensitivities at 1000 poses", best(lambda: Pc.model.sensitivity(poses), repeat)[1:],
              best(lambda: Pp.model.sensitivity(poses), repeat)[1:]),
             ("worst case at every pose, 2000 designs", best(lambda: Pc.evaluate(Xc), repeat)[1:],
              best(lambda: Pp.evaluate(Xp), repeat)[1:]),
             ("worst case, poses that can hold the max", best(lambda: Pc.evaluate(Xc, top_only=True), repeat)[1:],
              best(lambda: Pp.evaluate(Xp, top_only=True), repeat)[1:])]
    head = f"{'step':44s} {'callouts cpu (wall) s':>24s} {'placement cpu (wall) s':>24s} {'ratio':>7s}"
    print("== the study's steps (evotol run without the comparison) ==")
    print(head)
    tc = tp = 0.0
    for name, (cc, cw), (pc, pw) in study:
        tc, tp = tc + cc, tp + pc
        print(f"{name:44s} {cc:12.4f} ({cw:8.4f}) {pc:12.4f} ({pw:8.4f}) {cc / pc:7.2f}")
    print(f"{'whole study':44s} {tc:12.4f} {'':10s} {tp:12.4f} {'':10s} {tc / tp:7.2f}   (target <= 1.2: "
          f"{'OK' if tc / tp <= 1.2 else 'MISSED'})")
    print("== parts (diagnostics) ==")
    print(head)
    for name, (cc, cw), (pc, pw) in parts:
        print(f"{name:44s} {cc:12.4f} ({cw:8.4f}) {pc:12.4f} ({pw:8.4f}) {cc / pc:7.2f}")
    cmp_ = best(lambda: zone_comparison(Pc), 1)
    print(f"the exact-zones comparison the callout study adds (a second certified optimum under boxes and the "
          f"nonlinear checks): {cmp_[1]:.3f} s cpu ({cmp_[2]:.3f} s wall)")

if __name__ == "__main__":
    main()
