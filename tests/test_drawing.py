"""Drawing-ready values (issue 34 item 5): zones rounded to a stated drawing precision, the drawn
zones re-checked against the requirement (checked here against the worst-case closed form of a
linear stack), no float noise in the exported table."""
from __future__ import annotations

import re

import numpy as np
import pytest

from evotol.cost_models.power import PowerCost
from evotol.core.problem import Requirement, Tolerance, ToleranceProblem
from evotol.summaries.drawing import clean, rounded_design
from evotol.units.display import DisplayUnits
from evotol.robots.assembly import LinearStack

LIMIT = 1e-4          # m: gap within ±100 µm of its nominal


def stack_problem():
    robot = LinearStack({"a": 1.0, "b": -1.0, "c": 1.0}, {"gap": LIMIT})
    cost = PowerCost(1.0, 1.0, scale=1e-3)
    tol = {"a": Tolerance(cost, 1e-6, 1e-3, minus=1.0, plus=0.0),          # +0 / -t
           "b": Tolerance(cost, 1e-6, 1e-3, minus=0.4, plus=1.6),          # unequal
           "c": Tolerance.fixed(12.34e-6)}                                 # bought in: outward
    return ToleranceProblem(robot, tol, Requirement(position=1.0), np.zeros((1, 1)))


def test_rounded_zones_and_their_worst_case_closed_form():
    p = stack_problem()
    t = np.array([38.438e-6, 21.488e-6, 12.34e-6])
    d = rounded_design(p, t, DisplayUnits("µm"))
    z = d["zones"]
    assert z["a"] == {"drawing_lower": -38.4, "drawing_upper": 0.0}              # inward
    assert z["b"] == {"drawing_lower": -8.5, "drawing_upper": 34.3}              # -8.5952 up, 34.3808 down
    assert z["c"] == {"drawing_lower": -12.4, "drawing_upper": 12.4}             # fixed: outward
    # worst case of gap = a - b + c over the drawn zones and c as given (closed form), over the limit
    lower = -38.4 - 34.3 - 12.34
    upper = 0.0 + 8.5 + 12.34
    assert d["normalised_error"] == pytest.approx(max(-lower, upper) * 1e-6 / LIMIT, rel=1e-9)
    assert d["meets"] is (max(-lower, upper) <= 100)


def test_a_coarse_precision_says_the_zone_vanishes():
    p = stack_problem()
    d = rounded_design(p, np.array([38.438e-6, 21.488e-6, 12.34e-6]), DisplayUnits("mm"), {"mm": 0.1})
    assert set(d["vanished"]) >= {"a", "b"} and d["normalised_error"] is None


@pytest.mark.parametrize("v, want", [(9524.999999999998, 9525.0), (0.1 + 0.2, 0.3), (-0.0, 0.0), (1.0e-7 * 3, 3e-7)])
def test_clean_removes_float_noise(v, want):
    assert clean(v) == want and repr(clean(v)) == repr(want)


def test_exported_table_has_no_float_noise_and_states_the_drawing(tmp_path):
    from evotol.reporting.export import tolerance_table
    from evotol.summaries.user_study import study_summary
    from evotol.allocators import allocate_optimum

    p = stack_problem()
    r = allocate_optimum(p)
    summary = study_summary("s", p, {"optimum": r}, None, {}, seed=0, units=DisplayUnits("mm"), seconds=0.0, maps=False)
    table = tolerance_table(summary)
    for col in ("drawing lower deviation", "drawing upper deviation"):      # at most the precision's 4 decimals
        assert all(len(repr(float(v)).split(".")[1]) <= 4 for v in table[col]), table[col]
    for col in ("nominal", "± tolerance", "lower deviation", "upper deviation"):   # no 9524.999999999998
        assert not any(re.search(r"(9{8,}|0{8,})[1-9]$", repr(float(v))) for v in table[col] if v is not None), table[col]
    row = table.set_index("source").loc["b"]
    assert row["drawing upper deviation"] <= row["upper deviation"] and row["drawing lower deviation"] >= row["lower deviation"]
    assert summary["drawing"]["optimum"]["meets"]


def test_nominal_blank_when_not_known_and_filled_when_given():
    """A LinearStack built without nominals has none in the drawing table (not a made-up 0); with
    them, the nominal column carries them in display units."""
    from evotol.summaries.user_study import source_nominals

    assert source_nominals(stack_problem().model) == {}
    robot = LinearStack({"a": 1.0, "b": -1.0}, {"gap": LIMIT}, nominal={"a": 0.05, "b": 0.02})
    assert source_nominals(robot) == {"a": 0.05, "b": 0.02}


def test_report_precision_is_stated_and_checked_before_work(tmp_path):
    """[report] precision = 0.01 (mm) rounds the drawn zones to 0.01 mm; a bad value is refused
    before any method runs."""
    from evotol.errors import ValidationError
    from evotol.studyfile import run_study_file

    (tmp_path / "h34_prec_gap.py").write_text("def gap(a, b):\n    return a - b\n")
    text = ('name = "prec"\n[robot]\nassembly = "h34_prec_gap:gap"\nnominal = { a = 0.05, b = 0.02 }\n'
            'limits = { gap = 1e-4 }\n[bounds]\nlower = 1e-6\nupper = 1e-3\n[cost.default]\nmodel = "power"\n'
            'a0 = 1.0\na1 = 1.0\nscale = 1e-3\n[methods]\noptimum = {}\n[verify]\nn_samples = 20\n'
            '[report]\nunits = "mm"\nprecision = PREC\n')
    (tmp_path / "p.toml").write_text(text.replace("PREC", "0.01"))
    s = run_study_file(tmp_path / "p.toml", out=tmp_path)
    d = s["drawing"]["optimum"]
    assert d["precision"] == {"mm": 0.01} and d["zones"]["a"] == {"drawing_lower": -0.05, "drawing_upper": 0.05}
    (tmp_path / "p.toml").write_text(text.replace("PREC", "-1"))
    with pytest.raises(ValidationError, match="report.precision"):
        run_study_file(tmp_path / "p.toml", out=tmp_path / "out")
    assert not (tmp_path / "out").exists()
