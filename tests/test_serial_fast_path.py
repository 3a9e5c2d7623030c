"""The compiled serial-chain path (robots/mechanism/kinematics/serial.py) equals the general description path
(robots/mechanism/kinematics/tree.py) it replaces for serial arms (issue 23 item 5): sensitivities at
joint values, nonlinear pose errors (Monte Carlo) and the continued inverse geometry, on the UR5,
the redundant Panda (posture nearest the assembly), a mimic chain and a TOML serial arm with
constant offsets after its joints and parameters in its joint entries."""
from pathlib import Path

import numpy as np
import pytest

from evotol.robots.mechanism import MechanismModel, mechanism_from_dict

HERE = Path(__file__).resolve().parents[1] / "robots" / "mechanisms"

ARM = {
    "name": "RRP arm", "lengths": {"L1": 0.3, "L2": 0.25, "h": 0.1}, "angles": {"off": 0.2, "k": 1.0},
    "frame": [
        {"name": "A", "antecedent": "0", "joint": "revolute", "actuated": True, "theta": "q1", "r": "h"},
        {"name": "B", "antecedent": "A", "joint": "revolute", "actuated": True, "alpha": "pi/2", "d": "L1", "theta": "k*q2 + off"},
        {"name": "C", "antecedent": "B", "joint": "prismatic", "actuated": True, "alpha": "-pi/2", "d": "L2", "theta": 0.3, "r": "q3"},
        {"name": "E", "antecedent": "C", "d": 0.05, "theta": 0.4},
    ],
    "end_effector": {"frame": "E", "coordinates": [{"name": "x", "axis": "x", "low": 0.395, "high": 0.405},
                                                   {"name": "y", "axis": "y", "low": 0.23, "high": 0.24},
                                                   {"name": "z", "axis": "z", "low": 0.363, "high": 0.373}]},
    "assembly": {"pose": [0.39952007, 0.23509598, 0.36831087], "joints": {"q1": 0.5, "q2": 0.5, "q3": 0.1}},
    "tolerances": {"sources": ["A.tilt_?", "B.shift_?", "C.tilt_x", "E.shift_?", "E.tilt_?", "q?", "off", "k", "B.theta"]},
}


def pair(src, sources=None):
    fast = MechanismModel(src, sources=sources)
    slow = MechanismModel(src, sources=sources)
    slow._serial = None
    return fast, slow


@pytest.mark.parametrize("which", ["ur5", "panda", "arm"])
def test_fast_path_equals_general_path(which):
    src = mechanism_from_dict(ARM) if which == "arm" else HERE / f"{which}.toml"
    fast, slow = pair(src)
    assert fast._serial is not None
    poses = fast.workspace.latin_hypercube(12, seed=5)
    qf, qs = fast.joint_values(poses), slow.kin.inverse_geometry(poses)
    fast.kin._cache.clear()
    assert max(np.abs(qf[v] - qs[v]).max() for v in qs) < 1e-9
    S, Ss = fast.sensitivity_at_joints(qs), slow.sensitivity_at_joints(qs)
    assert np.abs(S - Ss).max() < 1e-12 * max(np.abs(Ss).max(), 1.0)
    assert np.abs(fast.sensitivity(poses) - Ss).max() < 1e-8                  # through the inverse geometry
    E = np.random.default_rng(1).uniform(-1e-3, 1e-3, (len(poses), 7, fast.n_columns))
    D, Ds = fast.pose_error_at_joints(qs, E), slow.pose_error_at_joints(qs, E)
    assert np.abs(D - Ds).max() < 1e-13


@pytest.mark.parametrize("n, m", [(1, 5000), (173, 29)])
def test_parallel_monte_carlo_blocks_equal_the_general_path(n, m):
    """The Monte Carlo kernel cuts the pose-samples into parallel blocks of 2 048 (issue 43 item 2):
    blocks that split one pose's samples (1 x 5 000) and blocks that start mid-pose (173 x 29) give the
    general NumPy path's errors, also for a broadcast (zero-stride) error array."""
    fast, slow = pair(HERE / "ur5.toml")
    poses = fast.workspace.latin_hypercube(n, seed=3) if n > 1 else fast.workspace.latin_hypercube(4, seed=3)[:1]
    q = slow.kin.inverse_geometry(poses)
    E = np.random.default_rng(2).uniform(-1e-3, 1e-3, (n, m, fast.n_columns))
    D, Ds = fast.pose_error_at_joints(q, E), slow.pose_error_at_joints(q, E)
    assert D.shape == (n, m, 6)
    assert np.abs(D - Ds).max() < 1e-13
    Eb = np.broadcast_to(E[:1, :3], (n, 3, fast.n_columns))
    assert np.abs(fast.pose_error_at_joints(q, Eb) - slow.pose_error_at_joints(q, np.ascontiguousarray(Eb))).max() < 1e-13


def _ur5_errors_in_a_child(args):
    Q, E = args
    m = MechanismModel(HERE / "ur5.toml")
    return m._serial.pose_error(Q, E)


def test_parallel_monte_carlo_survives_a_fork_and_threads():
    """The Monte Carlo kernel runs on its thread pool in the parent, then in forked pool workers (the pool's
    threads do not exist there: task_threads makes a new pool after a fork) and in two threads at once (each
    runs the tasks in its own thread): every result equals the parent's."""
    import threading
    from concurrent.futures import ProcessPoolExecutor, ThreadPoolExecutor

    m = MechanismModel(HERE / "ur5.toml")
    poses = m.workspace.latin_hypercube(6, seed=1)
    q = m.joint_values(poses)
    Q = np.stack([q[v] for v in m.kin.variables], 1)
    E = np.random.default_rng(4).uniform(-1e-3, 1e-3, (6, 700, m.n_columns))   # 4 200 samples: 3 blocks
    D = m._serial.pose_error(Q, E)
    with ProcessPoolExecutor(2) as pool:
        for Dc in pool.map(_ur5_errors_in_a_child, [(Q, E), (Q, E)]):
            assert np.array_equal(Dc, D)
    assert threading.current_thread() is threading.main_thread()
    with ThreadPoolExecutor(2) as pool:
        for Dt in pool.map(lambda _: m._serial.pose_error(Q, E), range(4)):
            assert np.array_equal(Dt, D)


def test_unsupported_sources_use_the_general_path():
    """A parameter of a constant entry (the origin's x of a URDF joint) is not a fast-path source."""
    m = MechanismModel(HERE / "ur5.toml", sources=["elbow_joint_x", "elbow_joint"])
    assert m._serial is None
    assert MechanismModel(HERE / "fivebar.toml")._serial is None          # loops


def test_panda_poses_at_the_damped_floor_equal_forty_general_steps():
    """Issue 43 item 1: where the damping of the steps (1e-13 of the trace) leaves the Panda's scaled
    residual between 1e-12 and 2.1e-12, the compiled inverse geometry stops once no joint moves by more
    than 1e-13 (serial_newton.FLOOR, STILL) instead of running its 40 iterations. The general NumPy path
    runs all 40 for the batch: the same joints to 2e-12 rad (1.28e-12 here, as from main's compiled path,
    which ran the 40: the two paths' round-off at the damped fixed point), with far fewer evaluations."""
    fast, slow = pair(HERE / "panda.toml")
    run, seen = fast._serial.inverse_geometry, {}

    def spy(*args):
        seen["out"] = run(*args)
        return seen["out"]

    fast._serial.inverse_geometry = spy
    poses = fast.workspace.latin_hypercube(200, seed=0)
    qf = fast.joint_values(poses)
    _, res, evals = seen["out"]
    floor = res >= 1e-12                             # stopped at the floor, not at the tolerance
    assert floor.sum() >= 20 and (res < 1e-10).all()
    assert evals[floor].max() < 40 and evals.mean() < 25     # 10 continuation steps + a few at the pose
    qs = slow.kin.inverse_geometry(poses)
    assert max(np.abs(qf[v] - qs[v]).max() for v in qs) < 2e-12
