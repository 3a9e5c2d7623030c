"""Analysis of given tolerances (issue 33 item 3): evotol/verification/tolerance_analysis.py and a study file
whose every source is ``fixed``.

Every number is checked against an independent computation: the worst case of the norm and the
signed per-axis limits against the enumeration of the corners of the tolerance box (the error is
linear in each source, so each extreme sits at a corner), RSS against its formula, the probability
and the quantile against sampling the first-order model with the stated (uniform) distributions.
"""
from __future__ import annotations

import itertools
import json

import numpy as np
import pytest

from evotol.core.problem import Requirement, Tolerance, ToleranceProblem
from evotol.studyfile import run_study_file
from evotol.verification.tolerance_analysis import analyse
from evotol.robots.mechanism.model.joint_space import joint_configurations
from evotol.robots.mechanism.model.error_model import MechanismModel
from tests.test_standard_dh import PUMA

SOURCES = ["a2", "a3", "d3", "d4", "theta2", "theta3"]
GIVEN = {"a2": 1e-4, "a3": 1e-4, "d3": 1e-4, "d4": 1e-4, "theta2": 2e-4, "theta3": 2e-4}
CONFIGS = [[10, 10, -100, -20, 30, -60], [0, 45, 180, 0, 45, 0]]


def given_problem(offsets=None, requirement=None):
    model = MechanismModel(PUMA, sources=SOURCES)
    jm, Q = joint_configurations(model, [[f"{v}*deg" for v in c] for c in CONFIGS])
    offsets = offsets or {}
    tol = {n: Tolerance.fixed(GIVEN[n], **offsets.get(n, {})) for n in SOURCES}
    return ToleranceProblem(jm, tol, requirement or Requirement(position=5e-4), Q, all_given=True), jm, Q


def corners(J, ends):
    """(n_poses, 6) lowest and highest error, and (n_poses,) largest |dp|, over every corner."""
    lo = np.full(J.shape[:2], np.inf)
    hi = -lo
    norm = np.zeros(J.shape[0])
    for pick in itertools.product((0, 1), repeat=len(ends)):
        e = J @ ends[np.arange(len(ends)), pick]
        lo, hi = np.minimum(lo, e), np.maximum(hi, e)
        norm = np.maximum(norm, np.linalg.norm(e[:, :3], axis=1))
    return lo, hi, norm


def test_worst_case_per_axis_and_rss_equal_the_corner_enumeration():
    problem, jm, Q = given_problem()
    a = analyse(problem, n_samples=0)
    J = jm.sensitivity(Q)
    t = np.array([GIVEN[n] for n in SOURCES])
    lo, hi, norm = corners(J, np.stack([-t, t], axis=1))
    assert np.allclose(a.worst_case["position"]["value"], norm, rtol=1e-9)
    for i, ax in enumerate("xyz"):
        assert np.allclose(a.axes["base"]["position"][ax]["low"], lo[:, i], rtol=1e-12)
        assert np.allclose(a.axes["base"]["position"][ax]["high"], hi[:, i], rtol=1e-12)
        assert np.allclose(a.axes["base"]["orientation"][ax]["high"], hi[:, 3 + i], rtol=1e-12)
        assert np.allclose(a.axes["base"]["position"][ax]["rss"], np.sqrt(((J[:, i] * t) ** 2).sum(axis=1)), rtol=1e-12)
    assert a.meets == bool(norm.max() <= 5e-4)
    assert a.violation == pytest.approx(norm.max() / 5e-4 - 1, rel=1e-9)


def test_one_sided_tolerances_give_both_signed_limits():
    problem, jm, Q = given_problem(offsets={"d4": {"minus": 0.0, "plus": 2.0}, "theta2": {"offset": 5e-5}})
    a = analyse(problem, n_samples=0)
    ends = problem.intervals(np.array([GIVEN[n] for n in SOURCES]))
    lo, hi, norm = corners(jm.sensitivity(Q), ends)
    for i, ax in enumerate("xyz"):
        assert np.allclose(a.axes["base"]["position"][ax]["low"], lo[:, i], rtol=1e-12, atol=1e-18)
        assert np.allclose(a.axes["base"]["position"][ax]["high"], hi[:, i], rtol=1e-12, atol=1e-18)
    assert not np.allclose(lo[:, :3], -hi[:, :3])           # the limits are not symmetric here
    assert np.allclose(a.worst_case["position"]["value"], norm, rtol=1e-6)


def test_probability_and_quantile_against_sampling():
    """Two-sided: the first-order yield model (docs/statistical.md: δp ~ N(0, Σ_j t_j² v_j B_j B_jᵀ),
    v = 1/3 for a source uniform in ±t) sampled here with its own normal draws gives the reported
    probability and the reported 0.99 quantile to within 4 standard errors of the sampling; and
    sampling the uniform sources themselves shows the model is conservative (the normal tail is
    heavier than the bounded sum's)."""
    E = 3e-4                                              # a bound the design misses now and then (P ≈ 0.97-0.99)
    problem, jm, Q = given_problem(requirement=Requirement(position=E))
    a = analyse(problem, n_samples=0, probability=0.99)
    t = np.array([GIVEN[n] for n in SOURCES])
    B = jm.sensitivity(Q)[:, :3]
    n = 400_000
    rng = np.random.default_rng(1)
    for p in range(len(Q)):
        cov = np.einsum("ij,j,kj->ik", B[p], t ** 2 / 3, B[p])
        r = np.linalg.norm(rng.multivariate_normal(np.zeros(3), cov, n), axis=1)
        sampled = np.mean(r <= E)
        assert abs(a.probability[p] - sampled) <= 4 * np.sqrt(sampled * (1 - sampled) / n)
        # the reported bound is met with probability 0.99 (binomial standard error sqrt(0.99·0.01/n))
        at_p = np.mean(r <= a.error_at_probability["position"][p])
        assert abs(at_p - 0.99) <= 4 * np.sqrt(0.99 * 0.01 / n)
    e = rng.uniform(-1, 1, (n, len(t))) * t                 # uniform inside ±t: the stated distribution
    dp = np.linalg.norm(np.einsum("pij,nj->pni", B, e), axis=2)
    assert np.all(a.error_at_probability["position"] >= np.quantile(dp, 0.99, axis=1))
    assert np.all(a.probability <= np.mean(dp <= E, axis=1))
    assert np.all(a.error_at_probability["position"] <= a.worst_case["position"]["value"])


def test_study_with_every_source_given_is_analysed(tmp_path):
    joints = ", ".join("[" + ", ".join(f'"{v}*deg"' for v in c) + "]" for c in CONFIGS)
    given = "\n".join(f"[sources.{n}]\nfixed = {v!r}" for n, v in GIVEN.items())
    f = tmp_path / "puma_given.toml"
    f.write_text(f'''name = "puma_given"
seed = 0
[robot]
mechanism = "{PUMA}"
sources = {SOURCES!r}
[poses]
joints = [{joints}]
[requirement]
position = 5e-4
{given}
[verify]
n_samples = 300
'''.replace("'", '"'))
    summary = run_study_file(f, out=tmp_path)
    assert summary["kind"] == "analysis"
    data = json.loads((tmp_path / "puma_given.json").read_text())
    wc = data["analysis"]["worst_case"]["position"]
    assert len(wc["value"]) == 2 and data["analysis"]["monte_carlo"]["n_samples"] == 300
    assert data["joints"]["variables"] == ["q1", "q2", "q3", "q4", "q5", "q6"]
    assert np.allclose(np.degrees(data["joints"]["values"]["q3"]), [-100, 180], atol=1e-9)    # wrapped to (-180, 180]
    html = (tmp_path / "puma_given.html").read_text()
    assert "Joints used at every pose" in html and "δx range" in html
    assert ("<b>meets</b>" in html) == data["analysis"]["meets"]


def test_per_axis_tool_frame_analysis_and_verdict():
    from evotol.core.axis_limits import AxisErrorModel, AxisLimits
    problem, jm, Q = given_problem()
    model = AxisErrorModel(jm, AxisLimits(position={"x": 3e-4, "z": 5e-4}, frame="tool"))
    P = model.expand(Q)
    tol = {n: Tolerance.fixed(GIVEN[n]) for n in SOURCES}
    per_axis = ToleranceProblem(model, tol, Requirement(position=3e-4), P, all_given=True)
    a = analyse(per_axis, n_samples=0)
    R = jm.tool_pose(Q)[:, :3, :3]
    Jt = np.concatenate([np.swapaxes(R, 1, 2) @ jm.sensitivity(Q)[:, :3], np.zeros((2, 3, len(SOURCES)))], axis=1)
    t = np.array([GIVEN[n] for n in SOURCES])
    lo, hi, _ = corners(Jt, np.stack([-t, t], axis=1))
    for i, ax in enumerate("xyz"):
        assert np.allclose(a.axes["tool"]["position"][ax]["high"], hi[:, i], rtol=1e-12)
        assert np.allclose(a.axes["tool"]["position"][ax]["low"], lo[:, i], rtol=1e-12)
    expect = max(hi[:, 0].max() / 3e-4, hi[:, 2].max() / 5e-4)
    assert a.violation + 1 == pytest.approx(expect, rel=1e-9) and a.meets == (expect <= 1)
