"""The study's GA, equal-effect rule, equal tolerances and Lagrange closed form on the random sources of a
calibrated budget (issue 44: every allocator, also inside ``[calibration]``; evotol/calibration/random_rules.py,
evotol/studyfile/iso9283_calibrated.py, docs/iso9283.md).

The UR5 of reports/studies/ur5_calibrated.toml with ``[requirement] iso9283 = { AP = "0.3 mm", RP = "0.05 mm" }``
(as tests/test_iso9283_calibrated_budget.py). References written here: each design's cost from the study file's
cost formulas (``a0 + a1 scale / t``, read from the TOML), RP at every ISO pose by our own sampling of J·δq
(Pinocchio's Jacobian, the cycle draws of tests/test_iso9283_calibrated_budget.py), the Lagrange stationarity by
central differences of those formulas, and the least-cost design of the same budget.
"""
from __future__ import annotations

import dataclasses
import tomllib
from pathlib import Path

import numpy as np
import pytest

from evotol.calibration.random_rules import calibrated_design, normalised_effects, rule_tolerances
from evotol.measures.iso9283.budget import joints_and_maps
from evotol.reporting.iso9283 import calibrated_method_lines, not_iso
from evotol.studyfile import load_problem
from evotol.studyfile.iso9283_calibrated import calibrated_methods, calibrated_scope
from tests.test_iso9283 import JOINTS, pinocchio_position_jacobian
from tests.test_iso9283_calibrated_budget import _columns, _cycles

ROOT = Path(__file__).resolve().parents[1]
STUDY = ROOT / "reports/studies/ur5_calibrated.toml"
RP = 5e-5
METHODS = ("equal", "sensitivity", "lagrange", "ga", "monotone")


@pytest.fixture(scope="module")
def case():
    spec = tomllib.loads(STUDY.read_text())
    spec["poses"]["grid"] = [2, 2, 2]
    spec["requirement"]["iso9283"] = {"AP": "0.3 mm", "RP": "0.05 mm"}
    spec["methods"] = {"sensitivity": {}, "optimum": {}, "ga": {"pop_size": 40, "n_gen": 40},
                       "equal": {}, "lagrange": {}, "monotone": {}}
    problem = load_problem(spec, base_dir=STUDY.parent)
    info = problem.calibration
    names = [s.name for s in info.random.sources]
    designs = {m: calibrated_design(info.random_budget, m, info.random_allocation, names, 0,
                                    ga={"pop_size": 40, "n_gen": 40} if m == "ga" else None) for m in METHODS}
    return spec, problem, names, designs


def _formula_cost(spec, names, tol: dict) -> float:
    """The study file's reciprocal prices, ``a0 + a1 scale / t`` per source, summed (written here)."""
    total = 0.0
    for n in names:
        kind = "backlash" if "backlash" in n or "lost" in n else "encoder"
        c = spec["iso9283"]["random"][kind]["cost"]
        total += c["a0"] + c["a1"] * c["scale"] / tol[n]
    return total


def test_the_study_asks_each_method_in_the_calibrated_budget(case):
    spec, problem, _, _ = case
    wanted = calibrated_methods(spec, problem)
    assert wanted == {"sensitivity": {}, "ga": {"pop_size": 40, "n_gen": 40}, "equal": {}, "lagrange": {},
                      "monotone": {}}
    scope = calibrated_scope(["sensitivity", "optimum", "ga", "monotone"], {"sensitivity": {}, "ga": {}})
    assert scope == {"sensitivity": "calibrated_budget.methods.sensitivity",
                     "optimum": "calibrated_budget.random_allocation", "ga": "calibrated_budget.methods.ga",
                     "monotone": None}
    # a method that did not allocate them is named for what it did, not as "not allocated to AP/RP"
    assert not_iso({"calibrated_budget": {}, "methods": scope}).startswith(
        "Random sources not allocated by monotone: it allocated the systematic sources alone, to the calibrated")


@pytest.mark.parametrize("method", METHODS)
def test_each_design_is_feasible_priced_and_on_the_boundary(case, method):
    spec, problem, names, designs = case
    info = problem.calibration
    rb, d, al = info.random_budget, designs[method], info.random_allocation
    t = np.array([d["tolerances"][n] for n in names])
    assert d["feasible"] and rb.ok(t) and max(d["figures"]) <= 1 + 1e-12
    assert d["cost"] == pytest.approx(_formula_cost(spec, names, d["tolerances"]), rel=1e-12)
    assert al["cost"] == pytest.approx(_formula_cost(spec, names, al["tolerances"]), rel=1e-12)
    # the least-cost design is the cheapest (its RP is sampled, so allow the aim's 1.5 % margin's effect)
    assert d["gap_to_optimum"] >= -0.005
    assert np.all(t >= rb.lo * (1 - 1e-12)) and np.all(t <= rb.hi * (1 + 1e-12))
    if method != "monotone" and not np.all(t >= rb.hi * (1 - 1e-9)):      # on the boundary: 1 % more misses
        assert not rb.ok(np.clip(1.01 * t, rb.lo, rb.hi))


@pytest.mark.parametrize("method", ("equal", "ga"))
def test_rp_of_the_design_by_our_own_sampling(case, method):
    _, problem, names, designs = case
    part = problem.calibration.random
    t = [designs[method]["tolerances"][n] for n in names]
    part = dataclasses.replace(part, tolerances=tuple(t))
    P = np.array(part.iso.positions)
    q, _ = joints_and_maps(problem.model.base, P)
    cols = _columns(part)
    dq = _cycles(part, (300000,), np.random.default_rng(5))
    dq = dq[:, [cols[part.sources.index(next(s for s in part.sources if s.joint == j))] for j in JOINTS]]
    for i in range(len(P)):
        e = dq @ pinocchio_position_jacobian({j: q[j][i:i + 1] for j in JOINTS})[:3].T
        l = np.linalg.norm(e - e.mean(axis=0), axis=1)
        rp = l.mean() + 3 * l.std(ddof=1)
        assert rp <= RP * 1.003
        assert rp == pytest.approx(designs[method]["iso"]["RP"][i], rel=5e-3)


def test_equal_and_lagrange_rules_hold_their_definitions(case):
    spec, problem, names, designs = case
    rb = problem.calibration.random_budget
    t = np.array([designs["equal"]["tolerances"][n] for n in names])
    free = (t > rb.lo * (1 + 1e-9)) & (t < rb.hi * (1 - 1e-9))
    assert free.sum() >= 2 and np.ptp(t[free]) <= 1e-12 * t[free].max()
    # Lagrange: -c_k'(τ_k) / e_k is the same multiplier for every source inside its bounds (central differences
    # of the file's formulas, written here)
    e = normalised_effects(rb)
    tl = rule_tolerances(rb, "lagrange")
    inside = (tl > rb.lo * (1 + 1e-6)) & (tl < rb.hi * (1 - 1e-6))
    assert inside.sum() >= 2
    lam = []
    for k in np.flatnonzero(inside):
        h = 1e-6 * tl[k]
        up, dn = dict(zip(names, tl)), dict(zip(names, tl))
        up[names[k]], dn[names[k]] = tl[k] + h, tl[k] - h
        slope = (_formula_cost(spec, names, up) - _formula_cost(spec, names, dn)) / (2 * h)
        lam.append(-slope / e[k])
    assert np.ptp(lam) <= 1e-5 * np.max(lam)
    assert float(np.sum(e * tl)) == pytest.approx(1.0, rel=1e-8)       # the stack-up holds with equality


def test_the_sentences_name_each_method_and_its_gap(case):
    _, problem, _, designs = case
    b = {"random_allocation": problem.calibration.random_allocation, "methods": designs}
    lines = calibrated_method_lines(b)
    assert len(lines) == 5 and all("feasible by the same check" in s and "NOT" not in s for s in lines)
    g = designs["ga"]
    assert f"The study's ga (40 x 40) allocated the random sources in the calibrated budget too: cost {g['cost']:.6g} " \
           f"({100 * g['gap_to_optimum']:+.2f} % against the least-cost design" in lines[3]


def test_the_monotone_bracket_holds_the_least_cost(case):
    """The polyblock's bracket contains the least-cost design's cost (its incumbent), its design is feasible by the
    budget's check and no dearer than the incumbent; with an RP target the lower bound is stated as proven for RP's
    monotone envelope only (the sampled RP is not monotone)."""
    _, problem, _, designs = case
    m, al = designs["monotone"], problem.calibration.random_allocation
    assert m["lower_bound"] <= al["cost"] * (1 + 1e-9) and m["cost"] <= al["cost"] * (1 + 1e-9)
    assert m["upper_bound"] == pytest.approx(m["cost"], rel=1e-12) and m["feasible"]
    assert m["gap"] == pytest.approx((m["upper_bound"] - m["lower_bound"]) / m["upper_bound"], rel=1e-9)
    assert "smaller design meets RP" in m["lower_bound_proven_for"]
    line = calibrated_method_lines({"random_allocation": al, "methods": {"monotone": m}})[0]
    assert f"Its bracket of the least cost: [{m['lower_bound']:.6g}, {m['upper_bound']:.6g}]" in line


def test_the_budget_check_decides_as_the_solved_quantiles_do(case):
    """``RandomBudget.ok`` decides each figure by one distribution evaluation per pose (``norm_within``); written
    here from the solved quantiles (``position`` = max q + max w <= budget, AP = w + q per ISO pose, RP on the fixed
    draws), it gives the same verdict on every method's design moved 1e-6 and 1e-9 either side of the boundary."""
    _, problem, names, designs = case
    rb = problem.calibration.random_budget

    def by_quantiles(t):
        return (rb.position(t) <= rb.budget and rb.ap(t).max() <= rb.AP and rb.rp_value(t).max() <= rb.rp_aim)

    checked = 0
    for m in METHODS:
        t = np.array([designs[m]["tolerances"][n] for n in names])
        for f in (1 - 1e-6, 1 - 1e-9, 1 + 1e-9, 1 + 1e-6):
            x = np.clip(t * f, rb.lo, rb.hi)
            assert rb.ok(x) == by_quantiles(x), (m, f)
            checked += rb.ok(x)
    assert 0 < checked < 4 * len(METHODS)


def test_the_methods_monotone_settings_reach_the_calibrated_bracket(case):
    """``[methods] monotone``'s ``max_evaluations``, ``rel_gap`` and ``batch`` reach the bracket in the calibrated budget
    (it ran at its own 150 evaluations and 1 % gap whatever the study said): a budget of one design stops it
    before any round, and so does a gap wider than the incumbent's bracket, where the defaults make rounds."""
    from types import SimpleNamespace
    from evotol.studyfile.iso9283_calibrated import calibrated_allocations
    spec, problem, _, designs = case
    assert designs["monotone"]["rounds"] > 0
    for settings, stop in (({"max_evaluations": 1, "rel_gap": 1e-4, "batch": 2}, "evaluations"),
                           ({"rel_gap": 0.99}, "gap")):
        assert calibrated_methods({**spec, "methods": {"monotone": settings}}, problem) == {"monotone": settings}
        out = calibrated_allocations(SimpleNamespace(calibrated={"monotone": settings}), problem.calibration, 0)
        assert out["monotone"]["stop"] == stop and out["monotone"]["rounds"] == 0, settings


def test_an_nsga2_beside_the_calibrated_iso_allocation_is_refused_from_the_file_alone(monkeypatch):
    """The ISO front does not take a calibrated budget: refused in one line before the robot is calibrated (the
    check was made after the calibrated problem, ~10 s of identification and budget here)."""
    import evotol.calibration.problem as calibration_problem
    from evotol.errors import ValidationError
    from evotol.studyfile.iso9283 import check_composable

    def no_identification(*a, **k):
        raise AssertionError("the calibration was identified before the refusal")

    spec = tomllib.loads(STUDY.read_text())
    spec["requirement"]["iso9283"] = {"AP": "0.3 mm", "RP": "0.05 mm"}
    spec["methods"]["nsga2"] = {"pop_size": 20}
    with pytest.raises(ValidationError, match=r"^methods.nsga2 = .*no nsga2 beside \[calibration\]"):
        check_composable(spec)
    monkeypatch.setattr(calibration_problem, "identify", no_identification)
    with pytest.raises(ValidationError, match="no nsga2 beside"):
        load_problem(spec, base_dir=STUDY.parent)
    del spec["requirement"]["iso9283"]           # without an ISO requirement the ordinary front runs: not refused
    check_composable(spec)


def test_random_sources_of_a_calibrated_budget_on_joint_configurations_are_refused_naming_both():
    """[poses] joints + [calibration] + [iso9283.random]: refused in one line naming the two parts, from the file
    alone (before, the same study stopped with "iso9283.random = 'JointSpaceModel'", a class name)."""
    from evotol.errors import ValidationError
    from evotol.studyfile.iso9283 import check_composable

    spec = tomllib.loads(STUDY.read_text())
    spec["poses"] = {"joints": [[0.1, -1.2, 1.4, -1.8, -1.57, 0.0]]}
    with pytest.raises(ValidationError, match=r"^iso9283.random = '\[poses\] joints': expected task poses beside "
                                              r"\[calibration\]"):
        check_composable(spec)
    del spec["calibration"]          # without [calibration] the ISO figures compose with joint configurations
    check_composable(spec)
