"""Benchmark of the joint-clearance engine (issue 6): speed and agreement against the thesis's method.

Prints, in one run:
* the 5-bar 41 x 41 closed-loop map (target < 10 s) and its largest certified gap (target <= 1e-3);
* the thesis's method (QR elimination + multistart SLSQP) on the same kind of points: time per
  pose, speed-up of the certified engine, agreement of the values, starts stuck at local maxima;
* the IRSBot-2 41 x 41 maps, distal module (78 variables) and distal + parallelograms (114
  variables, target < 2 min), with the thesis's method on two points;
* 32 768 clearance-bound sets of the 5-bar at one pose (the tolerance-synthesis workload);
* issue 13: the engine against its settings before issue 13 (``options=LEGACY``, :mod:`evotol.robots.clearance.options`) on the same
  IRSBot-2 points in one process: time and Newton-iteration ratios, agreement of the brackets;
* the compiled Newton iteration (``evotol.robots.clearance.newton_kernel``) against the NumPy one
  (``options=NUMPY``) on the same points in one process.

Absolute times depend on the load of this shared 2-core machine (printed with ``uptime``'s load
average); compare ratios measured in one run.

Run: ``python benchmarks/bench_clearance.py`` (``--quick`` for a smaller run).
"""
from __future__ import annotations

import argparse
import itertools
import time

import numpy as np


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="smaller grids and fewer starts")
    ap.add_argument("--workers", type=int, default=None, help="local processes for the grid maps (default: all cores)")
    args = ap.parse_args(argv)

    from evotol.robots.clearance import ClearanceEvaluator, max_pose_error, multistart_max_pose_error
    from evotol.robots.clearance.grid import grid_max_pose_error
    from evotol.robots.fivebar import FiveBar
    from evotol.robots.irsbot2 import MAP_WORKSPACE, IRSBot2
    import os

    print(f"load average at start: {os.getloadavg()[0]:.1f} ({os.cpu_count()} cores)")

    n = 21 if args.quick else 41
    starts = 5 if args.quick else 20
    print(f"== 5-bar linkage (Deng 2012 Ch. IV), {n} x {n} grid ==")
    fb = FiveBar()
    mech = fb.clearance_mechanism()
    poses = fb.workspace.grid(n)
    t = time.perf_counter()
    serial = max_pose_error(mech, poses)
    t_serial = time.perf_counter() - t
    res = grid_max_pose_error(mech, poses, workers=args.workers)
    print(f"closed-loop map: {t_serial:.2f} s in one process, {res.seconds:.2f} s on local workers "
          f"(target < 10 s); largest relative gap {max(serial.gap.max(), res.gap.max()):.2e} (target <= 1e-3)")
    pts = np.array([[0.0, 0.07], [0.01, 0.05], [-0.02, 0.03], [0.015, 0.045], [-0.005, 0.062]])[: 2 if args.quick else 5]
    ms = multistart_max_pose_error(mech, pts, n_starts=starts, seed=0)
    ours = max_pose_error(mech, pts)
    per_ms = ms.seconds / len(pts)
    per_ours = t_serial / len(poses)
    rel = np.maximum(np.abs(ms.p_max - ours.p_max) / ours.p_max, np.abs(ms.r_max - ours.r_max) / ours.r_max)
    stuck = [int(np.sum(np.asarray(l) < ours.p_max[i] * (1 - 1e-3))) for i, l in enumerate(ms.p_locals)]
    print(f"thesis's method ({ms.n_variables} variables, {starts} SLSQP starts per pose and quantity): "
          f"{per_ms:.2f} s per pose; certified engine {per_ours * 1e3:.2f} ms per pose -> speed-up x{per_ms / per_ours:.0f} "
          f"(x{per_ms * 200 / starts / per_ours:.0f} against the thesis's 200 starts)")
    print(f"agreement: max relative difference {rel.max():.1e}; multistart never above the certified bound: "
          f"{bool(np.all(ms.p_max <= ours.p_upper * (1 + 1e-9)) and np.all(ms.r_max <= ours.r_upper * (1 + 1e-9)))}; "
          f"starts stopped > 0.1 % below the global maximum: {stuck} of {starts}")

    print(f"\n== IRSBot-2 (Deng 2012 Ch. VI), {n} x {n} grid ==")
    robot = IRSBot2.thesis("VI.1")
    grid = MAP_WORKSPACE.grid(n)
    for par, label in ((False, "distal module"), (True, "distal + parallelograms")):
        m2 = robot.clearance_mechanism(parallelograms=par)
        r2 = grid_max_pose_error(m2, grid, workers=args.workers)
        pm = m2.pose_maps(grid[:1])[0]
        v = pm.n_rows - pm.n_loops
        tgt = " (target < 120 s)" if par else ""
        print(f"{label} ({v} variables): {r2.seconds:.1f} s{tgt}, largest gap {r2.gap.max():.2e}, "
              f"{r2.n_solves} convex solves")
        p2 = grid[[len(grid) // 2, len(grid) // 3]]
        ms2 = multistart_max_pose_error(m2, p2, n_starts=3 if args.quick else 6, seed=0)
        o2 = max_pose_error(m2, p2)
        per_ms2 = ms2.seconds / len(p2)
        print(f"   thesis's method, {3 if args.quick else 6} starts: {per_ms2:.1f} s per pose vs {r2.seconds / len(grid) * 1e3:.1f} ms "
              f"(x{per_ms2 / (r2.seconds / len(grid)):.0f}); best local p / certified p = "
              f"{np.round(ms2.p_max / o2.p_max, 4).tolist()}, r: {np.round(ms2.r_max / o2.r_max, 4).tolist()}")

    print(f"\n== issue 13: engine vs its settings before issue 13, same points, one process ==")
    from evotol.robots.clearance.options import LEGACY, NUMPY
    sub = grid[:: 40 if args.quick else 8]
    cases = [(robot.clearance_mechanism(parallelograms=False), sub, "IRSBot-2 distal module"),
             (robot.clearance_mechanism(parallelograms=True), sub, "IRSBot-2 distal + parallelograms"),
             (mech, poses[:: 4 if args.quick else 8], "5-bar (planar targets)")]
    for m2, sub, label in cases:
        out = {}
        for name in ("legacy", "new", "legacy again"):
            t = time.perf_counter()
            r = max_pose_error(m2, sub, **({"options": LEGACY} if name.startswith("legacy") else {}))
            out[name] = (time.perf_counter() - t, r.n_newton, r)
        (tl, nl, rl), (tn, nn, rn), (tl2, _, _) = out["legacy"], out["new"], out["legacy again"]
        overlap = bool(np.all(rn.p_max <= rl.p_upper * (1 + 1e-12)) and np.all(rl.p_max <= rn.p_upper * (1 + 1e-12))
                       and np.all(rn.r_max <= rl.r_upper * (1 + 1e-12)) and np.all(rl.r_max <= rn.r_upper * (1 + 1e-12)))
        print(f"{label}, {len(sub)} poses: before {tl:.1f} s / {tl2:.1f} s (two runs), now {tn:.1f} s -> "
              f"x{2 * tn / (tl + tl2):.2f} of the time; Newton iterations {nl} -> {nn} (x{nn / nl:.2f}); "
              f"convex solves {rl.n_solves} -> {rn.n_solves}; largest gap {rl.gap.max():.1e} -> {rn.gap.max():.1e}; "
              f"brackets overlap at every pose: {overlap}; max |p_now/p_before - 1| = {np.abs(rn.p_max / rl.p_max - 1).max():.1e}")

    print(f"\n== compiled Newton iteration (numba) vs NumPy iteration, same points, one process ==")
    from evotol.robots.clearance import newton_kernel
    if not newton_kernel.AVAILABLE:
        print("numba not available: skipped")
    for m2, sub, label in cases if newton_kernel.AVAILABLE else ():
        max_pose_error(m2, sub[:2])              # load the compiled kernel outside the timing
        ts = {}
        for name in ("numpy", "compiled", "numpy again", "compiled again"):
            t = time.process_time()
            r = max_pose_error(m2, sub, **({"options": NUMPY} if name.startswith("numpy") else {}))
            ts[name] = (time.process_time() - t, r)
        tn = ts["numpy"][0] + ts["numpy again"][0]
        tc = ts["compiled"][0] + ts["compiled again"][0]
        ra, rb = ts["numpy"][1], ts["compiled"][1]
        overlap = bool(np.all(ra.p_max <= rb.p_upper * (1 + 1e-12)) and np.all(rb.p_max <= ra.p_upper * (1 + 1e-12)))
        print(f"{label}, {len(sub)} poses: NumPy {ts['numpy'][0]:.2f} / {ts['numpy again'][0]:.2f} s CPU, compiled "
              f"{ts['compiled'][0]:.2f} / {ts['compiled again'][0]:.2f} s -> x{tc / tn:.2f} of the time; brackets overlap: {overlap}")

    print("\n== 5-bar tolerance-synthesis workload: 32 768 bound sets at (0, 70) mm ==")
    ev = ClearanceEvaluator(mech, [[0.0, 0.07]])
    lv_xy = np.array([1e-4, 1e-3, 1e-2, 1e-1]) * 1e-3
    lv_z = np.array([1e-3, 1e-1]) * 1e-3
    cxy = np.array(list(itertools.product(range(4), repeat=5)))
    cz = np.array(list(itertools.product(range(2), repeat=5)))
    BXY = np.repeat(lv_xy[cxy], len(cz), axis=0)
    BZ = np.tile(lv_z[cz], (len(cxy), 1))
    for label, kw in (("beta_xy = 0.01 rad", {}), ("beta_xy = b_xy / h, h = 10 mm", {"h": 0.01})):
        if args.quick and kw:
            continue
        b = mech.thesis_bounds(b_xy=BXY, b_z=BZ, **kw)
        t = time.perf_counter()
        r = ev.evaluate(b, workers=args.workers)
        print(f"{label}: {time.perf_counter() - t:.1f} s for {len(b)} sets ({r.n_solves} convex solves after "
              f"deduplication), largest gap {r.gap.max():.2e}")
    few = b[:: 64 if args.quick else 16]            # issue 13: same bound sets, legacy settings vs now
    work = {}
    for name in ("legacy", "new"):
        t = time.perf_counter()
        r = (ClearanceEvaluator(mech, [[0.0, 0.07]], options=LEGACY) if name == "legacy" else ev).evaluate(few)
        work[name] = (time.perf_counter() - t, r.n_newton, r)
    (tl, nl, rl), (tn, nn, rn) = work["legacy"], work["new"]
    print(f"issue 13, {len(few)} of these sets: before {tl:.1f} s, now {tn:.1f} s; Newton iterations {nl} -> {nn} "
          f"(x{nn / nl:.2f}); largest gap {rl.gap.max():.1e} -> {rn.gap.max():.1e}; "
          f"max |p_now/p_before - 1| = {np.abs(rn.p_max / rl.p_max - 1).max():.1e}")


if __name__ == "__main__":
    main()
