"""Issue 32 item 2, the three knots untied: the problem keeps the user's robot with the clearance
classes beside it (one combined error model, built once); refinement is a wrapper around an
allocator, and ``allocate_optimum(..., refine=True)`` with clearance sources is refused as its
docstring says -- from Python and from a study file, before any work; ``make_result`` reports the
design it is given (the repair to feasibility is the allocator's explicit step); warnings are
computed once, where they arise.
"""
import tomllib
import warnings
from pathlib import Path

import numpy as np
import pytest

import evotol.allocators.monotone as monotone_module
import evotol.allocators.optimum as optimum_module
from evotol.cost_models import ReciprocalCost
from evotol.allocators import allocate_optimum, allocate_sensitivity
from evotol.allocators.workspace_refinement import allocate_on_workspace
from evotol.cli import main
from evotol.core.plausibility import PlausibilityWarning, study_warnings
from evotol.core.problem import Requirement, Tolerance, ToleranceProblem
from evotol.core.result import make_result
from evotol.errors import ValidationError
from evotol.measures import feasibility
from evotol.measures.clearances import ClearanceSources, WithClearances, thesis_classes
from evotol.studyfile import load_problem
from evotol.robots.mechanism.model.error_model import MechanismModel, resolve_description
from tests.fast_study import fast_study

ROOT = Path(__file__).resolve().parents[1]
FIVEBAR_STUDY = ROOT / "reports" / "studies" / "fivebar_clearances.toml"
COST = ReciprocalCost(1.0, 1.0, scale=1e-6)


@pytest.fixture(scope="module")
def fivebar():
    robot = MechanismModel(resolve_description("fivebar"))
    mech = robot.clearance_mechanism()
    return robot, ClearanceSources(mech, thesis_classes([j.name for j in mech.joints], h=0.01))


def _problem(robot, cl, names):
    tols = {n: Tolerance(COST, lower=1e-7, upper=1e-4) for n in names}
    return ToleranceProblem(robot, tols, Requirement(position=1e-4), [[0.0, 0.07]], clearances=cl)


# --- knot 1: the problem holds the clearance sources beside the robot ---------------------------
def test_problem_keeps_the_users_robot_and_one_combined_error_model(fivebar):
    robot, cl = fivebar
    p = _problem(robot, cl, (*robot.source_names, *cl.names))
    assert p.model is robot and p.clearances is cl
    assert isinstance(p.error_model, WithClearances) and p.error_model.base is robot and p.error_model.geometric
    assert p.names == (*robot.source_names, *cl.names)
    # derived copies keep the same three objects (nothing rebuilt, nothing replaced)
    q = p.with_requirement(position=2e-4)
    assert q.model is robot and q.clearances is cl and q.error_model is p.error_model
    # a problem rebuilt from the first one's parts is the same problem (the robot is not the wrapper)
    r = ToleranceProblem(p.model, p.tolerances, p.requirement, p.poses, clearances=p.clearances)
    T = np.full((1, p.n_sources), 3e-6)
    assert r.evaluate(T).position == pytest.approx(p.evaluate(T).position, rel=1e-12)


def test_clearance_only_problem_has_the_classes_as_its_only_sources(fivebar):
    robot, cl = fivebar
    p = _problem(robot, cl, cl.names)
    assert p.model is robot and not p.error_model.geometric and p.names == tuple(cl.names)


def test_study_file_problem_holds_the_robot_it_describes():
    p = load_problem(tomllib.loads(FIVEBAR_STUDY.read_text()), base_dir=FIVEBAR_STUDY.parent)
    assert isinstance(p.model, MechanismModel) and p.error_model.base is p.model
    assert p.names == (*p.model.source_names, *p.clearances.names)


# --- knot 3: refinement is a wrapper; the optimum refuses refine with clearances -----------------
def test_optimum_refine_with_clearance_sources_is_refused_before_any_work(fivebar, monkeypatch):
    """allocate_optimum's docstring: ``budget``/``refine`` with clearance sources raise ValidationError.
    The polyblock bracket (the optimum's route for clearances) must not even start."""
    robot, cl = fivebar
    p = _problem(robot, cl, (*robot.source_names, *cl.names))

    def started(*args, **kwargs):
        raise AssertionError("the polyblock bracket started before the refusal")

    monkeypatch.setattr(monotone_module, "polyblock", started)
    monkeypatch.setattr(optimum_module, "allocate_monotone", started)
    for kw in ({"refine": True}, {"refine": {"grid": 3}}, {"budget": 100.0}):
        with pytest.raises(ValidationError) as exc:
            allocate_optimum(p, **kw)
        assert exc.value.field == next(iter(kw)) and "clearance sources" in str(exc.value)
        assert "\n" not in str(exc.value)


@pytest.mark.parametrize("table, field", [("optimum = { refine = true }", "methods.optimum.refine"),
                                          ("optimum = {}", "poses.refine")])
def test_study_file_optimum_refine_with_clearances_is_one_line_before_any_method(table, field, tmp_path, capsys):
    """``fivebar_clearances.toml`` with ``optimum = { refine = true }`` (or ``[poses] refine``) ended in
    ``IndexError: index 3 is out of bounds``; now one line naming the field, and no method runs
    (the GA listed first never starts)."""
    text = FIVEBAR_STUDY.read_text().replace("monotone = { max_evaluations = 1500 }", table)
    if field == "poses.refine":
        text = text.replace("[poses]\n", "[poses]\nrefine = true\n")
    study = tmp_path / "fivebar_clearances.toml"
    study.write_text(text)
    code = main(["run", str(study), "--out", str(tmp_path)])
    out = capsys.readouterr()
    assert code != 0
    lines = [x for x in out.err.splitlines() if x.strip()]
    assert len(lines) == 1 and field in lines[0] and "clearance sources" in lines[0], out.err
    assert "[evotol] ga" not in out.err and not (tmp_path / "fivebar_clearances.json").exists()


def test_refined_optimum_is_the_wrapper_around_the_optimum():
    """``allocate_optimum(p, refine=opts)`` is ``allocate_on_workspace(<optimum>, p, opts)``: the same
    design, poses and refinement record through the public wrapper."""
    from tests.test_tolerances import _ucr3_problem

    P = _ucr3_problem()
    a = allocate_optimum(P, refine={"grid": 3})
    b = allocate_on_workspace(allocate_optimum, P, {"grid": 3})
    np.testing.assert_array_equal(a.t, b.t)
    assert a.problem.n_poses == b.problem.n_poses > P.n_poses
    assert a.info["refinement"] == b.info["refinement"] and a.info["refinement"]["holds"]
    with pytest.raises(ValidationError, match="refine"):
        allocate_on_workspace(allocate_optimum, P, "yes")


def test_refined_optimum_from_a_study_file_writes_its_report(tmp_path):
    """[poses] refine with the optimum: the result's worst pose is one the refinement added (an index
    beyond the file's poses); the summary reads it from the result's own poses."""
    study = fast_study(tmp_path, ("sensitivity = {}", "optimum = {}"), ("grid = [2, 2, 2]", "latin_hypercube = 2"),
                       ("[poses]\n", "[poses]\nrefine = { grid = 3, max_rounds = 4 }\n"))
    assert main(["run", str(study), "--out", str(tmp_path)]) == 0
    import json
    data = json.loads((tmp_path / "ucr3_example.json").read_text())
    ref = data["results"]["optimum"]["refinement"]
    assert ref["n_poses"] > data["n_poses"] == 2 and ref["holds"]
    assert data["figures"]["error_maps"]["optimum"]


# --- knot 2: make_result is pure; the repair is the allocator's explicit step --------------------
def _ucr3():
    from tests.test_tolerances import _ucr3_problem

    P = _ucr3_problem()
    return P.with_poses(np.arange(P.n_poses))


def test_make_result_reports_the_design_it_is_given():
    """A design 1 % outside the requirement: make_result reports it as given (infeasible, no
    rescaling, no warning issued); hold_to_rule scales it in only when asked (a search method's
    ``max_miss``), and records the scale as before (``feasibility_repair``)."""
    P = _ucr3()
    t = allocate_optimum(P).t * 1.01                # on the requirement, then 1 % outside
    with warnings.catch_warnings():
        warnings.simplefilter("error")          # nothing issued by make_result
        r = make_result(P, "given", t)
    np.testing.assert_array_equal(r.t, t)
    assert not r.feasible and r.info["bound_ratio"] > 1 and "feasibility_repair" not in r.info
    t2, ev, rep = feasibility.hold_to_rule(P, t)        # a rule's answer 1 % outside: not repaired
    np.testing.assert_array_equal(t2, t)
    assert rep["feasibility_repair"]["failed"]
    t3, ev3, rep3 = feasibility.hold_to_rule(P, t, max_miss=np.inf)
    s = rep3["feasibility_repair"]["scale"]
    assert s < 1 and not rep3["feasibility_repair"].get("failed")
    fixed = make_result(P, "held", t3, evaluation=ev3, info=rep3)
    assert fixed.feasible and fixed.info["bound_ratio"] <= 1 + feasibility.FEASIBILITY_RTOL
    # the evaluation passed in is the design's own: the same result as evaluating it here
    assert fixed.info["bound_ratio"] == make_result(P, "held", t3).info["bound_ratio"]


def test_warnings_are_computed_once_and_listed_in_order():
    """problem.warnings is computed when the problem is built; a result's lines when it is made;
    the study lists both, in that order, without recomputing either."""
    from evotol.core import plausibility

    P = _ucr3()
    lax = P.with_requirement(position=0.05)          # 50 mm: a unit slip, and inactive for every design
    assert any("0.05 m (50 mm)" in w for w in lax.warnings) and P.warnings == []
    with pytest.warns(PlausibilityWarning, match="inactive for sensitivity"):
        r = allocate_sensitivity(lax)
    calls = []
    orig = plausibility.problem_warnings
    plausibility.problem_warnings = lambda p: calls.append(p) or orig(p)
    try:
        lines = study_warnings(lax, [r])
    finally:
        plausibility.problem_warnings = orig
    assert calls == [] and lines == [*lax.warnings, *r.info["warnings"]]
