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
