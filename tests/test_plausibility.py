"""Issue 27 item 3: requirements and tolerance bounds that are probably unit slips, and a
requirement that does not act, are flagged in one line with the numbers and a units hint --
from the Python API (a PlausibilityWarning) and from ``evotol run`` (stderr, the JSON's
``warnings`` list and the report).

The inactive-requirement factor is checked against the closed form of the RSS measure for a
linear model: each interval source's worst-case effect is ``t_j |J_j|`` (position rows), so the
largest error is ``max over poses of sqrt(sum_j (t_j |J_j|)^2)``.
"""
from __future__ import annotations

import json
import math
import warnings

import numpy as np
import pytest

import evotol.cost_models as cm
from evotol.allocators import allocate_sensitivity
from evotol.cli import main
from evotol.core.plausibility import PlausibilityWarning, problem_warnings, result_warnings
from evotol.core.problem import Requirement, Tolerance, ToleranceProblem
from tests.fast_study import fast_study
from tests.toy_robot import ToyRobot


def _problem(position=1e-3, orientation=None, upper=1e-3, lower=1e-6, measure="rss"):
    robot = ToyRobot(dims=(1, 1, 1))
    tol = {s.name: Tolerance(cm.ExponentialCost(1.0, 0.5, scale=1e-4), lower, upper) for s in robot.sources}
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", PlausibilityWarning)
        return ToleranceProblem(robot, tol, Requirement(position=position, orientation=orientation, measure=measure),
                                np.array([[0.0], [0.5], [1.0]]))


# name: (problem keywords, strings the one line must contain)
RANGE_CASES = {
    "position requirement written in mm": ({"position": 0.05}, ["requirement.position = 0.05 m (50 mm)", "above the usual range",
                                                                "if 0.05 was meant in mm, write 5e-05"]),
    "position requirement below 10 nm": ({"position": 5e-9}, ["requirement.position = 5e-09 m", "below the usual range", "10 nm to 10 mm"]),
    "orientation requirement written in deg": ({"orientation": 0.5}, ["requirement.orientation = 0.5 rad (28.6479 deg)",
                                                                      "if 0.5 was meant in deg, write 0.00872665"]),
    "upper bound written in mm": ({"upper": 0.2}, ["tolerance upper bound of 3 sources (s0, s1, s2) = 0.2 m (200 mm)",
                                                   "if 0.2 was meant in mm, write 0.0002"]),
    "lower bound written in mm": ({"lower": 0.02, "upper": 0.05}, ["tolerance lower bound of 3 sources", "0.02 m (20 mm)"]),
}


@pytest.mark.parametrize("case", list(RANGE_CASES))
def test_value_outside_its_usual_range_is_one_line_with_a_units_hint(case):
    kw, names = RANGE_CASES[case]
    lines = problem_warnings(_problem(**kw))
    hit = [line for line in lines if names[0] in line]
    assert len(hit) == 1 and "\n" not in hit[0], lines
    for name in names:
        assert name in hit[0], (name, hit[0])


def test_usual_values_give_no_warning():
    assert problem_warnings(_problem(position=5e-5, orientation=1e-3, upper=1e-4, lower=1e-6)) == []
    assert problem_warnings(_problem(position=5e-5, upper=1e-4, lower=1e-12)) == []      # a tiny lower bound only allows more


def test_python_api_warns_at_the_problem_and_at_the_allocator():
    robot = ToyRobot(dims=(1, 1, 1))
    tol = {s.name: Tolerance(cm.ExponentialCost(1.0, 0.5, scale=1e-4), 1e-6, 1e-3) for s in robot.sources}
    with pytest.warns(PlausibilityWarning, match=r"requirement.position = 0.05 m \(50 mm\)"):
        p = ToleranceProblem(robot, tol, Requirement(position=0.05, measure="rss"), np.array([[0.0], [1.0]]))
    with pytest.warns(PlausibilityWarning, match="inactive for sensitivity"):
        r = allocate_sensitivity(p)
    assert r.info["warnings"] and "inactive" in r.info["warnings"][0]


@pytest.mark.filterwarnings("ignore::evotol.core.plausibility.PlausibilityWarning")
def test_inactive_requirement_names_the_factor_of_the_closed_form():
    p = _problem(position=0.05, upper=1e-3)
    r = allocate_sensitivity(p)
    J = p.model.sensitivity(p.poses)[:, :3, :]                 # position rows, one column per source
    rss = np.sqrt(((np.linalg.norm(J, axis=1) * 1e-3) ** 2).sum(axis=1)).max()
    assert r.max_error() == pytest.approx(rss, rel=1e-9)
    (line,) = result_warnings(p, r)
    assert f"{rss:.6g} m" in line and f"{0.05 / rss:.3g}x below it" in line and "every free tolerance sits at its upper bound" in line


@pytest.mark.filterwarnings("ignore::evotol.core.plausibility.PlausibilityWarning")
def test_an_active_requirement_is_not_flagged():
    """The same problem with a requirement that binds (half the error at the upper bounds)."""
    p = _problem(position=0.05, upper=1e-3)
    err = allocate_sensitivity(p).max_error()
    q = _problem(position=err / 2, upper=1e-3)
    r = allocate_sensitivity(q)
    assert r.max_error() == pytest.approx(err / 2, rel=1e-6)
    assert result_warnings(q, r) == [] and "warnings" not in r.info


def test_assembly_requirement_is_a_ratio_and_not_flagged():
    from evotol.robots.assembly import LinearStack

    stack = LinearStack({"x1": 1.0, "x2": -1.0}, {"gap": 1e-4})
    tol = {n: Tolerance(cm.ExponentialCost(1.0, 0.5, scale=1e-5), 1e-6, 1e-4) for n in stack.source_names}
    p = ToleranceProblem(stack, tol, Requirement(position=1.0), stack.response_poses)
    assert not any("requirement" in line for line in problem_warnings(p))


# --- evotol run: the same lines on stderr, in the JSON and in the report ------------------------
def _study(tmp_path, *edits):
    return fast_study(tmp_path, *edits)


STUDY_WARNING_CASES = {   # study-file edit: strings of the one line (stderr, JSON, report)
    "position = 0.05 meant in mm": (("position = 5e-5 ", "position = 0.05 "),
                                    ["requirement.position = 0.05 m (50 mm) is above the usual range", "write 5e-05"]),
    "position inactive (0.05)": (("position = 5e-5 ", "position = 0.05 "),
                                 ["requirement.position = 0.05 m (50 mm) is inactive for sensitivity", "x below it"]),
    "orientation = 0.5 meant in deg": (("position = 5e-5 ", "position = 5e-5\norientation = 0.5 "),
                                       ["requirement.orientation = 0.5 rad (28.6479 deg)", "write 0.00872665"]),
    "upper = 0.2 meant in mm": (("upper = 2e-4", "upper = 0.2"),
                                ["tolerance upper bound of", "0.2 m (200 mm)", "write 0.0002"]),
}


@pytest.mark.parametrize("case", list(STUDY_WARNING_CASES))
def test_run_warns_in_one_line_and_the_report_says_so(case, tmp_path, capsys):
    edit, names = STUDY_WARNING_CASES[case]
    assert main(["run", str(_study(tmp_path, edit)), "--out", str(tmp_path)]) == 0
    err = capsys.readouterr().err
    line = next(x for x in err.splitlines() if names[0] in x)
    assert line.startswith("evotol: warning: ")
    for name in names:
        assert name in line, (name, line)
    summary = json.loads((tmp_path / "ucr3_example.json").read_text())
    assert line[len("evotol: warning: "):] in summary["warnings"]
    import html
    assert html.escape(names[0]) in (tmp_path / "ucr3_example.html").read_text()


def test_run_without_slips_warns_nothing(tmp_path, capsys):
    assert main(["run", str(_study(tmp_path)), "--out", str(tmp_path)]) == 0
    assert "warning" not in capsys.readouterr().err
    assert json.loads((tmp_path / "ucr3_example.json").read_text())["warnings"] == []
