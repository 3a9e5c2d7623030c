"""URDF arms against Pinocchio, in one run (issue 23 item 5): UR5 and Panda, 1 000 and 10 000 poses.

Printed per arm and size (CPU seconds of this process, so a loaded machine measures the same work;
wall seconds beside them), and the ratio evotol / Pinocchio (<= 1 means evotol is at least as fast):

Each sensitivity timing is the fastest of three calls, for evotol and for Pinocchio alike.

1. **sensitivities at given joint values**: ``MechanismModel.sensitivity_at_joints`` (all default
   sources) against Pinocchio's fastest regressor loop, per pose ``forwardKinematics`` +
   ``computeFrameKinematicRegressor`` (``LOCAL_WORLD_ALIGNED``; the faster of that and
   ``framesForwardKinematics`` + the regressor);
2. **the public path with the inverse geometry**: ``MechanismModel.sensitivity(poses)`` with an
   empty cache (continued Newton from the assembly, then the sensitivities) against a per-pose
   damped-Newton IK in Pinocchio (from the assembly configuration, ``log6`` error in the tip frame,
   damped least squares ``J^T (J J^T + 1e-12 I)^-1``, to 1e-12, then the regressor);
3. **nonlinear Monte Carlo**: ``evotol.verification.nonlinear.verify_nonlinear`` of the UR5 study's optimum
   (the study's own verification) and ``pose_error`` alone, in pose-samples per second;
4. **the Monte Carlo profile** (issue 43): the compiled kernel alone on one thread and on every thread,
   the share of the Python wrapper, and the arithmetic per sample against the machine's scalar limit.

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

    return min(best(a), best(b))


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

    _, c, w = timed(run)
    return c, w, iters[0] / len(poses)


def flops_per_sample(chain) -> tuple[int, int]:
    """(arithmetic operations, transcendental calls) of one Monte Carlo sample of the serial kernel,
    counted from its code: a placement exponential (Rodrigues, ~75 operations + sqrt, sin, cos) per
    perturbed mark, a 3x4 product (63) per stage that is not the identity and per perturbed mark, a
    joint motion (24 + sin, cos for a revolute), the relative rotation (27) and its rotation vector (~20 +
    arccos, sin)."""
    perturbed = len(set(chain.p_terms[:, 1].tolist()))
    ns, n_ident = len(chain.P), int(np.sum(chain.ident))
    n_joint = int(np.sum(chain.kind > 0))
    ops = 75 * perturbed + 63 * (ns - n_ident + perturbed) + 24 * n_joint + 27 + 20 + len(chain.p_terms)
    return ops, 3 * perturbed + 2 * int(np.sum(chain.kind == 1)) + 2


def mc_profile(robot, poses, E) -> None:
    """Where the Monte Carlo time goes: the kernel alone on 1 and on every thread, the Python
    wrapper around it, and the arithmetic it does against the machine's scalar limit."""
    import numba

    from evotol.robots.mechanism.kinematics.serial import _kernels

    ch = robot._serial
    q = robot.joint_values(poses)
    Q = np.stack([q[v] for v in robot.kin.variables], 1)
    K = _kernels()
    p = ch.p_terms
    args = (*ch._args(), Q, E, p[:, 0].copy(), p[:, 1].copy(), p[:, 2].copy(), ch.j_col, ch.j_stage, ch.j_coef,
            ch.j_var, ch.v_col, ch.v_var)
    n = E.shape[0] * E.shape[1]
    threads = numba.get_num_threads()
    rates = {}
    for k in sorted({1, threads}):
        numba.set_num_threads(k)
        K.pose_error(*args)
        rates[k] = n / best(lambda: K.pose_error(*args))[1]
    numba.set_num_threads(threads)
    _, w_pub = best(lambda: robot.pose_error(poses, E))
    ops, trans = flops_per_sample(ch)
    try:
        ghz = max(float(l.split(":")[1]) for l in open("/proc/cpuinfo") if l.startswith("cpu MHz")) / 1e3
    except (OSError, ValueError):
        ghz = float("nan")
    limit = threads * ghz * 1e9 * 4 / ops          # 2 scalar FMA ports = 4 operations a cycle per core
    print(f"  Monte Carlo profile: kernel {rates[1]:.3g} pose-samples/s on 1 thread, {rates[threads]:.3g} on {threads} "
          f"(x{rates[threads] / rates[1]:.2f}); public pose_error {n / w_pub:.3g}/s (wrapper "
          f"{100 * max(0.0, 1 - n / w_pub / rates[threads]):.0f} % of its time)")
    print(f"    per sample ~{ops} arithmetic operations + {trans} sin/cos/sqrt/arccos: "
          f"{rates[threads] * ops / 1e9:.2f} Gop/s achieved; scalar limit of {threads} cores at {ghz:.1f} GHz "
          f"(4 operations/cycle, no SIMD, transcendental calls not counted) {limit:.3g} pose-samples/s "
          f"= {rates[threads] / limit:.0%} reached")


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
            c_s, w_s = best(lambda: robot.sensitivity_at_joints(Q))
            c_p, w_p = pin_regressor_loop(robot, Q)
            robot.kin._cache.clear()
            _, c_pub, w_pub = timed(lambda: robot.sensitivity(poses))
            n_ik = min(n, 1000)                          # Pinocchio's IK loop timed on 1 000 poses, scaled
            c_ik, w_ik, it = pin_ik_loop(robot, poses[:n_ik], q_asm, Rt)
            c_ik, w_ik = c_ik * n / n_ik, w_ik * n / n_ik
            print(f"  {n:6d} poses  sensitivities at joints {c_s:.4f} ({w_s:.4f}) vs Pinocchio regressor loop "
                  f"{c_p:.4f} ({w_p:.4f}): ratio {c_s / c_p:.2f}")
            print(f"  {n:6d} poses  with inverse geometry    {c_pub:.4f} ({w_pub:.4f}) vs Pinocchio IK + regressor "
                  f"{c_ik:.3f} ({w_ik:.3f}; {it:.1f} iterations/pose{', scaled from 1 000' if n > n_ik else ''}): "
                  f"ratio {c_pub / c_ik:.3f}")
        m = 300
        poses = robot.workspace.latin_hypercube(1000, seed=1)
        E = np.random.default_rng(0).uniform(-1e-4, 1e-4, (len(poses), m, robot.n_columns))
        robot.pose_error(poses[:4], E[:4, :4])
        _, c_mc, w_mc = timed(lambda: robot.pose_error(poses, E))
        print(f"  pose_error: {len(poses)} poses x {m} samples in {c_mc:.3f} ({w_mc:.3f}): "
              f"{len(poses) * m / c_mc:.3g} pose-samples/s CPU ({len(poses) * m / w_mc:.3g} wall)")
        if robot._serial is not None:
            mc_profile(robot, poses, E)
    spec = tomllib.loads((ROOT / "reports" / "studies" / "ur5_urdf.toml").read_text())
    spec["poses"] = {"grid": [10, 10, 10]}
    problem = load_problem(spec, ROOT / "reports" / "studies")
    t = allocate_optimum(problem).tolerances
    verify_nonlinear(problem, t, n_samples=10)
    chk, c_v, w_v = timed(lambda: verify_nonlinear(problem, t, n_samples=300))
    print(f"\nUR5 study verification (verify_nonlinear, 10x10x10 grid, 300 samples): {c_v:.2f} s CPU ({w_v:.2f} wall), "
          f"{problem.n_poses * 300 / c_v:.3g} pose-samples/s CPU ({problem.n_poses * 300 / w_v:.3g} wall)")


if __name__ == "__main__":
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--quick", action="store_true")
    main(ap.parse_args().quick)
