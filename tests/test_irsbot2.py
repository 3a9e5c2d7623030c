"""IRSBot-2 of Deng 2012 Ch. II, V-VI: inverse geometry, DH tables II.1-II.2, error mapping of the
hybrid legs, certified maximum pose errors (distal module; distal module + parallelograms)."""
import numpy as np
import pytest

from evotol.errors import KinematicsError
from robots.clearance import max_pose_error, multistart_max_pose_error, twist_between
from robots.irsbot2 import MAP_WORKSPACE, IRSBot2

POSES = np.array([[0.0, -0.05], [0.012, -0.031], [-0.025, -0.065]])


@pytest.fixture(scope="module")
def robot():
    return IRSBot2()


def test_loops_close_on_the_corrected_tables(robot):
    """Eqs. II.2-II.35 with Tabs. II.1-II.2: parallelograms and the four distal chains reach one
    platform frame at P, parallel to the base; the printed row 28 misses it (alpha sign)."""
    res = robot.loop_residual(POSES)
    assert max(res.values()) < 1e-12
    printed = robot.loop_residual(POSES, variant="printed")
    assert printed["platform_32_position"] > 0.01 and printed["platform_11_position"] < 1e-12


def test_l2eq_is_the_corrected_II1(robot):
    """|E_11 F_11| = l2 needs l2eq^2 = l2^2 - (a1 - a2)^2 cos^2(beta) (eq. II.1 prints cos)."""
    W = robot.dh_tree().world_transforms(robot.dh_values(POSES), len(POSES))
    assert np.allclose(np.linalg.norm(W["9"][:, :3, 3] - W["7"][:, :3, 3], axis=1), robot.l2, atol=1e-14)
    bad = IRSBot2(l2eq_variant="printed")
    with pytest.raises(KinematicsError, match=r"\|E F\| != l2"):
        bad.dh_values(POSES)


def test_universal_joint_angles_match_thesis_formulas_II18_II35(robot):
    """In the elbows-out mode the geometric solve equals eqs. II.18-II.35."""
    a, b = robot.dh_values(POSES), robot.dh_values(POSES, "thesis")
    for k in ("t7", "t8", "t12", "t13", "t23", "t24", "t28", "t29"):
        assert np.allclose(a[k], b[k], atol=1e-12), k


def test_parallel_singularity_crosses_the_map(robot):
    """Fig. VI.2: the map's square contains parallel singularities (psi1 = psi2)."""
    s = robot.parallel_singularity(MAP_WORKSPACE.grid(21))
    assert s.min() < 0 < s.max()


@pytest.mark.parametrize("parallelograms,v", [(False, 78), (True, 114)])
def test_error_mapping_matches_finite_differences_V1(robot, parallelograms, v):
    """Eqs. V.1, V.4, VI.4-VI.7, VI.17-VI.30: every chain's M (joints) and M^e (start body)
    equal finite differences of the chain's nonlinear pose; variable count = eq. VI.37/VI.38."""
    mech = robot.clearance_mechanism(parallelograms=parallelograms)
    pm = mech.pose_maps(POSES[:1])[0]
    assert pm.n_rows - pm.n_loops == v
    h = 1e-6
    for c in mech.chains:
        M, Me = mech.error_mapping(POSES[:2], c)
        T0 = mech.chain_end_pose(POSES[:2], c)
        for k, jn in enumerate(c.joints):
            for comp in (0, 2, 3, 5):
                s = np.zeros(6); s[comp] = h
                fd = (twist_between(T0, mech.chain_end_pose(POSES[:2], c, {jn: s}))
                      - twist_between(T0, mech.chain_end_pose(POSES[:2], c, {jn: -s}))) / (2 * h)
                assert np.allclose(fd, M[:, :, 6 * k + comp], atol=1e-8)
        if c.start != "base":
            for comp in range(6):
                s = np.zeros(6); s[comp] = h
                fd = (twist_between(T0, mech.chain_end_pose(POSES[:2], c, start_twist=s))
                      - twist_between(T0, mech.chain_end_pose(POSES[:2], c, start_twist=-s))) / (2 * h)
                assert np.allclose(fd, Me[:, :, comp], atol=1e-8)


@pytest.fixture(scope="module")
def maps(robot):
    distal = max_pose_error(robot.clearance_mechanism(), POSES)
    full = max_pose_error(robot.clearance_mechanism(parallelograms=True), POSES)
    return distal, full


def test_certified_gap_and_hybrid_legs_add_error(maps):
    """Gap <= 0.1 %; Sec. VI.3: clearances in the parallelograms add to the distal ones, so the
    maximum with them is larger (the distal set is a subset of the full one)."""
    distal, full = maps
    assert distal.gap.max() <= 1e-3 and full.gap.max() <= 1e-3
    assert np.all(full.p_upper >= distal.p_max) and np.all(full.r_upper >= distal.r_max)
    assert np.all(full.p_max > distal.p_max)


def test_never_below_multistart_78_variables(robot, maps):
    """The thesis's method (78 variables, eq. VI.37) never exceeds the certified bound."""
    distal, _ = maps
    ms = multistart_max_pose_error(robot.clearance_mechanism(), POSES[:1], n_starts=3, seed=0)
    assert ms.n_variables == 78
    assert ms.p_max[0] <= distal.p_upper[0] * (1 + 1e-9) and ms.r_max[0] <= distal.r_upper[0] * (1 + 1e-9)


def test_maps_are_symmetric_about_the_z_axis(robot):
    """Sec. VI.1: the robot and the square are symmetric, so are the maxima (x -> -x)."""
    P = np.array([[0.015, -0.04], [-0.015, -0.04]])
    r = max_pose_error(robot.clearance_mechanism(parallelograms=True), P)
    assert abs(r.p_max[0] - r.p_max[1]) <= 1e-3 * r.p_max[0]
    assert abs(r.r_max[0] - r.r_max[1]) <= 1e-3 * r.r_max[0]
