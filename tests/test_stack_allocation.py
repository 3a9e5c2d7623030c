"""Allocation on a stack (evotol.allocators.stack_allocation, [stack.allocation]): the allocated
design's worst-case (or RSS) gap limits lie within [LSL, USL] exactly as the problem's normalised
error says (closed forms of the stack), one-sided zones stay one-sided, bought-in zones are kept."""
from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from evotol.cost_models.power import PowerCost
from evotol.allocators import allocate_ga, allocate_optimum
from evotol.allocators.stack_allocation import allocated_stack, stack_problem
from evotol.errors import ValidationError
from evotol.measures.stack_analysis import gap_moments, rss_half_width, worst_case
from evotol.studies.drake1999_motor import motor_stack
from evotol.studyfile import run_study_file

INCH = 0.0254
MOTOR = Path(__file__).resolve().parents[1] / "reports" / "studies" / "motor_stack.toml"


def _problem(measure):
    s = motor_stack(0.0, 0.12)
    cost = {n: PowerCost(1.0, 1.0, scale=INCH * 1e-3) for n in s.names}
    lo, up = {n: 0.0005 * INCH for n in s.names}, {n: 0.03 * INCH for n in s.names}
    return s, stack_problem(s, cost, lo, up, measure=measure, fixed=("D", "H"))


def test_worst_case_optimum_holds_the_limits_as_the_stack_computes_them():
    s, p = _problem("worst_case")
    r = allocate_optimum(p)
    st = allocated_stack(s, p, r.t)
    lo, hi = worst_case(st)
    centre, half = 0.06 * INCH, 0.06 * INCH
    assert max(hi - centre, centre - lo) / half == pytest.approx(r.errors.violation[0] + 1, rel=1e-9)
    assert lo >= -1e-12 and hi <= 0.12 * INCH + 1e-12
    d = {x.name: x for x in st.dimensions}
    assert d["A"].upper == 0.0 and d["A"].lower < 0          # +0/-t stays one-sided
    assert d["J"].lower == 0.0 and d["J"].upper > 0
    assert d["D"].lower == pytest.approx(-0.015 * INCH) and d["H"].upper == 0.0    # bought in: kept
    assert d["F"].upper / -d["F"].lower == pytest.approx(0.010 / 0.004)           # the drawing's shape


def test_rss_design_closed_form():
    """rss: normalised error = (|μ − centre| + T_rss)/L of the allocated stack (t = 3σ normal)."""
    s, p = _problem("rss")
    r = allocate_ga(p, pop_size=20, n_gen=15, seed=1, progress=False)
    st = allocated_stack(s, p, r.t)
    mu = gap_moments(st)["mean"]
    want = (abs(mu - 0.06 * INCH) + rss_half_width(st)) / (0.06 * INCH)
    assert r.errors.violation[0] + 1 == pytest.approx(want, rel=1e-9)
    assert r.feasible


def test_study_file_allocation_reported_as_a_stack(motor_stack_run):
    out, s = motor_stack_run
    data = json.loads((out / "motor_stack.json").read_text())
    al = data["allocation"]
    assert al["measure"] == "worst_case" and set(al["methods"]) == {"optimum", "sensitivity"}
    opt = al["methods"]["optimum"]
    assert opt["verdict"].startswith("certified optimal") and opt["cost"] <= al["methods"]["sensitivity"]["cost"]
    lo, hi = opt["stack"]["worst_case"]["limits"]
    assert -1e-12 <= lo and hi <= 0.12 * INCH + 1e-12
    assert opt["drawing"]["meets"] and opt["drawing"]["normalised_error"] <= 1
    page = Path(s["html"]).read_text()
    assert "Allocated tolerances" in page and "(kept)" in page


def test_bad_allocation_refused_before_work(tmp_path):
    text = MOTOR.read_text().replace('measure = "worst_case"', 'measure = "rss"').replace(
        "methods = { optimum = {}, sensitivity = {} }", "methods = { sensitivity = {}, optimum = {} }")
    (tmp_path / "m.toml").write_text(text)
    with pytest.raises(ValidationError) as e:
        run_study_file(tmp_path / "m.toml", out=tmp_path / "out")
    assert e.value.field == "methods.optimum: requirement.measure"
    (tmp_path / "m.toml").write_text(MOTOR.read_text().replace('fixed = ["D", "H"]', 'fixed = ["D", "Q"]'))
    with pytest.raises(ValidationError, match="stack.allocation.fixed"):
        run_study_file(tmp_path / "m.toml", out=tmp_path / "out")
    assert not (tmp_path / "out").exists()


def test_rss_of_asymmetric_zones_refused_before_the_problem_is_built(tmp_path, monkeypatch):
    """Issue 43: the refusal of the RSS optimum for asymmetric zones is read off the drawing (here a
    2 000-dimension stack), before the allocation problem is set up; the message is the optimum's."""
    import evotol.studyfile.stack_table as table

    def never(*a, **k):
        raise AssertionError("the problem was built before the refusal")

    monkeypatch.setattr(table, "stack_problem", never)
    dims = "\n".join(f"[stack.dimensions.D{i}]\nnominal = 1.0\nupper = 0.002\nlower = -0.001\ndirection = {1 - 2 * (i % 2)}"
                     for i in range(2000))
    (tmp_path / "big.toml").write_text(
        'name = "big"\n[stack]\nunit = "mm"\nlower_limit = -0.5\nupper_limit = 0.5\n'
        '[stack.allocation]\nmeasure = "rss"\nlower = 0.0001\nupper = 0.01\nmethods = { optimum = {} }\n'
        'cost = { model = "power", a0 = 1.0, a1 = 1.0, scale = 1e-6 }\n' + dims + "\n")
    with pytest.raises(ValidationError) as e:
        run_study_file(tmp_path / "big.toml", out=tmp_path / "out")
    assert e.value.field == "methods.optimum: requirement.measure" and "asymmetric" in str(e.value)
    assert not (tmp_path / "out").exists()
