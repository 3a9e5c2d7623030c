"""Random sources in a calibrated budget (issue 44 item 4; evotol/calibration/random_share.py,
random_allocation.py, docs/calibration.md).

References, each written here and independent of the code under test:
* the random sources' worst case at a pose against enumeration of every corner of their box (segments);
* their covariance through the identification against sampling: visits drawn here, readings pushed through
  the plan's estimator, the sample covariance of the identified values;
* the calibrated UR5 example against a simulation written here: robots drawn within the allocated
  tolerances (systematic uniform within their bounds, lost motion and encoder quantisation drawn anew at
  every visit), readings on the nonlinear model plus the tracker's noise, identification by our own
  Gauss-Newton least squares on the identified columns, compensation by the identified model, and the worst
  residual at the task poses against the requirement.
"""
from __future__ import annotations

import itertools
import tomllib
from pathlib import Path

import numpy as np
import pytest

from evotol.calibration.random_share import (RandomPart, identification_covariance, visit_covariance,
                                             worst_case_norm)
from evotol.errors import ValidationError
from evotol.studyfile import load_problem
from evotol.robots.mechanism.model.random_sources import RandomSource, column_loading

ROOT = Path(__file__).resolve().parents[1]
STUDY = ROOT / "reports/studies/ur5_calibrated.toml"
ARCMIN = np.pi / 180 / 60


@pytest.fixture(scope="module")
def problem():
    spec = tomllib.loads(STUDY.read_text())
    return load_problem(spec, base_dir=STUDY.parent)


def _draw(part, n, rng):
    """Column errors of n visits, drawn here from the kinds' definitions (docs/iso9283.md)."""
    out = np.zeros((n, part.loadings[0].shape[0]))
    for s, t, G in zip(part.sources, part.tolerances, part.loadings):
        col = np.flatnonzero(G[:, 0])[0]
        if s.kind == "backlash":        # taken up from either side (b' = b), plus the varying share
            out[:, col] += t * (0.5 * np.where(rng.random(n) < 0.5, -1.0, 1.0) + s.variation * (rng.random(n) - 0.5))
        elif s.kind == "encoder":
            out[:, col] += t * (rng.random(n) - 0.5)
        else:
            raise AssertionError(s.kind)
    return out


def test_worst_case_at_a_pose_is_the_largest_corner(problem):
    robot = problem.model.described
    src = [RandomSource("backlash", j, ARCMIN, 0.1) for j in robot.kin.actuated]
    part = RandomPart(tuple(src), tuple(s.tolerance for s in src), tuple(column_loading(robot, src)))
    J = np.asarray(robot.sensitivity(problem.poses[:4]), float)[:, :3]
    bound = worst_case_norm(J, part)
    cols = [np.flatnonzero(G[:, 0])[0] for G in part.loadings]
    half = np.array([(1 + s.variation) / 2 * s.tolerance for s in src])
    corners = np.array(list(itertools.product((-1.0, 1.0), repeat=len(src)))) * half       # (64, 6)
    exact = np.linalg.norm(np.einsum("pim,cm->pci", J[:, :, cols], corners), axis=-1).max(axis=1)
    assert np.all(bound >= exact * (1 - 1e-12))
    assert np.all(bound <= exact * 1.01)          # the grid's covering angle: within 1 %


def test_identification_covariance_matches_sampled_readings(problem):
    cal = problem.model
    robot, idn, plan = cal.base, problem.calibration.identification, problem.calibration.plan
    part = problem.calibration.random
    S = robot.sensitivity_at_joints(idn.joints)[:, :3]                                  # position measured
    rng = np.random.default_rng(7)
    n = 20000
    R = _draw(part, n * len(S), rng).reshape(len(S), n, -1)
    y = np.einsum("crm,cnm->ncr", S, R).reshape(n, -1) * idn.weights                    # whitened readings
    x = y @ idn.estimator.T
    sampled = np.cov(x, rowvar=False)
    model = identification_covariance(idn.estimator, idn.weights, S, part)
    d = np.sqrt(np.diag(model))
    assert np.allclose(np.diag(sampled), np.diag(model), rtol=0.05, atol=1e-6 * d.max() ** 2)
    assert np.abs(sampled - model).max() <= 0.05 * d.max() ** 2
    # the column covariance of one visit, from its definition
    V = visit_covariance(part)
    s = part.sources[0]
    col = np.flatnonzero(part.loadings[0][:, 0])[0]
    enc = next(t for q, t in zip(part.sources, part.tolerances) if q.kind == "encoder" and q.joint == s.joint)
    assert V[col, col] == pytest.approx(part.tolerances[0] ** 2 * (0.25 + s.variation ** 2 / 12) + enc ** 2 / 12)


def test_the_calibrated_requirement_binds_on_the_random_sources(problem):
    info = problem.calibration
    al, n = info.random_allocation, info.noise["position"]
    assert al is not None and al["active"] and al["joint_optimum"]
    # the requirement: the fit's error quantile + the random worst case + second order + the systematic share
    total = n["allowance"] + n["random_worst_case"] + n["second_order"] + n["remainder"] + n["geometric_bound"]
    assert total == pytest.approx(5e-4, rel=1e-9)
    assert n["random_worst_case"] > n["noise_only"] and n["random_identification"] > 0
    # every random tolerance between its bounds, each paid for
    for s, lo, hi, t in zip(info.random.sources, info.random.lower, info.random.upper, info.random.tolerances):
        assert lo * (1 - 1e-9) <= t <= hi * (1 + 1e-9), s.name
    assert al["cost"] == pytest.approx(sum(c.cost(t) for c, t in zip(info.random.costs, info.random.tolerances)))


def test_independent_simulation_of_the_calibrated_ur5_meets_the_requirement(problem):
    """Robots within the allocated tolerances, calibrated and compensated by code written here."""
    info, cal = problem.calibration, problem.model
    robot, idn, part = cal.base, info.identification, info.random
    rng = np.random.default_rng(11)
    n_rob = 150
    t_sys = problem.upper                     # the calibrated optimum: every systematic tolerance at its upper bound
    Qc = idn.joints
    qt = robot.joint_values(problem.poses)
    Qt = np.stack([np.asarray(qt[v], float) for v in robot.kin.variables], axis=1)
    K = idn.identified
    m = robot.n_columns
    delta = t_sys * rng.uniform(-1, 1, (n_rob, m))
    visits = _draw(part, len(Qc) * n_rob, rng).reshape(len(Qc), n_rob, m)
    y = robot.pose_error_at_joints(Qc, delta[None] + visits)[..., :3] + 20e-6 * rng.standard_normal((len(Qc), n_rob, 3))
    AK = robot.sensitivity_at_joints(Qc)[:, :3][:, :, K].reshape(-1, len(K))
    pinv = np.linalg.pinv(AK)
    x = np.zeros((n_rob, len(K)))
    for _ in range(8):                        # Gauss-Newton with the first-order Jacobian
        E = np.zeros((n_rob, m))
        E[:, K] = x
        model = robot.pose_error_at_joints(Qc, np.broadcast_to(E, (len(Qc), n_rob, m)).copy())[..., :3]
        r = (y - model).transpose(1, 0, 2).reshape(n_rob, -1)
        x = x + r @ pinv.T
    E = np.zeros((n_rob, m))
    E[:, K] = x
    task = _draw(part, len(Qt) * n_rob, rng).reshape(len(Qt), n_rob, m)
    true = robot.pose_error_at_joints(Qt, delta[None] + task)[..., :3]
    ident = robot.pose_error_at_joints(Qt, np.broadcast_to(E, (len(Qt), n_rob, m)).copy())[..., :3]
    resid = np.linalg.norm(true - ident, axis=-1)                                         # (poses, robots)
    worst = resid.max()
    assert worst <= 5e-4
    # the random sources matter: the same robots without them leave far less
    y0 = robot.pose_error_at_joints(Qc, np.broadcast_to(delta, (len(Qc), n_rob, m)).copy())[..., :3]
    x0 = (y0.transpose(1, 0, 2).reshape(n_rob, -1)) @ pinv.T
    assert worst > 0.4 * 5e-4
    assert np.linalg.norm(np.einsum("pim,sm->psi", robot.sensitivity_at_joints(Qt)[:, :3][:, :, K],
                                    x0) - robot.pose_error_at_joints(Qt, np.broadcast_to(delta, (len(Qt), n_rob, m)).copy())[..., :3],
                          axis=-1).max() < 0.2 * worst


def test_random_sources_with_an_rss_requirement_are_refused():
    spec = tomllib.loads(STUDY.read_text())
    spec["requirement"]["measure"] = "rss"
    with pytest.raises(ValidationError, match="worst-case requirement"):
        load_problem(spec, base_dir=STUDY.parent)


def test_the_study_states_what_the_random_sources_take_and_cost(tmp_path, capsys):
    """evotol run of the example (smaller grid and simulation): the JSON's calibrated budget adds up to the
    requirement, the ISO block's calibrated AP is the proven systematic part plus the fit's quantile and above
    the first-order residual, RP is unchanged, the simulated calibration (random sources drawn) stays within the
    stated worst case, and the terminal and the page say what the random sources take and cost."""
    import json

    from evotol.cli import main

    text = STUDY.read_text().replace("grid = [3, 3, 3]", "grid = [2, 2, 2]").replace("simulate = 200 ", "simulate = 20 ")
    text = text.replace("ga = { pop_size = 80, n_gen = 150 }\n", "")      # the sensitivity rule stays
    text = text.replace("n_samples = 300", "n_samples = 30")
    (tmp_path / "s.toml").write_text(text)
    main(["run", str(tmp_path / "s.toml"), "--out", str(tmp_path)])
    out = capsys.readouterr().out
    data = json.loads((tmp_path / "ur5_calibrated.json").read_text())
    page = (tmp_path / "ur5_calibrated.html").read_text()
    b = data["iso9283"]["calibrated_budget"]
    assert b["noise_only"] + b["random_identification"] + b["random_worst_case"] + b["second_order"] + \
        b["remainder"] + b["geometric_bound"] == pytest.approx(b["requirement"], rel=1e-9)
    al = b["random_allocation"]
    assert al["active"] and al["cost"] == pytest.approx(sum(s["cost"] for s in data["iso9283"]["random_sources"]))
    for p in data["iso9283"]["poses"]:
        c = p["calibrated"]
        assert c["AP"]["predicted"] == pytest.approx(c["AP"]["systematic_bound"] + c["AP"]["noise_quantile"])
        assert c["AP"]["systematic"] <= c["AP"]["systematic_bound"] < p["AP"]["predicted"]
        assert c["RP"]["predicted"] == p["RP"]["predicted"]
    sim = data["calibration"]["methods"]["optimum"]["simulation"]
    assert sim["simulated"]["position"]["max"] <= sim["worst_case"]["position"] <= 5e-4
    assert "Random sources (12" in out and f"they cost {al['cost']:.4g}" in out and "the requirement binds" in out
    assert "ISO 9283 after calibration" in out and "iso9283-calibrated-plan" in page and "they cost" in page
    # the study's sensitivity rule allocated the random sources in the same budget too, judged by its check
    rule = b["methods"]["sensitivity"]
    assert rule["feasible"] and max(rule["figures"]) <= 1 + 1e-12 and rule["cost"] >= al["cost"] * (1 - 1e-9)
    assert data["iso9283"]["methods"] == {"sensitivity": "calibrated_budget.methods.sensitivity",
                                          "optimum": "calibrated_budget.random_allocation"}
    sentence = f"The study's sensitivity allocated the random sources in the calibrated budget too: cost {rule['cost']:.6g}"
    assert sentence in out and sentence in page.replace("&#x27;", "'")
