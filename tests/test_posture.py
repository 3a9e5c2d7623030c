"""One posture, stated and held (issue 33 item 2): robots/mechanism/posture/held.py.

The PUMA 560's inverse-geometry branches are told apart by three independent factors of its
Jacobian determinant (derived here from the textbook product and checked numerically below):
``det J = a2 · s5 · (d4 c3 + a3 s3) · (a2 c2 + a3 c23 - d4 s23)`` -- wrist, elbow and shoulder.
A pose whose solution has every factor's sign of the assembly is kept; one that changes any is
refused, naming the pose.
"""
from __future__ import annotations

import warnings
from pathlib import Path

import numpy as np
import pytest

from evotol.errors import KinematicsError
from evotol.robots.mechanism.model.error_model import MechanismModel
from evotol.robots.mechanism.posture.held import PostureWarning, wrapped
from tests.test_standard_dh import textbook_fk

FIXTURE = Path(__file__).resolve().parent / "data" / "puma560_rpy.toml"
A2, A3, D4 = 0.4318, 0.0203, 0.4318
ASSEMBLY = np.radians([10, 10, -100, -20, 30, -60])


def factors(q):
    q = np.atleast_2d(q)
    c2, c3, s3 = np.cos(q[:, 1]), np.cos(q[:, 2]), np.sin(q[:, 2])
    c23, s23 = np.cos(q[:, 1] + q[:, 2]), np.sin(q[:, 1] + q[:, 2])
    return np.stack([np.sin(q[:, 4]), D4 * c3 + A3 * s3, A2 * c2 + A3 * c23 - D4 * s23], axis=1)


def pose_of(q):
    T = textbook_fk(q)
    R = T[:3, :3]
    return np.r_[T[:3, 3], np.arctan2(R[1, 0], R[0, 0]), np.arcsin(-R[2, 0]), np.arctan2(R[2, 1], R[2, 2])]


def geometric_jacobian_det(q, h=1e-6):
    """det of the geometric Jacobian by central differences of the textbook forward kinematics."""
    T0 = textbook_fk(q)
    J = np.zeros((6, 6))
    for i in range(6):
        up, dn = np.array(q, float), np.array(q, float)
        up[i] += h
        dn[i] -= h
        Tu, Td = textbook_fk(up), textbook_fk(dn)
        J[:3, i] = (Tu[:3, 3] - Td[:3, 3]) / (2 * h)
        W = (Tu[:3, :3] - Td[:3, :3]) / (2 * h) @ T0[:3, :3].T
        J[3:, i] = [W[2, 1], W[0, 2], W[1, 0]]
    return np.linalg.det(J)


def test_the_three_factors_are_the_determinant():
    Q = np.random.default_rng(0).uniform(-np.pi, np.pi, (30, 6))
    det = np.array([geometric_jacobian_det(q) for q in Q])
    assert np.allclose(det, A2 * np.prod(factors(Q), axis=1), rtol=1e-6, atol=1e-12)


def test_branch_changes_are_refused_and_kept_branches_are_kept():
    model = MechanismModel(FIXTURE)
    sign0 = np.sign(factors(ASSEMBLY)[0])
    rng = np.random.default_rng(3)
    kept = refused = 0
    for _ in range(60):
        q = ASSEMBLY + rng.normal(0, 0.5, 6)
        P = pose_of(q)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", PostureWarning)
            try:
                sol = model.joint_values(P[None])
            except KinematicsError as e:
                assert "another branch" in str(e) and "pose 0" in str(e) and "\n" not in str(e)
                refused += 1
                continue
        qs = np.array([sol[f"q{i}"][0] for i in range(1, 7)])
        assert np.allclose(textbook_fk(qs), textbook_fk(q), atol=1e-9)          # it is that pose
        assert np.array_equal(np.sign(factors(qs)[0]), sign0)                    # on the assembly's branch
        kept += 1
    assert kept >= 30 and refused >= 3


def test_refused_poses_are_on_another_branch():
    model = MechanismModel(FIXTURE)
    sign0 = np.sign(factors(ASSEMBLY)[0])
    rng = np.random.default_rng(3)
    refused = 0
    for _ in range(60):
        q = ASSEMBLY + rng.normal(0, 0.5, 6)
        try:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore", PostureWarning)
                model.joint_values(pose_of(q)[None])
        except KinematicsError as e:
            refused += 1
            # the solution named in the message differs from the assembly in one factor's sign
            text = str(e).split("to the solution there (")[1].split(")")[0]
            qs = np.radians([float(part.split("=")[1].split()[0]) for part in text.split(",")])
            assert not np.array_equal(np.sign(factors(qs)[0]), sign0)
            # ... and is a solution of that pose: the textbook product at the printed angles (0.1 deg,
            # so at most 0.05 deg = 8.7e-4 rad per joint off) reaches the pose's frame within
            # 6 joints x 8.7e-4 rad x about 1 m of reach = 5e-3 (m, and unitless for the rotation)
            assert np.abs(textbook_fk(qs) - textbook_fk(q)).max() < 5e-3
    # the same 60 draws as the test above: at least 3 refused (10 are), so the loop's asserts ran
    assert refused >= 3


def test_a_wrist_singularity_is_a_warning_naming_the_pose():
    model = MechanismModel(FIXTURE)
    P = pose_of(np.radians([0, -90, 90, 0, 0, 0]))
    with pytest.warns(PostureWarning, match="near a singularity"):
        model.joint_values(P[None])
    assert any("near a singularity" in n for n in model.notes())


def test_wrapped_angles():
    model = MechanismModel(FIXTURE)
    w = wrapped(model.kin, {"q1": np.radians([180, -180, 507.5, -226.4, 0])})
    assert np.allclose(np.degrees(w["q1"]), [180, 180, 147.5, 133.6, 0])


def test_typed_assembly_pose_and_joints_of_a_serial_arm_must_agree(tmp_path):
    # issue 33: the typed joints were moved by 12.6 deg in silence; now an error naming both
    text = FIXTURE.read_text().replace('q4 = "-20*deg"', 'q4 = "-7.4*deg"')
    f = tmp_path / "puma_disagree.toml"
    f.write_text(text)
    model = MechanismModel(f)
    with pytest.raises(KinematicsError) as e:
        model.kin.assembly()
    msg = str(e.value)
    assert "[assembly] pose" in msg and "q4 from -7.4 deg" in msg and "disagree" in msg
    # the same joints, exactly those of the pose: accepted, unchanged
    x0, q = MechanismModel(FIXTURE).kin.assembly()
    assert np.allclose([q[f"q{i}"] for i in range(1, 7)], ASSEMBLY, atol=1e-9)


def test_unreachable_poses_are_reported_together_or_dropped(tmp_path):
    from evotol.studyfile import load_problem
    from tests.test_standard_dh import PUMA
    text = PUMA.read_text().replace('high = "700*mm"', 'high = "1100*mm"')       # beyond the arm's reach in x
    f = tmp_path / "puma_far.toml"
    f.write_text(text)
    spec = {"robot": {"mechanism": str(f), "sources": ["a2", "d4"]}, "poses": {"grid": [5, 2, 2]},
            "requirement": {"position": 5e-4}, "cost": {"default": {"model": "exponential", "a0": 1.9, "a1": 0.5, "scale": 1e-5}}}
    with pytest.raises(KinematicsError) as e:
        load_problem(spec)
    msg = str(e.value)
    n_bad = len(e.value.poses)
    assert f"{n_bad} of 20 poses" in msg and "loops" not in msg and "drop_unreachable" in msg and n_bad >= 4
    # every pose named is beyond the reach of the wrist centre (frame 6's origin): farther from the shoulder
    # than sqrt((a2 + sqrt(a3^2 + d4^2))^2 + d3^2)
    reach = np.hypot(A2 + np.hypot(A3, D4), 0.15005)
    assert np.all(np.linalg.norm(np.asarray(e.value.poses), axis=1) > reach)
    spec["poses"]["drop_unreachable"] = True
    problem = load_problem(spec)
    assert problem.n_poses == 20 - n_bad
    assert any(f"{n_bad} of 20 poses dropped" in line for line in problem.model.notes())
    # what is kept is reached: the model's joints reproduce those poses (textbook forward kinematics)
    q = problem.model.joint_values(problem.poses)
    for i, p in enumerate(problem.poses):
        T = textbook_fk([q[f"q{k}"][i] for k in range(1, 7)])
        assert np.allclose(T[:3, 3], p, atol=1e-9)


def test_compiled_task_jacobian_equals_the_general_one():
    from evotol.robots.mechanism.posture.held import _task_jacobian
    from evotol.robots.mechanism.kinematics.serial import SERIAL_COMPILED, SerialChain
    if not SERIAL_COMPILED:
        pytest.skip("numba not available: the general path is the only one")
    for f in (FIXTURE, Path(__file__).resolve().parents[1] / "robots" / "mechanisms" / "ur5.toml"):
        m = MechanismModel(f)
        kin = m.kin
        chain = SerialChain.build(kin, list(kin.variables))
        Q = np.random.default_rng(0).uniform(-3, 3, (20, len(kin.variables)))
        q = {v: Q[:, i] for i, v in enumerate(kin.variables)}
        P = m.workspace.latin_hypercube(20)
        assert np.abs(_task_jacobian(kin, q, P, chain) - _task_jacobian(kin, q, P)).max() < 1e-12


def test_dropped_poses_are_stated_with_callouts_too(tmp_path):
    """``[poses] drop_unreachable`` on an arm with drawing callouts: the report's notes still say how many
    poses were dropped (the count was set on the callout part and read from the arm: lost, before)."""
    from evotol.studyfile import load_problem
    from tests.test_standard_dh import PUMA
    f = tmp_path / "puma_far.toml"
    f.write_text(PUMA.read_text().replace('high = "700*mm"', 'high = "1100*mm"'))
    spec = {"robot": {"mechanism": str(f)}, "poses": {"grid": [5, 2, 2]}, "requirement": {"position": 5e-4},
            "cost": {"default": {"model": "exponential", "a0": 1.9, "a1": 0.5, "scale": 1e-5}}}
    with pytest.raises(KinematicsError) as e:
        load_problem(spec)
    n_bad = len(e.value.poses)
    spec["poses"]["drop_unreachable"] = True
    spec["robot"]["callouts"] = [{"joint": "J3", "kind": "position", "length": "50 mm"}]
    problem = load_problem(spec)
    assert problem.model.part_of("callouts") is not None and problem.n_poses == 20 - n_bad
    assert [line for line in problem.model.notes() if f"{n_bad} of 20 poses dropped" in line]


def test_the_branch_check_in_blocks_of_poses_is_the_check_of_all_at_once(monkeypatch):
    """Poses checked a few at a time (PATH_BLOCK, memory) give the same near-singular poses and refuse the
    same first pose (its index in the whole set) as one batch; the refusal by the textbook's factors."""
    import evotol.robots.mechanism.posture.held as held

    model = MechanismModel(FIXTURE)
    rng = np.random.default_rng(3)
    Q = ASSEMBLY + rng.normal(0, 0.5, (60, 6))
    Q[7] = np.radians([0, -90, 90, 0, 0, 0])                  # a wrist singularity among them
    sol = {f"q{i + 1}": Q[:, i] for i in range(6)}             # the joints themselves: no inverse geometry
    P = np.array([pose_of(q) for q in Q])
    sign0 = np.sign(factors(ASSEMBLY)[0])
    other = [i for i in range(len(Q)) if not np.array_equal(np.sign(factors(Q[i])[0]), sign0)
             and abs(factors(Q[i])[0]).min() > 1e-3]

    def run():
        try:
            return held.check_branch(model.kin, P, sol, model.workspace.names), None
        except KinematicsError as e:
            return None, str(e)

    whole = run()
    monkeypatch.setattr(held, "PATH_BLOCK", 5 * held.PATH_SAMPLES)   # five poses a block: 12 blocks
    blocked = run()
    assert whole[1] is not None and whole[1] == blocked[1]
    assert f"pose {other[0]} " in whole[1] or any(f"pose {i} " in whole[1] for i in range(other[0]))
    ok = [i for i in range(len(Q)) if i not in other]            # without the refused poses: the near ones
    sol_ok = {k: v[ok] for k, v in sol.items()}
    monkeypatch.setattr(held, "PATH_BLOCK", 1 << 15)
    near_whole = held.check_branch(model.kin, P[ok], sol_ok, model.workspace.names)
    monkeypatch.setattr(held, "PATH_BLOCK", 5 * held.PATH_SAMPLES)
    near_blocked = held.check_branch(model.kin, P[ok], sol_ok, model.workspace.names)
    assert np.array_equal(near_whole, near_blocked) and ok.index(7) in near_whole.tolist()


def test_compiled_path_determinants_equal_numpy_det_of_the_general_jacobian():
    """The posture check's compiled kernel (serial_newton.path_determinants, issue 43 item 1): det J
    at every sample of the joint-space paths and J at their ends equal LAPACK's determinant of the
    general path's task Jacobian (tree.py) at the same configurations, on the PUMA (RPY) and the UR5."""
    from evotol.robots.mechanism.posture.held import _path_determinants, _task_jacobian
    from evotol.robots.mechanism.kinematics.serial import SERIAL_COMPILED, SerialChain
    if not SERIAL_COMPILED:
        pytest.skip("numba not available: the general path is the only one")
    for f in (FIXTURE, Path(__file__).resolve().parents[1] / "robots" / "mechanisms" / "ur5.toml"):
        kin = MechanismModel(f).kin
        chain = SerialChain.build(kin, list(kin.variables))
        rng = np.random.default_rng(1)
        q0 = {v: float(x) for v, x in zip(kin.variables, rng.uniform(-2, 2, len(kin.variables)))}
        diff = {v: rng.uniform(-3, 3, 15) for v in kin.variables}
        S = np.linspace(0.0, 1.0, 5)[1:]
        det, J_end = _path_determinants(kin, chain, q0, diff, S)
        q = {v: (q0[v] + S[:, None] * diff[v][None, :]).ravel() for v in kin.variables}
        J = _task_jacobian(kin, q, np.zeros((60, len(kin.mech.coordinates)))).reshape(4, 15, *J_end.shape[1:])
        ref = np.linalg.det(J)
        assert np.abs(det - ref).max() < 1e-12 * np.abs(ref).max() and (np.sign(det) == np.sign(ref)).all()
        assert np.abs(J_end - J[-1]).max() < 1e-12


def test_smallest_singular_value_bound_decides_as_the_svd():
    """The posture check's near-singular test (issue 43 item 1): the SVD runs only where the bound
    ``|det J| / U^m`` (U from Gershgorin's circles of J^T J) is below NEAR_SINGULAR. On matrices of
    every conditioning, near-singular ones included, the decision equals the SVD's, the value is the
    SVD's where it is below the threshold, and a lower bound of it elsewhere."""
    from evotol.robots.mechanism.posture.held import NEAR_SINGULAR, _relative_smallest_singular_value
    rng = np.random.default_rng(4)
    U, V = np.linalg.qr(rng.normal(size=(400, 6, 6)))[0], np.linalg.qr(rng.normal(size=(400, 6, 6)))[0]
    sv = np.concatenate([rng.uniform(0.3, 3.0, (400, 5)), 10.0 ** rng.uniform(-5, 0, (400, 1))], axis=1)
    J = np.einsum("nij,nj,nkj->nik", U, sv, V)
    ref = np.linalg.svd(J, compute_uv=False)
    ref = ref[:, -1] / ref[:, 0]
    got = _relative_smallest_singular_value(J, np.linalg.det(J))
    near = ref < NEAR_SINGULAR
    assert 50 < near.sum() < 350 and ((got < NEAR_SINGULAR) == near).all()
    assert np.allclose(got[near], ref[near], rtol=1e-12, atol=0) and (got[~near] <= ref[~near] * (1 + 1e-12)).all()
