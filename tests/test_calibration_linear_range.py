"""The calibrated sources' cap derived from the iterated identification, and the noise's share as a
probability (issue 44 item 4; docs/calibration.md "Calibrated sources are not free").

Independent checks written here: robots at the corners of the caps (and of twice the caps) are read on the
nonlinear model, fitted by Levenberg-Marquardt (scipy.optimize.least_squares, one robot at a time, not the
chord iteration the cap is derived with) and compensated by a full Newton on the actuators with a
finite-difference Jacobian (not evotol's chord-method Compensation); the residual beyond the first-order
prediction must stay within the linear fraction of the requirement at the cap and grow as the square of
the scale. The noise's quantile is checked against closed forms (chi with 3 degrees of freedom, the 1-D normal)
and against noise sampled on the readings and pushed through a least-squares fit (numpy.linalg.lstsq)."""
from __future__ import annotations

import tomllib
from pathlib import Path

import numpy as np
import pytest
from scipy.optimize import least_squares
from scipy.stats import chi2, norm

from evotol.calibration import CalibrationPlan, calibrated_problem
from evotol.calibration.noise_share import level_of, norm_quantile
from evotol.errors import ValidationError
from evotol.studyfile import load_problem

ROOT = Path(__file__).resolve().parents[1]
OFFSETS = ["shoulder_pan_joint", "shoulder_lift_joint", "elbow_joint", "wrist_1_joint", "wrist_2_joint"]
E_REQ = 5e-4


@pytest.fixture(scope="module")
def offsets():
    spec = tomllib.loads((ROOT / "reports/studies/ur5_urdf.toml").read_text())
    p = load_problem(spec, base_dir=ROOT / "reports/studies")
    return calibrated_problem(p, CalibrationPlan(noise="20 um", identify=OFFSETS, count=40, seed=0))


def _readings(robot, Qc, E):
    """Flange position errors (n_conf * 3,) of one robot with column errors E on the nonlinear model."""
    return robot.pose_error_at_joints(Qc, np.broadcast_to(E, (len(Qc), 1, len(E))).copy())[:, 0, :3].ravel()


def _lm_fit(robot, Qc, K, y):
    """Identified values of the columns K by Levenberg-Marquardt on the nonlinear readings."""
    def fun(x):
        E = np.zeros(robot.n_columns)
        E[K] = x
        return (_readings(robot, Qc, E) - y) * 1e4

    sol = least_squares(fun, np.zeros(len(K)), method="lm", xtol=1e-15, ftol=1e-15, gtol=1e-15)
    assert sol.success
    return sol.x


def _compensated(robot, Qt, act, E_true, E_ident):
    """True position error (n_task, 3) after the controller makes the identified model reach each pose:
    full Newton on the actuators, Jacobian by central differences."""
    out = []
    for q in Qt:
        def err(dq, E):
            Ed = E.copy()
            Ed[act] += dq
            return robot.pose_error_at_joints(q[None], Ed[None, None])[0, 0]
        dq = np.zeros(len(act))
        for _ in range(8):
            f = err(dq, E_ident)
            J = np.column_stack([(err(dq + h, E_ident) - err(dq - h, E_ident)) / 2e-7 for h in 1e-7 * np.eye(len(act))])
            dq = dq - np.linalg.lstsq(J, f, rcond=None)[0]
        out.append(err(dq, E_true)[:3])
    return np.array(out)


def test_iterated_fit_cap_holds_at_the_cap_and_is_second_order(offsets):
    """At the corners of the final upper bounds the LM-fitted, Newton-compensated residual differs from the
    first-order prediction J M x by at most phi E (here 50 um); at twice the bounds by about 4x as much (the
    term the cap limits is second order). The caps bind: shifts the offsets absorb are capped below 1 mm."""
    info = offsets.calibration
    robot, idn = offsets.model.base, info.identification
    capped = [n for n, b in info.bounds.items() if b["linear_range"] is not None and b["upper"] < b["upper_before"]]
    assert len(capped) >= 20 and "wrist_2_joint.shift_y" in capped
    b = np.array([info.bounds[n.split("[")[0]]["upper"] for n in idn.source_names])
    q = robot.joint_values(offsets.poses)
    Qt = np.stack([np.asarray(q[v], float) for v in robot.kin.variables], axis=1)[::4]
    act = [list(robot.source_names).index(a) for a in robot.kin.actuated]
    JM = robot.sensitivity_at_joints(Qt)[:, :3] @ idn.M
    rng = np.random.default_rng(7)
    beyond = {1.0: [], 2.0: []}
    for _ in range(4):
        signs = rng.choice([-1.0, 1.0], size=len(b))
        for c in beyond:
            x = c * signs * b
            xk = _lm_fit(robot, idn.joints, idn.identified, _readings(robot, idn.joints, x))
            E_id = np.zeros_like(x)
            E_id[idn.identified] = xk
            e = _compensated(robot, Qt, act, x, E_id)
            beyond[c].append(np.linalg.norm(e - JM @ x, axis=1).max())
    r1, r2 = max(beyond[1.0]), max(beyond[2.0])
    assert r1 <= 0.1 * E_REQ
    assert 3.2 <= r2 / r1 <= 4.8
    # what the requirement keeps for it: the larger of the proven second-order term and the check's worst
    assert 0 < info.noise["position"]["remainder"] <= 0.1 * E_REQ


def test_full_identification_keeps_the_users_bounds():
    """Every identifiable source identified from joint-space configurations: the iterated fit reproduces the
    readings exactly, no second-order term is left, and every source keeps its 1 mm / 1 mrad upper bound
    (the one-step linear fit capped 33 of 36 sources, some at 0.3 mm). Checked independently on one robot
    at the corners: LM + Newton leave below 1 nm."""
    spec = tomllib.loads((ROOT / "reports/studies/ur5_calibrated.toml").read_text())
    pc = load_problem(spec, base_dir=ROOT / "reports/studies")
    info = pc.calibration
    robot, idn = pc.model.base, info.identification
    assert all(b["linear_range"] is None and b["upper"] == b["upper_before"] for b in info.bounds.values())
    x = np.random.default_rng(3).choice([-1.0, 1.0], size=robot.n_columns) * 1e-3
    xk = _lm_fit(robot, idn.joints, idn.identified, _readings(robot, idn.joints, x))
    E_id = np.zeros_like(x)
    E_id[idn.identified] = xk
    q = robot.joint_values(pc.poses)
    Qt = np.stack([np.asarray(q[v], float) for v in robot.kin.variables], axis=1)[::9]
    act = [list(robot.source_names).index(a) for a in robot.kin.actuated]
    assert np.linalg.norm(_compensated(robot, Qt, act, x, E_id), axis=1).max() < 1e-9


def test_norm_quantile_against_closed_forms():
    p = level_of(3.0)
    assert p == pytest.approx(2 * norm.cdf(3) - 1)
    s = 2e-5
    assert norm_quantile(s * s * np.eye(3), p) == pytest.approx(s * np.sqrt(chi2(3).ppf(p)), rel=1e-9)
    assert norm_quantile(np.diag([s * s, 0, 0]), p) == pytest.approx(3 * s, rel=1e-9)
    assert norm_quantile(np.diag([s * s, s * s, 0]), p) == pytest.approx(s * np.sqrt(chi2(2).ppf(p)), rel=1e-9)
    assert norm_quantile(np.zeros((3, 3)), p) == 0.0
    with pytest.raises(ValidationError, match="^probability = 1.0: expected"):
        norm_quantile(np.eye(3), 1.0)


def test_norm_within_decides_as_the_quantile_does():
    """``norm_within`` (one distribution evaluation per covariance, what the calibrated budget's check uses) accepts
    limits 1e-9 above every quantile and refuses limits 1e-9 below any one, on random covariances of rank 1-3 and a
    zero one; a negative limit is missed, a zero covariance holds a zero limit; the chi-square closed form too."""
    from evotol.calibration.noise_share import norm_within
    p = level_of(3.0)
    rng = np.random.default_rng(5)
    covs = []
    for rank in (1, 2, 3, 3, 3):
        A = rng.normal(scale=1e-5, size=(3, rank))
        covs.append(A @ A.T)
    covs = np.array(covs)
    q = norm_quantile(covs, p)
    assert norm_within(covs, p, q * (1 + 1e-9))
    for i in range(len(covs)):
        assert not norm_within(covs, p, np.where(np.arange(len(covs)) == i, q * (1 - 1e-9), q * (1 + 1e-9)))
    s = 2e-5
    assert norm_within(s * s * np.eye(3), p, s * np.sqrt(chi2(3).ppf(p)) * (1 + 1e-9))
    assert not norm_within(s * s * np.eye(3), p, s * np.sqrt(chi2(3).ppf(p)) * (1 - 1e-9))
    assert norm_within(np.zeros((1, 3, 3)), p, 0.0) and not norm_within(np.zeros((1, 3, 3)), p, -1e-12)
    with pytest.raises(ValidationError, match="^probability = 1.0: expected"):
        norm_within(np.eye(3), 1.0, 1.0)


def test_noise_share_is_a_quantile_of_sampled_noise(offsets):
    """Noise drawn on the readings (20 um per axis), fitted by numpy.linalg.lstsq on the first-order readings of
    the identified columns and pushed to the pose with the largest share: the norm exceeds the stated
    allowance at the stated rate 1 - 0.9973 (within 4 binomial standard deviations of 400 000 draws)."""
    info = offsets.calibration
    robot, idn = offsets.model.base, info.identification
    nz = info.noise["position"]
    q = robot.joint_values(offsets.poses)
    Qt = np.stack([np.asarray(q[v], float) for v in robot.kin.variables], axis=1)
    A = robot.sensitivity_at_joints(idn.joints)[:, :3][:, :, idn.identified].reshape(-1, len(idn.identified))
    Jt = robot.sensitivity_at_joints(Qt)[:, :3][:, :, idn.identified]
    # the pose with the largest share: largest quantile of the propagated covariance, from the sampled noise
    rng = np.random.default_rng(11)
    n = 400_000
    X = np.linalg.lstsq(A, 2e-5 * rng.standard_normal((A.shape[0], n)), rcond=None)[0]      # (n_K, n)
    norms = np.linalg.norm(np.einsum("pik,kn->pin", Jt, X), axis=1)                       # (n_task, n)
    worst = int(np.argmax(np.quantile(norms, 0.9973, axis=1)))
    rate = np.mean(norms[worst] > nz["allowance"])
    sd = np.sqrt(0.0027 * 0.9973 / n)
    assert abs(rate - (1 - nz["level"])) < 4 * sd
    assert nz["allowance"] > nz["k_sigma"]        # the 3-D norm's quantile is wider than 3 sigma along one axis
    assert offsets.requirement.position == pytest.approx(E_REQ - nz["allowance"] - nz["second_order"] - nz["remainder"])
