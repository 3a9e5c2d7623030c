"""The batched serial-arm Monte Carlo kernel (robots/mechanism/kinematics/serial_montecarlo.py, issue 43
item 2) against three references: the general description path (robots/mechanism/kinematics/tree.py,
NumPy), the scalar kernel it replaced (serial_kernels.pose_error) and, written here, the product of
4x4 matrices P_s expm(twist) Rot_z(q) with SciPy's matrix exponential (independent of evotol's
Rodrigues formulas). Arms: the UR5 and the Panda (URDF), the PUMA 560 in standard and in modified DH
(placement sources), and a TOML arm with a prismatic joint, a mimic multiplier and a joint entry."""
from pathlib import Path

import numpy as np
import pytest
from scipy.linalg import expm

from evotol.robots.mechanism import MechanismModel, mechanism_from_dict
from evotol.robots.mechanism.kinematics.placement import PLACEMENT_FIELDS
from evotol.robots.mechanism.kinematics.serial_montecarlo import W

from tests.test_serial_fast_path import ARM

HERE = Path(__file__).resolve().parents[1] / "robots" / "mechanisms"
PLACED = ["?.tilt_?", "?.shift_?", "q?"]           # the DH arms' placement sources (the serial path)
ARMS = {"ur5": (HERE / "ur5.toml", None), "panda": (HERE / "panda.toml", None),
        "puma560": (HERE / "puma560.toml", PLACED), "puma560_modified": (HERE / "puma560_modified.toml", PLACED),
        "arm": (None, None)}


def models(which):
    path, sources = ARMS[which]
    src = mechanism_from_dict(ARM) if path is None else path
    fast, slow = MechanismModel(src, sources=sources), MechanismModel(src, sources=sources)
    slow._serial = None
    assert fast._serial is not None
    return fast, slow


def joints(model, n, seed):
    q = model.joint_values(model.workspace.latin_hypercube(n, seed=seed))
    return q, model._serial.joints_array(q)


@pytest.mark.parametrize("which", list(ARMS))
def test_equals_the_general_path_and_the_scalar_kernel(which):
    """Small errors (the Taylor series of every lane) and large ones (0.3 rad: the closed forms), at
    13 poses x (W + 5) samples (a full group of W lanes and a tail): <= 1e-12 m / rad of the general path."""
    fast, slow = models(which)
    q, Q = joints(fast, 13, 2)
    rng = np.random.default_rng(7)
    for scale in (1e-4, 1e-3, 0.3):
        E = rng.uniform(-scale, scale, (13, W + 5, fast.n_columns))
        D, Ds = fast.pose_error_at_joints(q, E), slow.pose_error_at_joints(q, E)
        assert np.abs(D - Ds).max() < 1e-12, (which, scale)
        assert np.abs(D - fast._serial._pose_error_scalar(Q, E)).max() < 1e-12
    assert np.array_equal(fast.pose_error_at_joints(q, np.zeros((13, 5, fast.n_columns))), np.zeros((13, 5, 6)))


def _expm_chain(ch, q, e):
    """The perturbed tip, written independently: 4x4 products with scipy.linalg.expm of each mark's
    twist (placement errors) and the joint offsets and joint terms added to the joint values."""
    qe = q.copy()
    for c, v in zip(ch.v_col, ch.v_var):
        qe[v] += e[c]
    T = np.eye(4)
    for s in range(len(ch.P)):
        T = T @ ch.P[s]
        d = np.zeros(6)
        for c, m, f in ch.p_terms:
            if m == ch.mark[s]:
                d[f] += e[c]
        X = np.zeros((4, 4))
        X[:3, :3] = [[0, -d[5], d[4]], [d[5], 0, -d[3]], [-d[4], d[3], 0]]
        X[:3, 3] = d[:3]
        T = T @ expm(X)
        if ch.kind[s] > 0:
            v = ch.a[s] * qe[ch.var[s]] + ch.c[s]
            for c, st, coef, jv in zip(ch.j_col, ch.j_stage, ch.j_coef, ch.j_var):
                if st == s:
                    v += e[c] * coef * (qe[jv] if jv >= 0 else 1.0)
            J = np.eye(4)
            if ch.kind[s] == 1:
                J[:2, :2] = [[np.cos(v), -np.sin(v)], [np.sin(v), np.cos(v)]]
            else:
                J[2, 3] = v
            T = T @ J
    return T


@pytest.mark.parametrize("which", ["ur5", "puma560", "arm"])
def test_equals_an_independent_matrix_exponential_chain(which):
    """Against the expm chain, including tilts of 1e-7 rad beside shifts of 1e-4 m, where the closed
    form (1 - cos t)/t^2 loses half its digits (the general path and the scalar kernel are off by up to 1.6e-13 m there;
    the series is not): within 2e-15 m, and the rotation within 2e-15 rad."""
    fast, _ = models(which)
    ch = fast._serial
    _, Q = joints(fast, 3, 4)
    rng = np.random.default_rng(3)
    E = rng.uniform(-1e-4, 1e-4, (3, 6, fast.n_columns))
    tilt = [c for c, col in enumerate(fast.columns) if isinstance(col, tuple) and col[1] in PLACEMENT_FIELDS[3:]]
    E[:, :3, tilt] *= 1e-3
    D = ch.pose_error(Q, E)
    for i in range(3):
        T0 = _expm_chain(ch, Q[i], np.zeros(fast.n_columns))
        for k in range(6):
            T = _expm_chain(ch, Q[i], E[i, k])
            assert np.abs(D[i, k, :3] - (T[:3, 3] - T0[:3, 3])).max() < 2e-15
            R = T[:3, :3] @ T0[:3, :3].T
            w = 0.5 * np.array([R[2, 1] - R[1, 2], R[0, 2] - R[2, 0], R[1, 0] - R[0, 1]])
            s = np.linalg.norm(w)
            assert np.abs(D[i, k, 3:] - w * np.arcsin(s) / s).max() < 2e-15


def test_tasks_split_poses_and_a_broadcast_array():
    """One pose with 1 100 samples (three tasks of 512) and a zero-stride (broadcast) error array
    give the general path's errors."""
    fast, slow = models("ur5")
    q, _ = joints(fast, 4, 9)
    E = np.random.default_rng(5).uniform(-1e-3, 1e-3, (1, 1100, fast.n_columns))
    q1 = {v: x[:1] for v, x in q.items()}
    assert np.abs(fast.pose_error_at_joints(q1, E) - slow.pose_error_at_joints(q1, E)).max() < 1e-12
    Eb = np.broadcast_to(E[:, :40], (4, 40, fast.n_columns))
    assert np.abs(fast.pose_error_at_joints(q, Eb) - slow.pose_error_at_joints(q, np.ascontiguousarray(Eb))).max() < 1e-12


def test_the_result_does_not_depend_on_the_threads_or_the_calling_thread(monkeypatch):
    """The kernels' tasks run on Python threads (task_threads.run_tasks): one thread, three, and two calls at once
    from two other threads (each then runs in its caller's thread) give the same array, for independent samples
    at each pose and for samples shared by every pose; a range of tasks per call covers every task once."""
    import threading
    from evotol.robots.mechanism.kinematics import task_threads
    fast, _ = models("ur5")
    q, Q = joints(fast, 7, 4)
    E = np.random.default_rng(3).normal(scale=1e-4, size=(7, 1100, fast.n_columns))
    shared = np.broadcast_to(E[0], E.shape)
    ref = {k: fast._serial.pose_error(Q, e) for k, e in (("each", E), ("shared", shared))}
    for threads in (1, 3):
        monkeypatch.setattr(task_threads, "threads_available", lambda t=threads: t)
        for k, e in (("each", E), ("shared", shared)):
            assert np.array_equal(fast._serial.pose_error(Q, e), ref[k]), (threads, k)
    monkeypatch.undo()
    got = {}
    calls = [threading.Thread(target=lambda k=k, e=e: got.setdefault(k, fast._serial.pose_error(Q, e)))
             for k, e in (("each", E), ("shared", shared))]
    for t in calls:
        t.start()
    for t in calls:
        t.join()
    assert all(np.array_equal(got[k], ref[k]) for k in ref)
    seen = []
    task_threads.run_tasks(lambda a, b: seen.extend(range(a, b)), 37, threads=2)
    assert sorted(seen) == list(range(37))
