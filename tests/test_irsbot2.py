"""IRSBot-2 of Deng 2012 Ch. II, V-VI: inverse geometry, DH tables II.1-II.2, error mapping of the
hybrid legs, certified maximum pose errors (distal module; distal module + parallelograms)."""
import numpy as np
import pytest

from evotol.errors import KinematicsError
from evotol.robots.clearance import max_pose_error, multistart_max_pose_error, twist_between
from evotol.robots.irsbot2 import MAP_WORKSPACE, IRSBot2

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
    # the number: where sin(psi1 - psi2) crosses zero along a grid column, the input-output map is
    # singular -- the determinant of d(q1, q2)/d(x, z) (central differences of the inverse
    # geometry, an independent reading of the same robot) vanishes there (eq. II.38: det A = 0
    # makes det(B^-1 A) = 0), while it is of order 300 at the centre of the map
    from scipy.optimize import brentq

    x = -0.021
    z = np.linspace(-0.07, -0.01, 21)
    v = robot.parallel_singularity(np.c_[np.full(z.size, x), z])
    k = int(np.flatnonzero(np.diff(np.sign(v)))[0])
    z0 = brentq(lambda zz: robot.parallel_singularity([[x, zz]])[0], z[k], z[k + 1], xtol=1e-15)

    def det_dq_dx(p, h=1e-7):
        cols = []
        for e in np.eye(2) * h:
            gp, gm = robot.inverse_geometry([p + e]), robot.inverse_geometry([p - e])
            cols.append([(gp[f"q{i}"][0] - gm[f"q{i}"][0]) / (2 * h) for i in (1, 2)])
        return np.linalg.det(np.array(cols).T)

    regular = abs(det_dq_dx(np.array([0.0, -0.05])))
    assert regular > 100
    assert abs(det_dq_dx(np.array([x, z0]))) < 1e-6 * regular


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


def test_zero_parallelogram_clearances_give_the_distal_model(robot, maps):
    """The 114-variable model (eq. VI.38) with the parallelogram joints' clearances set to zero is
    the 78-variable one (eq. VI.37): the two error models, built from different chains, give the
    same certified maxima at every pose (to the 0.1 % gap; measured: 3e-7)."""
    distal, _ = maps
    mech = robot.clearance_mechanism(parallelograms=True)
    bounds = mech.default_bounds().copy()
    parallelogram = [i for i, j in enumerate(mech.joints) if j.name[0] in "ABCD"]
    assert len(parallelogram) == 8 and mech.n_joints - len(parallelogram) == robot.clearance_mechanism().n_joints
    bounds[parallelogram] = 0.0
    zero = max_pose_error(mech, POSES, bounds)
    np.testing.assert_allclose(zero.p_max, distal.p_max, rtol=1e-3)
    np.testing.assert_allclose(zero.r_max, distal.r_max, rtol=1e-3)


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


@pytest.mark.parametrize("variant", ["printed", "thesys", "Corrected"])
def test_dh_values_refuses_an_unknown_variant(robot, variant):
    """dh_values accepts only "corrected" and "thesis": any other value (a typo, or "printed",
    which only dh_tree knows) is a ValidationError naming the field, the value and the accepted
    ones, not a silent fall-back to the corrected solve."""
    from evotol.errors import ValidationError

    with pytest.raises(ValidationError) as ei:
        robot.dh_values(POSES, variant)
    assert str(ei.value) == f"dh_values variant = {variant!r}: expected 'corrected' or 'thesis'"
    # the accepted values still give the same numbers as before
    a, b = robot.dh_values(POSES, "corrected"), robot.dh_values(POSES)
    assert all(np.array_equal(a[k], b[k]) for k in b)
