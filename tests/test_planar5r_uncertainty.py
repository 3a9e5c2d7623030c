"""Planar 5R uncertainty and clearance sampling (Lara-Molina et al. 2019, Table 1, eqs. 7-8,
23-24, Sec. 2.5) and its propagation through the exact kinematics."""
import numpy as np
import pytest

from evotol.errors import KinematicsError, ValidationError
from evotol.robots.planar5r import Planar5R
from evotol.robots.planar5r import kinematics as K
from evotol.robots.planar5r import uncertainty as U
from evotol.robots.planar5r.design import CASES
from evotol.robots.planar5r.model import COLUMN_PARAMETERS


def test_table1_constants():
    assert U.DELTA_R == pytest.approx(0.004 / 100)
    assert np.rad2deg(U.DELTA_THETA) == pytest.approx(0.05)
    assert U.PAPER_CIRCLE == 0.005


def test_lhs_is_stratified_and_seeded():
    u = U.unit_samples(64, 9, "lhs", seed=3)
    for j in range(9):
        assert sorted(np.floor(u[:, j] * 64).astype(int)) == list(range(64))
    np.testing.assert_array_equal(u, U.unit_samples(64, 9, "lhs", seed=3))
    assert not np.array_equal(u, U.unit_samples(64, 9, "lhs", seed=4))
    with pytest.raises(ValidationError):
        U.unit_samples(10, 9, "sobolish")


def test_sampled_distributions_eq7_eq8_eq23():
    d = CASES["b"]
    m = U.UncertaintyModel(clearance=3e-4, shared_lengths=False, renormalise=False)
    e = m.errors_from_unit(U.unit_samples(40000, m.n_dims, "mc", seed=1), d.r1, d.r2, d.r3)
    assert np.std(e["dA1B1"]) / d.r1 == pytest.approx(U.DELTA_R, rel=0.03)       # eq. 7
    assert np.std(e["dB2P"]) / d.r2 == pytest.approx(U.DELTA_R, rel=0.03)
    assert np.corrcoef(e["dA1B1"], e["dA2B2"])[0, 1] == pytest.approx(0, abs=0.03)
    assert np.std(e["dth2"]) == pytest.approx(U.DELTA_THETA, rel=0.03)             # eq. 8
    np.testing.assert_allclose(np.hypot(e["cA1x"], e["cA1y"]), 3e-4, rtol=1e-12)   # contact mode, eq. 23
    np.testing.assert_allclose(np.hypot(e["cB2x"], e["cB2y"]), 3e-4, rtol=1e-12)
    assert np.var(e["cB1x"]) == pytest.approx(3e-4 ** 2 / 2, rel=0.03)            # uniform direction


def test_shared_and_renormalised_lengths_follow_the_paper():
    d = CASES["c"]
    m = U.UncertaintyModel()                       # paper: shared lengths, renormalised by D(Omega)
    e = m.errors_from_unit(U.unit_samples(1000, m.n_dims, "lhs", seed=2), d.r1, d.r2, d.r3)
    np.testing.assert_array_equal(e["dA1B1"], e["dA2B2"])
    np.testing.assert_allclose(e["dA1B1"] + e["dB1P"] + e["dOA1"], 0.0, atol=1e-15)   # sum stays 3 (eq. 2)


def test_printed_eq24_variant_respects_assumption3():
    d = CASES["b"]
    m = U.UncertaintyModel(clearance=1e-3, clearance_model="eq24_printed")
    u = U.unit_samples(20000, m.n_dims, "mc", seed=5)
    e = m.errors_from_unit(u, d.r1, d.r2, d.r3)
    rB = np.hypot(e["cB1x"], e["cB1y"])
    assert rB.max() < 1e-3 + 1e-15 and rB.min() >= 0
    # conditioning |c_B| < r_c of the uniform pair (v_A, v_B) leaves v_B - (pi - v_A) uniform on +-60 deg
    vA = 2 * np.pi * u[:, 5 + 0]
    ang = np.angle(np.exp(1j * (np.arctan2(e["cB1y"] + 1e-3 * np.sin(np.pi - vA), e["cB1x"] + 1e-3 * np.cos(np.pi - vA)) - (np.pi - vA))))
    assert np.abs(ang).max() <= np.pi / 3 + 1e-9
    assert np.mean(np.abs(ang) < np.pi / 6) == pytest.approx(0.5, abs=0.02)


@pytest.mark.parametrize("case", ["b", "d"])
def test_sample_covariance_matches_linear_propagation(case):
    """Independent check of sampler + exact kinematics against the robot's first-order map:
    cov(dP) = S Sigma S^T with Sigma the source covariance (lengths, actuators, r_c^2/2 I)."""
    rc = 5e-4
    robot = Planar5R(case, D=1.0)
    poses = robot.evaluation_poses()
    d = robot.design
    m = U.UncertaintyModel(clearance=rc, shared_lengths=False, renormalise=False)
    dp = U.sample_deviations(poses, d.r1, d.r2, d.r3, m, n_samples=30000, method="lhs", seed=7)
    S = robot.sensitivity(poses)[:, :2, :]
    var = np.array([(U.DELTA_R * L) ** 2 for L in (d.r1, d.r1, d.r2, d.r2, d.r3, d.r3)]
                   + [U.DELTA_THETA ** 2] * 2 + [rc ** 2 / 2] * 8)
    cov_lin = np.einsum("pik,k,pjk->pij", S, var, S)
    cov_mc = np.einsum("psi,psj->pij", dp - dp.mean(1, keepdims=True), dp - dp.mean(1, keepdims=True)) / (dp.shape[1] - 1)
    scale = np.trace(cov_lin, axis1=1, axis2=2)[:, None, None]
    assert np.max(np.abs(cov_mc - cov_lin) / scale) < 0.03


def test_vectorised_sampler_equals_robot_pose_error_path():
    robot = Planar5R("c", D=1.0)
    poses = robot.evaluation_poses()
    d = robot.design
    m = U.UncertaintyModel(clearance=2e-4)
    u = U.unit_samples(500, m.n_dims, "mc", seed=11)
    dp = U.position_deviations(poses, d.r1, d.r2, d.r3, m, u)
    err = m.errors_from_unit(u, d.r1, d.r2, d.r3)
    cols = np.stack([np.broadcast_to(err.get(k, 0.0), (500,)) for k in COLUMN_PARAMETERS], -1)
    out = robot.pose_error(poses, np.broadcast_to(cols, (len(poses),) + cols.shape))
    np.testing.assert_allclose(out[..., :2], dp, atol=1e-14)
    # one pose at a time gives the same numbers as all poses in one pass
    np.testing.assert_allclose(U.position_deviations(poses[4:5], d.r1, d.r2, d.r3, m, u)[0], dp[4], atol=1e-15)


def test_unassemblable_samples_raise_or_are_counted():
    d = CASES["a"]
    m = K.mic_closed_form(d.r1, d.r2, d.r3)
    pose = np.array([[0.7 * m["radius"] * np.cos(np.deg2rad(225)), m["center_y"] + 0.7 * m["radius"] * np.sin(np.deg2rad(225))]])
    with pytest.raises(KinematicsError, match="cannot be assembled"):
        U.sample_deviations(pose, d.r1, d.r2, d.r3, n_samples=4000)
    dp, ok = U.sample_deviations(pose, d.r1, d.r2, d.r3, n_samples=4000, failures="mask")
    st = U.pose_statistics(dp, assembled=ok)
    assert 0 < st["p_unassembled"][0] < 0.5
    assert st["p_exceed"][0] >= st["p_unassembled"][0]
    assert np.all(dp[~ok] == 0)


def test_pose_statistics_on_a_known_sample():
    dp = np.zeros((1, 4, 2))
    dp[0, :, 0] = [0.003, -0.003, 0.006, 0.0]
    dp[0, :, 1] = [0.004, 0.004, 0.0, 0.0]
    st = U.pose_statistics(dp, radius=0.005)
    assert st["mean_dx"][0] == pytest.approx(0.0015)
    assert st["max_dev"][0] == pytest.approx(0.006)
    assert st["mean_dev"][0] == pytest.approx((0.005 + 0.005 + 0.006) / 4)
    assert st["p_exceed"][0] == pytest.approx(0.25)          # only |dp| = 0.006 > 0.005
    assert st["std_dy"][0] == pytest.approx(np.std([0.004, 0.004, 0, 0], ddof=1))


def test_lhs_converges_faster_than_mc_for_the_mean():
    """The paper's claim (Sec. 2.2), measured: error variance ratio MC / LHS at equal N."""
    d = CASES["b"]
    robot = Planar5R("b")
    out = U.convergence_study(robot.evaluation_poses()[:3], d.r1, d.r2, d.r3, sizes=(32, 128), n_rep=30,
                              n_reference=2 ** 13, seed=1)
    assert min(out["variance_ratio"]["mean_dx"]) > 3
    for method in ("mc", "lhs"):
        assert out[method]["rms_dev"][1] < out[method]["rms_dev"][0]      # error falls with N
