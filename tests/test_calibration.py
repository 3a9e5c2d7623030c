"""Calibrated robots (issue 36, docs/calibration.md): the post-calibration map e = (J - J_K A_K+ A) dp, the
base set, the propagated noise and its share of the requirement, on the shipped UR5 study.

Independent checks: the map against a least-squares fit of sampled readings (numpy.linalg.lstsq, not the
pseudo-inverse the module uses); the noise covariance against sampled noise pushed through the fit; the
first-order yield with noise against a Monte Carlo of the same normal model."""
from __future__ import annotations

import tomllib
from pathlib import Path

import numpy as np
import pytest
import scipy.linalg
import scipy.optimize

from evotol.allocators import allocate_optimum
from evotol.calibration import CalibrationPlan, calibrated_problem, identify
from evotol.errors import ValidationError
from evotol.studyfile import load_problem

ROOT = Path(__file__).resolve().parents[1]
#: the five joint offsets a position reading at tool0 sees (wrist_3 turns tool0 about its own origin)
OFFSETS = ["shoulder_pan_joint", "shoulder_lift_joint", "elbow_joint", "wrist_1_joint", "wrist_2_joint"]


@pytest.fixture(scope="module")
def ur5():
    spec = tomllib.loads((ROOT / "reports/studies/ur5_urdf.toml").read_text())
    return load_problem(spec, base_dir=ROOT / "reports/studies")


def qr_rank(A: np.ndarray, rtol: float = 1e-9) -> int:
    """Rank by column-pivoted QR (scipy): the count of |R_ii| above ``rtol`` of |R_00|. The stated tolerance
    1e-9 lies between the model's round-off (a combination of columns cancels to ~1e-12 of the largest
    column in double precision) and the weakest real direction of these plans (~1e-4)."""
    d = np.abs(np.diag(scipy.linalg.qr(A, pivoting=True, mode="r")[0]))
    return int(np.sum(d > rtol * d[0]))


def fibonacci_sphere(n: int) -> np.ndarray:
    """(n, 3) nearly uniform unit directions."""
    i = np.arange(n) + 0.5
    z = 1 - 2 * i / n
    r, phi = np.sqrt(1 - z * z), np.pi * (1 + 5 ** 0.5) * i
    return np.c_[r * np.cos(phi), r * np.sin(phi), z]


def slsqp_optimum(problem, G: np.ndarray, E: float, n_directions: int = 300) -> float:
    """An independent optimum: min Σ cost_j(t_j) s.t. Σ_j t_j |uᵀ G_pj| <= E for every pose p and every u of a
    direction grid (the support function of the error box's image, sampled: a relaxation, so its optimum is a
    lower bound of the exact one), solved by scipy's SLSQP in t/upper."""
    U = fibonacci_sphere(n_directions)
    rows = np.abs(np.einsum("ud,pdj->puj", U, G)).reshape(-1, G.shape[-1])
    u = problem.upper
    res = scipy.optimize.minimize(lambda x: problem.cost((x * u)[None])[0], np.full(len(u), 0.05),
                                  jac=lambda x: problem.dcost(x * u) * u, method="SLSQP",
                                  bounds=scipy.optimize.Bounds(problem.lower / u, np.ones(len(u))),
                                  constraints=[scipy.optimize.LinearConstraint(rows * u / E, -np.inf, 1.0)],
                                  options={"maxiter": 1000, "ftol": 1e-14})
    return float(res.fun)


# Slow (about 20 s in CI) because its check is strong: the reference optimum is an independent SLSQP on
# 27 poses x 300 directions = 8 100 rows of 36 sources, solved twice (before and after calibration).
def test_issue_numbers_rank_and_offsets_only_optimum(ur5):
    """Issue 36: 40 LHS configurations of the task box see 17 identifiable directions of the 36 sources (the
    zero column of wrist_3_joint is no direction, issue 39); calibrating the offsets (first order only: linear
    range switched off) takes the certified optimum from 15.12 to 1.81. Rank: scipy's pivoted QR of the readings'
    map; optima: an independent SLSQP on the direction-grid relaxation (lower bound within 0.5 %), the calibrated
    map built by numpy.linalg.lstsq (J − J_K A_K⁺ A), not by the module."""
    idn = identify(ur5.model, CalibrationPlan(noise=0.0, count=40, seed=0))
    S = ur5.model.sensitivity_at_joints(idn.joints)
    A = S[:, :3].reshape(-1, S.shape[-1])
    assert idn.rank == qr_rank(A) == 17 and idn.n_measurements == A.shape[0] == 120
    assert "wrist_3_joint" in idn.unseen
    J = ur5.model.sensitivity(ur5.poses)[:, :3]
    E = ur5.requirement.position
    own, ref = allocate_optimum(ur5).cost, slsqp_optimum(ur5, J, E)
    assert 0.995 * own <= ref <= own * (1 + 1e-9)
    assert own == pytest.approx(15.12, abs=0.005)                   # the number issue 36 quotes
    pc = calibrated_problem(ur5, CalibrationPlan(noise=0.0, identify=OFFSETS, count=40, seed=0, linear_fraction=1e8))
    Sc = ur5.model.sensitivity_at_joints(pc.calibration.identification.joints)
    Ac = Sc[:, :3].reshape(-1, Sc.shape[-1])
    K = [ur5.names.index(n) for n in OFFSETS]
    G = J - J[:, :, K] @ np.linalg.lstsq(Ac[:, K], Ac, rcond=None)[0]
    own, ref = allocate_optimum(pc).cost, slsqp_optimum(pc, G, E)
    assert 0.995 * own <= ref <= own * (1 + 1e-9)
    assert own == pytest.approx(1.81, abs=0.005)


def test_post_calibration_map_against_a_least_squares_fit(ur5):
    """J M dp equals J dp - J_K x, x the lstsq fit of the readings A dp by the identified columns."""
    plan = CalibrationPlan(noise="20 um", identify=OFFSETS, count=40, seed=0)
    idn = identify(ur5.model, plan)
    S = ur5.model.sensitivity_at_joints(idn.joints)
    A = S[:, :3].reshape(-1, S.shape[-1])
    K = [ur5.names.index(n) for n in OFFSETS]
    dp = np.random.default_rng(3).uniform(-1e-3, 1e-3, (ur5.model.n_columns, 5))
    x = np.linalg.lstsq(A[:, K], A @ dp, rcond=None)[0]
    J = ur5.model.sensitivity(ur5.poses)
    expected = J @ dp - J[:, :, K] @ x
    assert np.allclose(J @ idn.M @ dp, expected, rtol=0, atol=1e-12)


def test_every_identifiable_source_leaves_no_first_order_error_in_the_box(ur5):
    """Issue 36: calibrating the base set the box configurations see leaves J M = 0 at the task poses (position)."""
    pc = calibrated_problem(ur5, CalibrationPlan(noise="2 um", count=40, seed=0))
    J = ur5.model.sensitivity(ur5.poses)[:, :3]
    assert np.abs(pc.jacobian[:, :3]).max() < 1e-9 * np.abs(J).max()
    info = pc.calibration.identification
    assert len(info.identified) + len(info.registration) <= info.rank
    assert "wrist_3_joint" in info.unseen and info.condition > 1e3        # the box alone is a poor plan
    assert all(n in info.dropped for n in pc.names if n not in info.identified_names)


def test_joint_space_plan_is_better_conditioned_and_registers_the_instrument(ur5):
    """Drawing over the joint limits sees more (23 identifiable directions > 17, by pivoted QR) with a condition number near 5; with an unknown
    instrument frame the base registration absorbs the base placement errors (they are dropped, with reason)."""
    known = identify(ur5.model, CalibrationPlan(noise="20 um", count=40, over="joints", seed=0))
    unknown = identify(ur5.model, CalibrationPlan(noise="20 um", count=40, over="joints", seed=0, instrument="unknown"))
    S = ur5.model.sensitivity_at_joints(known.joints)
    assert known.rank == qr_rank(S[:, :3].reshape(-1, S.shape[-1])) == 23 and known.condition < 10
    assert unknown.registration[:6] == ["base.shift_x", "base.shift_y", "base.shift_z", "base.tilt_x", "base.tilt_y",
                                        "base.tilt_z"]
    assert "shoulder_pan_joint.shift_x" in known.identified_names
    assert "shoulder_pan_joint.shift_x" not in unknown.identified_names
    assert "registration" in unknown.dropped["shoulder_pan_joint.shift_x"]


def test_noise_covariance_against_sampled_noise(ur5):
    """J_K Sigma_K J_K^T against 20 000 noise draws pushed through the weighted fit (position block)."""
    plan = CalibrationPlan(noise={"position": ["20 um", "20 um", "40 um"]}, identify=OFFSETS, count=40, seed=0)
    pc = calibrated_problem(ur5, plan)
    idn = pc.calibration.identification
    eps = np.random.default_rng(0).standard_normal((20000, idn.n_measurements)) * plan.sigma_rows(40)
    xhat = (eps * idn.weights) @ idn.estimator.T
    J = ur5.model.sensitivity(ur5.poses)[:, :3][:, :, idn.identified]
    e = -np.einsum("pik,sk->psi", J, xhat)
    C = np.einsum("psi,psj->pij", e, e) / len(eps)
    model = pc.model.noise_covariance(ur5.poses)[:, :3, :3]
    assert np.allclose(C, model, rtol=0.05, atol=0.05 * np.abs(model).max())


def test_noise_share_of_the_requirement(ur5):
    """Worst case: E - q - second order (q the noise norm's 99.73 % quantile, between 3 sigma_max and the 3-D
    chi quantile of sigma_max, sqrt(chi2_3(0.9973)) = 3.76: the propagated covariance has one eigenvalue
    sigma_max^2 and smaller ones); rss: in quadrature; yield: the bound is kept (covariance)."""
    plan = CalibrationPlan(noise="20 um", identify=OFFSETS, count=40, seed=0, k=3)
    pc = calibrated_problem(ur5, plan)
    n = pc.calibration.noise["position"]
    sig = np.sqrt(np.linalg.eigvalsh(pc.model.noise_covariance(ur5.poses)[:, :3, :3])[:, -1]).max()
    q = n["allowance"]
    assert n["sigma"] == pytest.approx(sig) and 3 * sig < q < 3.7625 * sig
    d = n["second_order"] + n["remainder"]
    assert pc.requirement.position == pytest.approx(5e-4 - q - d)
    assert pc.calibration.requirement.position == 5e-4
    rss = calibrated_problem(ur5.with_requirement(measure="rss"), plan)
    assert rss.requirement.position == pytest.approx(np.sqrt((5e-4 - d) ** 2 - q ** 2))


def test_yield_with_noise_against_monte_carlo(ur5):
    """The yield model adds the propagated noise covariance: its probability at the worst pose matches a Monte
    Carlo of normal source errors plus noise through the fit (exact normal model; 40 000 samples)."""
    from evotol.core.tolerance import Tolerance
    import dataclasses

    tol = {n: dataclasses.replace(t, distribution="normal") for n, t in ur5.tolerances.items()}
    base = type(ur5)(ur5.model, tol, ur5.requirement.__class__(position=5e-4, measure="yield", probability=0.99),
                     ur5.poses)
    plan = CalibrationPlan(noise="40 um", identify=OFFSETS, count=40, seed=0)
    pc = calibrated_problem(base, plan)
    t = np.full(len(pc.names), 2e-4)
    ym = pc.first_order_yield()
    res = ym.evaluate(t[None], 0.99)
    p = int(np.argmin(res.probability[0]))
    rng = np.random.default_rng(1)
    n = 40000
    k = ym.unit_var ** 0.5                                   # unit sigma of a normal tolerance (t = k-sigma bound)
    dp = rng.standard_normal((n, len(t))) * t * k
    idn = pc.calibration.identification
    eps = rng.standard_normal((n, idn.n_measurements)) * plan.sigma_rows(40)
    J = pc.model.base.sensitivity(pc.poses[p:p + 1])[0, :3]
    e = dp @ (J @ idn.M).T - ((eps * idn.weights) @ idn.estimator.T) @ J[:, idn.identified].T
    inside = np.mean(np.linalg.norm(e, axis=1) <= pc.requirement.position)
    assert inside == pytest.approx(res.probability[0, p], abs=4 * np.sqrt(0.01 / n) + 2e-3)
    assert isinstance(tol[pc.names[0]], Tolerance)


def test_plans_by_joints_poses_and_orientation(ur5):
    """Joint values of the same configurations give the same map as the count they came from; workspace poses work;
    measuring the orientation too makes wrist_3_joint (unseen by a position reading at tool0) identifiable."""
    a = identify(ur5.model, CalibrationPlan(noise="20 um", identify=OFFSETS, count=40, seed=0))
    b = identify(ur5.model, CalibrationPlan(noise="20 um", identify=OFFSETS, joints=a.joints))
    assert np.allclose(a.M, b.M, atol=1e-12)
    c = identify(ur5.model, CalibrationPlan(noise="20 um", identify=OFFSETS, poses=ur5.poses))
    assert c.n_measurements == 3 * ur5.n_poses and c.condition < 100
    with pytest.raises(ValidationError, match="wrist_3_joint"):
        identify(ur5.model, CalibrationPlan(noise="20 um", identify=["*_joint"], count=40))
    d = identify(ur5.model, CalibrationPlan(noise={"position": "20 um", "orientation": "10 urad"}, identify=["*_joint"],
                                            count=40, measure=["position", "orientation"]))
    assert "wrist_3_joint" in d.identified_names and d.n_measurements == 240


def test_a_model_without_joint_maps_and_with_disk_sources():
    """The 3-UCR (evotol.robots.ucr3: lengths plus joint-clearance disks): from workspace poses only its interval
    sources are identified and a disk named is refused; but a calibrated *problem* is refused with its
    reason (no joint maps: no linear-range bound, no simulated calibration), since without them every
    identified source would run to its upper bound and the first-order model would call that design
    certified (issue 39: 'certified' at a cost of 8.8e-21)."""
    from evotol.calibration.identification import identify

    spec = tomllib.loads((ROOT / "reports/studies/ucr3_example.toml").read_text())
    p = load_problem(spec, base_dir=ROOT / "reports/studies")
    idn = identify(p.model, CalibrationPlan(noise=1e-6, count=30))
    assert idn.identified_names == ["l1", "l2", "l3"]
    J = p.model.sensitivity(p.poses)
    assert np.abs((J @ idn.M)[:, :, :3]).max() < 1e-9 * np.abs(J).max()
    with pytest.raises(ValidationError, match="U1a"):
        identify(p.model, CalibrationPlan(noise=1e-6, count=30, identify=["U1a"]))
    with pytest.raises(ValidationError, match="calibration.joints"):
        identify(p.model, CalibrationPlan(noise=1e-6, count=30, over="joints"))
    with pytest.raises(ValidationError, match="^calibration = '3-UCR.*joint maps give the linear-range bounds"):
        calibrated_problem(p, CalibrationPlan(noise=1e-6, count=30))


def test_no_source_of_a_calibrated_robot_is_marked_without_effect(ur5):
    """Calibrating every identifiable source zeroes the first-order map at the task poses (below
    1e-9 of the uncalibrated one), yet each source still acts through the second-order terms its
    linear-range bound limits: the tables must not call any of them 'no effect on the requirement'.
    The uncalibrated problem's own marks are what the first-order map says."""
    import numpy as np

    from evotol.summaries.user_study import sources_without_effect

    pc = calibrated_problem(ur5, CalibrationPlan(noise="2 um", count=40, seed=0))
    J = ur5.model.sensitivity(ur5.poses)[:, :3]            # position: the requirement's component
    assert np.abs(pc.jacobian[:, :3]).max() < 1e-9 * np.abs(J).max()   # the first-order map is gone ...
    assert not sources_without_effect(pc).any()            # ... but no source is called without effect
    assert sources_without_effect(ur5).sum() < ur5.n_sources
