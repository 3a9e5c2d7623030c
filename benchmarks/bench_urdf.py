"""URDF arms against Pinocchio, in one run (issue 23 item 5): UR5 and Panda, 1 000 and 10 000 poses.

Printed per arm and size (CPU seconds of this process, so a loaded machine measures the same work;
wall seconds beside them), and the ratio evotol / Pinocchio (<= 1 means evotol is at least as fast):

Each sensitivity timing is the fastest of three calls, for evotol and for Pinocchio alike.

1. **sensitivities at given joint values**: ``MechanismModel.sensitivity_at_joints`` (all default
   sources) against Pinocchio's fastest regressor loop, per pose ``forwardKinematics`` +
   ``computeFrameKinematicRegressor`` (``LOCAL_WORLD_ALIGNED``; the faster of that and
   ``framesForwardKinematics`` + the regressor);
2. **the public path with the inverse geometry**: ``MechanismModel.sensitivity(poses)`` with empty
   caches (continued Newton from the assembly, the posture check of a 6-joint arm, then the
   sensitivities; until issue 43 item 1 the posture check's cache stayed warm from an earlier call
   and its time was left out) against a per-pose
   damped-Newton IK in Pinocchio (from the assembly configuration, ``log6`` error in the tip frame,
   damped least squares ``J^T (J J^T + 1e-12 I)^-1``, to 1e-12, then the regressor);
3. **nonlinear Monte Carlo**: ``evotol.verification.nonlinear.verify_nonlinear`` of the UR5 study's optimum
   (the study's own verification) and ``pose_error`` alone, in pose-samples per second (its first call on
   new poses, which includes their inverse geometry, then the fastest of three with the joint values cached:
   the rate the issue's target reads);
4. **the Monte Carlo kernel before and after** (issue 43 item 2): the scalar kernel
   (``SerialChain._pose_error_scalar``) and the batched one (``serial_montecarlo``) on the same poses and
   samples, their ratio (less noisy than either rate on a shared machine) and the load average; the
   batched kernel alone on one thread and on every thread, the share of the Python wrapper, the
   arithmetic per pose-sample against the machine's SIMD peak, the split of its time between the
   samples' operations and their application (the batched kernel minus ``pose_error_shared``, one thread),
   the samples shared by every pose (``pose_error_shared``); the UR5 study's ``verify_nonlinear`` with each kernel and a cProfile of it.

Run it from the repository root with ``PYTHONPATH=.`` to measure this checkout (``python benchmarks/...``
puts ``benchmarks/`` first on ``sys.path``, so an installed evotol would be imported instead).

``python benchmarks/bench_urdf.py [--quick]``. The first call compiles the kernels (numba, cached
on disk), so every timing below is of a second call.
"""
from __future__ import annotations

import argparse
import os
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
ARMS = {"UR5": "ur5", "Panda": "panda"}


def timed(f):
    c0, w0 = time.process_time(), time.perf_counter()
    out = f()
    return out, time.process_time() - c0, time.perf_counter() - w0


def best(f, repeat: int = 3):
    """(cpu, wall) of the fastest of ``repeat`` calls (both sides get the same treatment)."""
    runs = [timed(f)[1:] for _ in range(repeat)]
    return min(r[0] for r in runs), min(r[1] for r in runs)


def pin_setup(robot):
    import pinocchio as pin

    from evotol.robots.mechanism.urdf.reader import frame_id

    path, tip = robot.mechanism.urdf
    model = pin.buildModelFromUrdf(path)
    return pin, model, model.createData(), frame_id(model, tip)


def repeats(n_poses: int) -> int:
    """Calls of which the fastest is kept: 15 for calls on up to 1 000 poses (about a millisecond, where
    one call's CPU time swings by a third between runs), 3 above; both sides of a ratio the same."""
    return 15 if n_poses <= 1000 else 3


def pin_regressor_loop(robot, Q):
    pin, model, data, fid = pin_setup(robot)
    Qp = np.zeros((len(Q), model.nq))
    Qp[:, :Q.shape[1]] = Q
    ref = pin.LOCAL_WORLD_ALIGNED

    def a():
        for q in Qp:
            pin.forwardKinematics(model, data, q)
            pin.computeFrameKinematicRegressor(model, data, fid, ref)

    def b():
        for q in Qp:
            pin.framesForwardKinematics(model, data, q)
            pin.computeFrameKinematicRegressor(model, data, fid, ref)

    return min(best(a, repeats(len(Q))), best(b, repeats(len(Q))))


def pin_ik_loop(robot, poses, q_asm, Rt):
    """Damped-Newton IK per pose (Pinocchio's documented CLIK), then the regressor; (cpu, wall, iters)."""
    pin, model, data, fid = pin_setup(robot)
    nv = len(q_asm)
    q0 = np.zeros(model.nq)
    q0[:nv] = q_asm
    iters = [0]

    def run():
        for x in poses:
            target = pin.SE3(Rt, np.asarray(x, float))
            q = q0.copy()
            for it in range(100):
                pin.framesForwardKinematics(model, data, q)
                err = pin.log6(target.actInv(data.oMf[fid])).vector
                if np.abs(err).max() < 1e-12:
                    break
                J = pin.computeFrameJacobian(model, data, q, fid, pin.LOCAL)[:, :nv]
                J = -pin.Jlog6(target.actInv(data.oMf[fid])) @ J
                dq = -J.T @ np.linalg.solve(J @ J.T + 1e-12 * np.eye(6), err)
                q[:nv] = q[:nv] - dq
            iters[0] += it
            pin.computeFrameKinematicRegressor(model, data, fid, pin.LOCAL_WORLD_ALIGNED)

    c, w = best(run, 3)                   # fastest of 3, as the cold calls of ours it is compared with
    return c, w, iters[0] / (3 * len(poses))


def inverse_geometry_parts(robot, poses):
    """(CPU s of the compiled inverse geometry, CPU s of the posture check, mean task evaluations per
    pose) on ``poses``, each with an empty cache (general path: NaN for the evaluations)."""
    from evotol.robots.mechanism.kinematics import serial as serial_module
    from evotol.robots.mechanism.posture.held import check_posture

    ch, seen = robot._serial, {}
    robot.kin._cache.clear()
    if ch is None:
        q, c_ig, _ = timed(lambda: robot.kin.inverse_geometry(poses))
    else:
        run = ch.inverse_geometry
        ch.inverse_geometry = lambda *a: seen.setdefault("out", run(*a))
        try:
            q, c_ig, _ = timed(lambda: serial_module.serial_inverse_geometry(robot.kin, ch, poses))
        finally:
            del ch.inverse_geometry
    robot.__dict__.pop("_posture_checked", None)
    _, c_held, _ = timed(lambda: check_posture(robot, poses, q))
    return c_ig, c_held, float(np.mean(seen["out"][2])) if seen else float("nan")


def flops_per_sample(chain) -> int:
    """Arithmetic operations of one pose-sample of the batched kernel, counted from its code
    (robots/mechanism/kinematics/serial_montecarlo.py): per operation with placement errors the
    series coefficients (33) and Rodrigues (75) and a per-lane 3x4 product (63); per joint error the
    sin/cos series (25) and the rotation (18, a translation 6); per constant a 3x4 product (63); the
    terms' sums; the tip error and its rotation vector (70). No transcendental call below 0.1 rad."""
    from evotol.robots.mechanism.kinematics.serial_montecarlo import program

    seg_start, _, _, op_stage, op_p = program(chain)[:5]
    ops = 70 + len(chain.p_terms) + len(chain.v_col) + 3 * len(chain.j_col)
    for k in range(len(op_stage)):
        ops += (33 + 75 + 63) * (op_p[k + 1] > op_p[k])
        if op_stage[k] >= 0:
            ops += 43 if chain.kind[op_stage[k]] == 1 else 6
        ops += 63 * (seg_start[k + 2] > seg_start[k + 1])
    return int(ops)


def machine_peak() -> tuple[float, int, float]:
    """(GHz, float64 SIMD lanes, peak flop/s of all cores): lanes from lscpu's flags (AVX-512: 8,
    AVX2: 4), two FMA ports a core (2 flops each)."""
    flags, ghz = "", float("nan")
    try:
        for line in open("/proc/cpuinfo"):
            if line.startswith("flags") and not flags:
                flags = line
            if line.startswith("cpu MHz"):
                ghz = max(0.0 if ghz != ghz else ghz, float(line.split(":")[1]) / 1e3)
    except (OSError, ValueError):
        pass
    lanes = 8 if "avx512f" in flags else 4 if "avx2" in flags else 2
    return ghz, lanes, os.cpu_count() * ghz * 1e9 * lanes * 2 * 2


def mc_profile(robot, poses, E) -> None:
    """Where the Monte Carlo time goes: the batched kernel alone on 1 and on every thread (CPU and wall),
    the Python wrapper around it, and the arithmetic per pose-sample against the machine's SIMD peak;
    the samples shared by every pose (verify_nonlinear's broadcast array) on their own line."""
    import numba

    from evotol.robots.mechanism.kinematics import serial_montecarlo as mc

    ch = robot._serial
    Q = ch.joints_array(robot.joint_values(poses))
    args = (ch.P, ch.kind, ch.var, ch.a, ch.c, *mc.program(ch), ch.v_col, ch.v_var, Q, E)
    n = E.shape[0] * E.shape[1]
    threads = numba.get_num_threads()
    rates, shared1 = {}, None
    for k in sorted({1, threads}):
        numba.set_num_threads(k)
        mc.pose_error(*args)
        c, w = best(lambda: mc.pose_error(*args))
        rates[k] = (n / c, n / w)
        if k == 1:
            mc.pose_error_shared(*args[:-1], E[0])
            shared1 = best(lambda: mc.pose_error_shared(*args[:-1], E[0]))[0] / n
    numba.set_num_threads(threads)
    Eb = np.broadcast_to(E[0], E.shape)                   # the same samples at every pose
    mc.pose_error_shared(*args[:-1], E[0])
    c_sh, w_sh = best(lambda: mc.pose_error_shared(*args[:-1], E[0]))
    c_sc, w_sc = best(lambda: ch._pose_error_scalar(Q, Eb))
    _, w_pub = best(lambda: robot.pose_error(poses, E))
    ops = flops_per_sample(ch)
    ghz, lanes, peak = machine_peak()
    r1, rt = rates[1][0], rates[threads][1]
    print(f"  Monte Carlo profile (batched kernel): 1 thread {r1:.3g} pose-samples/s per CPU second; {threads} threads "
          f"{rates[threads][0]:.3g} per CPU second, {rt:.3g} wall; public pose_error {n / w_pub:.3g}/s wall "
          f"(wrapper: inverse geometry cache, checks, {100 * max(0.0, 1 - n / w_pub / rt):.0f} % of its time)")
    print(f"    where its time goes (1 thread, CPU ns per pose-sample): {1e9 / r1:.0f} in all; the operations (errors "
          f"gathered into lanes, placement exponentials, joint coefficients) {1e9 * (1 / r1 - shared1):.0f} (batched minus "
          f"shared); applying them to the pose's constants and the tip error {1e9 * shared1:.0f} (pose_error_shared, "
          f"which computes the operations once for all poses)")
    print(f"    per pose-sample ~{ops} operations: {r1 * ops / 1e9:.2f} Gflop/s per core achieved; peak of "
          f"{os.cpu_count()} cores at {ghz:.1f} GHz with {lanes} float64 lanes x 2 FMA {peak / 1e9:.0f} Gflop/s = "
          f"{peak / ops:.3g} pose-samples/s; reached {os.cpu_count() * r1 / (peak / ops):.0%} (CPU-time rate x cores)")
    print(f"    samples shared by every pose (pose_error_shared, verify_nonlinear's case): {n / c_sh:.3g} per CPU second "
          f"({n / w_sh:.3g} wall) vs scalar kernel {n / c_sc:.3g} ({n / w_sc:.3g} wall): after/before x{c_sc / c_sh:.2f} CPU, "
          f"x{w_sc / w_sh:.2f} wall")


def main(quick: bool = False) -> None:
    from evotol.verification.nonlinear import verify_nonlinear
    from evotol.allocators import allocate_optimum
    from evotol.studyfile import load_problem
    from evotol.robots.mechanism import MechanismModel

    import tomllib

    sizes = (200, 1000) if quick else (1000, 10000)
    print(f"load average {os.getloadavg()[0]:.1f} on {os.cpu_count()} cores; times: CPU s (wall s)")
    for label, name in ARMS.items():
        robot = MechanismModel(ROOT / "robots" / "mechanisms" / f"{name}.toml")
        robot.sensitivity(robot.workspace.latin_hypercube(5, seed=9))          # compile / load the kernels
        x0, q0 = robot.kin.assembly()
        q_asm = np.array([q0[v] for v in robot.kin.variables])
        Rt = robot.kin._target_orientation(x0[None])[0]
        fast = "compiled serial chain" if robot._serial is not None else "general NumPy path"
        print(f"\n{label}: {robot.n_columns} sources, {len(robot.kin.variables)} joints ({fast})")
        for n in sizes:
            poses = robot.workspace.latin_hypercube(n, seed=0)
            q = robot.joint_values(poses)
            Q = np.stack([q[v] for v in robot.kin.variables], 1)
            c_s, w_s = best(lambda: robot.sensitivity_at_joints(Q), repeats(n))
            c_p, w_p = pin_regressor_loop(robot, Q)
            def cold():
                robot.kin._cache.clear()
                robot.__dict__.pop("_posture_checked", None)      # the posture check is part of the public path
                robot.__dict__.pop("_solved", None)               # and the inverse geometry: no joint values kept
                return timed(lambda: robot.sensitivity(poses))[1:]

            c_pub, w_pub = (min(r) for r in zip(*(cold() for _ in range(3))))     # fastest of 3 cold calls
            c_ig, c_held, evals = inverse_geometry_parts(robot, poses)
            n_ik = min(n, 1000)                          # Pinocchio's IK loop timed on 1 000 poses, scaled
            c_ik, w_ik, it = pin_ik_loop(robot, poses[:n_ik], q_asm, Rt)
            c_ik, w_ik = c_ik * n / n_ik, w_ik * n / n_ik
            print(f"  {n:6d} poses  sensitivities at joints {c_s:.4f} ({w_s:.4f}) vs Pinocchio regressor loop "
                  f"{c_p:.4f} ({w_p:.4f}): ratio {c_s / c_p:.2f}")
            print(f"  {n:6d} poses  with inverse geometry    {c_pub:.4f} ({w_pub:.4f}) vs Pinocchio IK + regressor "
                  f"{c_ik:.3f} ({w_ik:.3f}; {it:.1f} iterations/pose{', scaled from 1 000' if n > n_ik else ''}): "
                  f"ratio {c_pub / c_ik:.3f}")
            print(f"  {n:6d} poses    of which the inverse geometry {c_ig:.4f} ({evals:.1f} task evaluations/pose), "
                  f"the posture check {c_held:.4f} ({100 * c_held / c_pub:.0f} % of the public call)")
        m = 300
        poses = robot.workspace.latin_hypercube(1000, seed=1)
        E = np.random.default_rng(0).uniform(-1e-4, 1e-4, (len(poses), m, robot.n_columns))
        robot.pose_error(poses[:4], np.ascontiguousarray(E[:4, :4]))   # compile / load E's layout (C-contiguous)
        robot.__dict__.pop("_solved", None)                            # no joint values kept from earlier sets
        _, c_ig, w_ig = timed(lambda: robot.pose_error(poses, E))      # with the inverse geometry of the new poses
        c_mc, w_mc = best(lambda: robot.pose_error(poses, E), 10)      # the joint values cached: the Monte Carlo
        print(f"  pose_error: {len(poses)} poses x {m} samples, first call with the inverse geometry of the poses "
              f"{c_ig:.3f} s CPU, {w_ig:.3f} s wall; then, joint values cached (best of 10), {c_mc:.3f} ({w_mc:.3f}): "
              f"{len(poses) * m / c_mc:.3g} pose-samples/s CPU ({len(poses) * m / w_mc:.3g} wall)")
        if robot._serial is not None:
            Q = robot._serial.joints_array(robot.joint_values(poses))
            after = best(lambda: robot._serial.pose_error(Q, E))
            before = best(lambda: robot._serial._pose_error_scalar(Q, E))
            n_ps = len(poses) * m
            print(f"  kernel before (scalar, one sample at a time) {n_ps / before[0]:.3g} CPU ({n_ps / before[1]:.3g} wall), "
                  f"after (batched) {n_ps / after[0]:.3g} CPU ({n_ps / after[1]:.3g} wall) pose-samples/s: "
                  f"after/before x{before[0] / after[0]:.2f} CPU, x{before[1] / after[1]:.2f} wall "
                  f"(load {os.getloadavg()[0]:.1f})")
            mc_profile(robot, poses, E)
    spec = tomllib.loads((ROOT / "reports" / "studies" / "ur5_urdf.toml").read_text())
    spec["poses"] = {"grid": [10, 10, 10]}
    problem = load_problem(spec, ROOT / "reports" / "studies")
    t = allocate_optimum(problem).tolerances
    verify_nonlinear(problem, t, n_samples=10)
    chain = type(problem.robot._serial)
    rates = {}
    for label, kernel in (("before", chain._pose_error_scalar), ("after", chain.pose_error)):
        chain.pose_error, saved = kernel, chain.pose_error            # the scalar kernel behind the same call
        try:
            verify_nonlinear(problem, t, n_samples=10)
            _, c_v, w_v = timed(lambda: verify_nonlinear(problem, t, n_samples=300))
        finally:
            chain.pose_error = saved
        rates[label] = (problem.n_poses * 300 / c_v, problem.n_poses * 300 / w_v)
        print(f"\nUR5 study verification {label} (verify_nonlinear, 10x10x10 grid, 300 samples): {c_v:.2f} s CPU "
              f"({w_v:.2f} wall), {rates[label][0]:.3g} pose-samples/s CPU ({rates[label][1]:.3g} wall)")
    print(f"  after/before x{rates['after'][0] / rates['before'][0]:.2f} CPU, x{rates['after'][1] / rates['before'][1]:.2f} wall; "
          f"load average {os.getloadavg()[0]:.1f} on {os.cpu_count()} cores")
    # the check's fixed parts (the linear worst case of each constrained component, once: its maximisers
    # are the worst vertices and its value the report's; the worst vertices through the kernel, one
    # sample a pose in a 64-lane group) do not
    # grow with the samples: the Monte Carlo's own rate is the slope between 300 and 3 000 samples
    n_big = 3000
    c_big, w_big = best(lambda: verify_nonlinear(problem, t, n_samples=n_big))       # best of 3 each: a
    c_300, w_300 = best(lambda: verify_nonlinear(problem, t, n_samples=300))         # slope amplifies noise
    extra = problem.n_poses * (n_big - 300)
    print(f"  its Monte Carlo (the slope from 300 to {n_big} samples): {c_big:.3f} s CPU ({w_big:.3f} wall) against "
          f"{c_300:.3f} ({w_300:.3f}): {extra / (c_big - c_300):.3g} pose-samples/s CPU ({extra / (w_big - w_300):.3g} wall); "
          f"the parts that do not grow with the samples {w_300 - 300 * problem.n_poses * (w_big - w_300) / extra:.3f} s wall")
    import cProfile
    import pstats

    pr = cProfile.Profile()
    pr.enable()
    verify_nonlinear(problem, t, n_samples=300)
    pr.disable()
    st = pstats.Stats(pr)
    top = sorted(st.stats.items(), key=lambda kv: -kv[1][2])[:5]
    print("  where verify_nonlinear's time goes (cProfile, own time): " + ", ".join(
        f"{Path(fn[0]).stem}.{fn[2]} {100 * v[2] / st.total_tt:.0f} %" for fn, v in top))

if __name__ == "__main__":
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--quick", action="store_true")
    main(ap.parse_args().quick)
