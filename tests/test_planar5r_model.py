"""Planar 5R as an evotol robot error model (evotol.robots.base protocol)."""
import numpy as np
import pytest

from evotol.errors import KinematicsError, ValidationError
from evotol.robots.checks import check_robot
from evotol.robots.planar5r import Planar5R
from evotol.robots.planar5r import kinematics as K


@pytest.mark.parametrize("case", "abcd")
def test_check_robot_passes(case):
    robot = Planar5R(case, D=0.25)
    rep = check_robot(robot, step=1e-7 * robot.D)                 # Latin hypercube over the workspace
    assert rep["fd_relative_mismatch"] < 1e-6
    rep = check_robot(robot, poses=robot.miw_poses(), step=1e-7 * robot.D)
    assert rep["n_poses"] == 17 and rep["fd_relative_mismatch"] < 1e-6


def test_sources_and_sensitivity_structure():
    robot = Planar5R("b", D=0.2)
    assert robot.n_columns == 16
    assert [s.dim for s in robot.sources if s.name.startswith("clearance")] == [2, 2, 2, 2]
    S = robot.sensitivity(robot.evaluation_poses())
    assert S.shape == (9, 6, 16)
    assert np.all(S[:, 2:, :] == 0)                              # planar point: rows 2-5 unused
    sl = dict(zip(robot.source_names, robot.column_slices))
    # a clearance at A_i and at B_i both move the elbow B_i: identical columns
    np.testing.assert_array_equal(S[:, :, sl["clearance_A1"]], S[:, :, sl["clearance_B1"]])


def test_actuator_columns_equal_kinematic_jacobian():
    robot = Planar5R("d", D=0.3)
    P = robot.evaluation_poses()
    S = robot.sensitivity(P)
    th = robot.nominal_angles(P)
    J = K.jacobian(P, th, robot.r1, robot.r3)
    np.testing.assert_allclose(S[:, :2, 6:8], J, rtol=1e-10, atol=1e-14)


def test_scaling_with_D():
    """Non-dimensional model (eq. 1, 3): length columns are scale-free, angle columns scale with D."""
    a, b = Planar5R("c", D=1.0), Planar5R("c", D=0.1)
    Sa, Sb = a.sensitivity(a.evaluation_poses()), b.sensitivity(b.evaluation_poses())
    np.testing.assert_allclose(Sb[:, :, :6], Sa[:, :, :6], atol=1e-12)
    np.testing.assert_allclose(Sb[:, :, 6:8], 0.1 * Sa[:, :, 6:8], atol=1e-12)


def test_bad_input_is_named():
    with pytest.raises(ValidationError):
        Planar5R("b", D=-1)
    with pytest.raises(ValidationError):
        Planar5R("q")
    robot = Planar5R("b", D=0.2)
    with pytest.raises(KinematicsError):
        robot.sensitivity([[0.0, 0.0]])                       # outside the declared workspace
    with pytest.raises(ValidationError):
        robot.pose_error(robot.evaluation_poses(), np.zeros((9, 3, 5)))


# --- issue 43: pose_error's one compiled pass is the NumPy code, number for number ----------------
def _reference_pose_error(robot, poses, E):
    """Planar5R.pose_error as it was: K.perturbed_position on the errors' dict, then the same masking."""
    theta = robot.nominal_angles(poses)
    px, py, h2 = K.perturbed_position(theta[:, None, :], robot.r1, robot.r2, robot.r3, robot.errors_dict(E),
                                      robot.assembly)
    out = np.zeros(E.shape[:2] + (6,))
    out[..., 0], out[..., 1] = px - poses[:, 0:1], py - poses[:, 1:2]
    out[~(h2 >= 0)] = np.nan
    return out


@pytest.mark.parametrize("layout", ["contiguous", "shared samples", "large errors"])
def test_compiled_pose_error_equals_the_numpy_chain_bit_for_bit(layout):
    robot = Planar5R("b", D=0.2)
    poses = robot.evaluation_poses()
    rng = np.random.default_rng(5)
    t = 1e-4                                             # 0.1 mm and 0.1 mrad: the scale of the study's tolerances
    if layout == "contiguous":
        E = rng.uniform(-1, 1, (len(poses), 3000, 16)) * t
    elif layout == "shared samples":                     # the nonlinear check's layout: a broadcast view, not copied
        E = np.broadcast_to(rng.uniform(-1, 1, (3000, 16)) * t, (len(poses), 3000, 16))
    else:                                                # errors so large that many samples cannot be assembled
        E = rng.normal(0, 0.05, (len(poses), 3000, 16))
    ours = robot.pose_error(poses, E, failures="nan")
    ref = _reference_pose_error(robot, poses, E)
    assert np.array_equal(ours, ref, equal_nan=True)
    if layout == "large errors":
        assert 0 < np.isnan(ours[..., 0]).mean() < 1        # both outcomes occur, and agree


def test_compiled_pose_error_without_numba_is_the_numpy_chain(hide_numba):
    from evotol.robots.planar5r.kinematics import perturbed_compiled

    robot = Planar5R("b", D=0.2)
    poses = robot.evaluation_poses()
    E = np.random.default_rng(6).uniform(-1e-4, 1e-4, (len(poses), 200, 16))
    hide_numba(perturbed_compiled._compiled)
    assert perturbed_compiled._compiled() is None
    assert np.array_equal(robot.pose_error(poses, E), _reference_pose_error(robot, poses, E))


def test_pose_error_names_errors_with_the_wrong_number_of_columns():
    robot = Planar5R("b", D=0.2)
    poses = robot.evaluation_poses()
    with pytest.raises(ValidationError, match=r"errors shape.*n_samples, 16"):
        robot.pose_error(poses, np.zeros((len(poses), 4, 15)))
