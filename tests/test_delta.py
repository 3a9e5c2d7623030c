"""Delta robot model of Brahmia et al. 2023 (robots/delta/): kinematics, closure, Jacobians."""
import numpy as np
import pytest

from evotol.errors import KinematicsError, ValidationError
from evotol.robots.checks import check_robot
from evotol.robots.delta import (ANGULAR, LINEAR, PARAMETER_NAMES, POSTURES_MM, DeltaRobot,
                          cylinder_poses)

ROBOT = DeltaRobot()
P15 = np.array(list(POSTURES_MM.values())) / 1e3
DENSE = cylinder_poses(1000, seed=3)
BOUND = np.where(np.isin(PARAMETER_NAMES, LINEAR), 0.015e-3, np.radians(0.015))  # eq. (13) bounds


def col(name):
    return PARAMETER_NAMES.index(name)


def test_parameter_set_is_the_47_of_eq12():
    # eq. (12): i = 1..11 linear, j = 12..47 angular
    assert len(PARAMETER_NAMES) == 47 and len(LINEAR) == 11 and len(ANGULAR) == 36
    assert [s.unit for s in ROBOT.sources].count("m") == 11
    assert {s.group for s in ROBOT.sources} == {"linear", "angular"}


def test_postures_given_in_the_paper():
    # Tables A1-A2: P1, P3, P6, P9
    assert POSTURES_MM["P1"] == (0, 0, 250) and POSTURES_MM["P3"] == (0, 0, 500)
    assert POSTURES_MM["P6"] == (100, 0, 500) and POSTURES_MM["P9"] == (0, 100, 500)
    assert len(POSTURES_MM) == 15 and np.all(ROBOT.workspace.contains(P15))


def test_inverse_kinematics_closes_every_branch_to_1e9_mm():
    # eq. (3) solved in closed form; eq. (1) and eq. (2) (both rods) must end at P
    poses = np.vstack([P15, DENSE, ROBOT.workspace.grid(4)])
    Q = ROBOT.inverse_kinematics(poses)
    assert Q.shape == (len(poses), 3, 7)
    # relations of Sec. 2.1.2: q3 = q6, q4 = q7 = -q3
    assert np.allclose(Q[..., 2], Q[..., 5]) and np.allclose(Q[..., 3], -Q[..., 2]) and np.allclose(Q[..., 6], -Q[..., 2])
    b1, b2 = ROBOT.branch_points(Q[..., 0], Q[..., 1], Q[..., 2], np.zeros((len(poses), 47)))
    for b in (b1, b2):
        gap_mm = np.max(np.abs(np.stack(b, -1) - poses[:, None, :])) * 1e3
        assert gap_mm < 1e-9


def test_closed_form_forward_kinematics_inverts_ik():
    # independent method: three-sphere intersection
    q1 = ROBOT.inverse_kinematics(DENSE)[..., 0]
    assert np.max(np.abs(ROBOT.forward_kinematics_nominal(q1) - DENSE)) * 1e3 < 1e-9


def test_forward_kinematics_with_errors_closes_to_1e9_mm():
    rng = np.random.default_rng(0)
    poses = np.vstack([P15, DENSE[:85]])
    e = rng.uniform(-1, 1, (len(poses), 50, 47)) * BOUND * 3
    res = ROBOT.closure_residual(poses, e)
    assert res.shape == (100, 50) and res.max() * 1e3 < 1e-9
    # zero errors -> the nominal pose
    assert np.max(np.abs(ROBOT.pose_error(poses, np.zeros((1, 1, 47))))) < 1e-15


def test_check_robot_jacobian_matches_finite_differences_to_1e6():
    rep = check_robot(ROBOT, np.vstack([P15, DENSE[:20]]), rtol=1e-6)
    assert rep["fd_relative_mismatch"] < 1e-6


def test_closure_jacobian_matches_central_differences():
    q1, X0, J = ROBOT._nominal_state(P15)
    h = 1e-7
    zero = np.zeros((15, 47))
    fd = np.stack([(ROBOT._residual(X0 + h * np.eye(9)[k], q1, zero) - ROBOT._residual(X0 - h * np.eye(9)[k], q1, zero)) / (2 * h)
                   for k in range(9)], axis=-1)
    assert np.max(np.abs(fd - J)) < 1e-6 * np.max(np.abs(J))


def _rigid_delta_jacobian(poses):
    """Textbook Delta: rod vector s_i = B_i - C_i, |s_i| = Lb, s_i . dP = s_i . (dC_i - dB_offset_i)."""
    g = ROBOT.geometry
    q1 = ROBOT.inverse_kinematics(poses)[..., 0]
    th = g.theta
    u = np.stack([np.cos(th), np.sin(th), np.zeros(3)], -1)                   # radial unit vectors
    a = np.stack([np.cos(th) * np.cos(q1), np.sin(th) * np.cos(q1), np.sin(q1)], -1)
    da = np.stack([-np.cos(th) * np.sin(q1), -np.sin(th) * np.sin(q1), np.cos(q1)], -1)
    C = g.Ra * u + g.La * a
    s = poses[:, None, :] + g.Rb * u - C
    return q1, u, a, da, C, s


def test_sensitivity_matches_textbook_delta_jacobian():
    # independent derivation (rigid Delta, parallelogram = one rod of length Lb) for the columns
    # Ra, Rb, La_i, Lb_i, q1_i, theta_i; solve s_i . dP = rhs_i for each error
    g = ROBOT.geometry
    poses = np.vstack([P15, DENSE[:50]])
    S = ROBOT.sensitivity(poses)[:, :3, :]
    q1, u, a, da, C, s = _rigid_delta_jacobian(poses)
    ez = np.array([0.0, 0.0, 1.0])
    dot = lambda x, y: np.sum(x * y, -1)
    cases = {"Ra": dot(s, u), "Rb": -dot(s, u)}
    for i in range(3):
        onehot = np.eye(3)[i]
        cases[f"La_{i + 1}"] = dot(s, a) * onehot
        cases[f"Lb_{i + 1}"] = g.Lb * onehot + 0 * dot(s, u)
        cases[f"q1_{i + 1}"] = g.La * dot(s, da) * onehot
        rot = np.cross(ez, C) - g.Rb * np.cross(ez, u)  # d(C_i - Rb u_i)/d theta_i
        cases[f"theta_{i + 1}"] = dot(s, rot) * onehot
    for name, rhs in cases.items():
        expected = np.linalg.solve(s, rhs[..., None])[..., 0]
        assert np.max(np.abs(S[:, :, col(name)] - expected)) < 1e-10, name


def test_bar_width_and_free_joint_offsets_have_no_first_order_effect():
    # Δd enters r2 = d + Δd, r5 = -(d + Δd) (Table 2): cancels on a nominal parallelogram;
    # Δq2 is an offset of a free passive joint in the closed loop
    S = ROBOT.sensitivity(DENSE[:100])
    for name in ("d_1", "d_2", "d_3", "q2_1", "q2_2", "q2_3"):
        assert np.max(np.abs(S[:, :, col(name)])) < 1e-12
    # Δθ_i at a pose on the axis: the leg turns about z through P
    S_axis = ROBOT.sensitivity(P15[:3])
    for i in (1, 2, 3):
        assert np.max(np.abs(S_axis[:, :, col(f"theta_{i}")])) < 1e-12


def test_nonlinear_error_is_first_order_plus_quadratic_remainder():
    rng = np.random.default_rng(1)
    e = rng.uniform(-1, 1, (15, 20, 47)) * BOUND
    S = ROBOT.sensitivity(P15)
    rem = []
    for k in (1.0, 2.0):
        lin = np.einsum("nij,nsj->nsi", S, k * e)
        rem.append(np.max(np.abs(ROBOT.pose_error(P15, k * e) - lin)))
    assert 3.5 < rem[1] / rem[0] < 4.5  # O(|e|^2)


def test_open_chain_points_are_the_pose_without_errors_and_move_with_them():
    pts = ROBOT.open_chain_points(P15, np.zeros((15, 1, 47)))
    assert pts.shape == (15, 1, 3, 2, 3) and np.max(np.abs(pts - P15[:, None, None, None, :])) < 1e-15
    e = np.zeros(47)
    e[col("alpha6_1")] = 1e-4  # only the rod-2 branch of leg 1 moves
    pts = ROBOT.open_chain_points(P15, np.broadcast_to(e, (15, 1, 47)))
    moved = np.abs(pts - P15[:, None, None, None, :]).max(axis=(0, 1, 4))
    assert moved[0, 1] > 1e-9 and np.all(np.delete(moved.ravel(), 1) < 1e-15)


def test_bad_input_raises_named_errors():
    with pytest.raises(KinematicsError, match="outside the workspace"):
        ROBOT.sensitivity([[0.0, 0.0, 0.9]])
    wide = DeltaRobot(workspace=type(ROBOT.workspace)(("x", "y", "z"), (-2, -2, 0), (2, 2, 2), ("m",) * 3))
    with pytest.raises(KinematicsError, match="out of reach"):
        wide.inverse_kinematics([[1.5, 0.0, 0.3]])
    with pytest.raises(ValidationError, match="errors shape"):
        ROBOT.pose_error(P15, np.zeros((15, 2, 46)))
    with pytest.raises(ValidationError, match="DeltaGeometry.La"):
        from evotol.robots.delta import DeltaGeometry
        DeltaGeometry(La=-1.0)
    with pytest.raises(ValidationError, match="geometry"):
        DeltaRobot(geometry={"Lc": 0.3})
    # a study file passes the geometry as a table of lengths (m)
    assert DeltaRobot(geometry={"La": 0.25}).geometry.La == 0.25


def test_delta_from_a_study_file_spec():
    # evotol run STUDY.toml builds robots by registry name; Δd_i and Δq2_i (no first-order effect)
    # must be locked for the sensitivity rule
    from evotol.studyfile import load_problem

    um, mdeg = 1e-6, float(np.radians(1e-3))
    spec = {"robot": {"model": "delta", "geometry": {"La": 0.26}}, "poses": {"latin_hypercube": 20},
            "bounds": {"lower": 0.5 * um, "upper": 100 * um},
            "cost": {"linear": {"model": "reciprocal", "a0": 1.0, "a1": 10.0, "scale": um},
                     "angular": {"model": "reciprocal", "a0": 1.0, "a1": 10.0, "scale": mdeg}},
            "sources": {f"{p}_{i}": {"locked": 100 * um} for p in ("d", "q2") for i in (1, 2, 3)},
            "requirement": {"position": 2e-4}}
    prob = load_problem(spec)
    assert prob.n_sources == 47 and prob.n_poses == 20 and int((~prob.free).sum()) == 6
