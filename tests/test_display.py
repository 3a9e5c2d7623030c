"""Issue 25 item 1: display units (µm or mm, arcsec, mrad or deg) in summaries and tables, SI in the
JSON; summaries that do not contradict themselves."""
from __future__ import annotations

import math
import re
import tomllib
from pathlib import Path

import numpy as np
import pytest

from evotol.allocators import allocate_equal, allocate_optimum
from evotol.units.display import DisplayUnits, default_units, number, parse_units, pose_text
from evotol.errors import ValidationError
from evotol.verification.montecarlo import MonteCarloResult
from evotol.studyfile import check_study_keys, load_problem, report_units

STUDIES = Path(__file__).resolve().parents[1] / "reports" / "studies"


def _problem(name: str, **edits):
    spec = tomllib.loads((STUDIES / f"{name}.toml").read_text())
    spec["poses"] = {"grid": [3, 3, 2]}
    spec.update(edits)
    return spec, load_problem(spec, base_dir=STUDIES)


def test_conversions_are_the_definitions_of_the_units():
    u = DisplayUnits("mm", "arcsec")
    assert u.convert(4.4665e-05, "m") == pytest.approx(0.044665, rel=1e-12)
    assert u.convert(math.pi / 180 / 3600, "rad") == pytest.approx(1.0, rel=1e-12)       # 1″ = π/648000 rad
    assert DisplayUnits("um", "mrad").convert(1e-3, "rad") == pytest.approx(1.0, rel=1e-12)
    assert DisplayUnits("um", "deg").convert(math.pi, "rad") == pytest.approx(180.0, rel=1e-12)
    assert DisplayUnits("µm").format(1.0204e-05, "m", sign="±") == "±10.20 µm"
    assert number(0.044665) == "0.04467" and number(272.3456) == "272.3" and number(3e-7) == "3.000e-07"
    assert number(0.09999999) == "0.1000" and number(99.99996) == "100.0"


@pytest.mark.parametrize("spec,expected", [
    ("mm", ("mm", "arcsec")), ("um, mrad", ("µm", "mrad")), (["mm", "deg"], ("mm", "deg")),
    ({"angle": "deg"}, ("µm", "deg")), ({"length": "mm", "angle": "mrad"}, ("mm", "mrad")), (None, ("µm", "arcsec")),
    ("inch", ("in", "arcsec")), ("in, deg", ("in", "deg")),      # issue 34: stacks in inch
])
def test_report_units_setting(spec, expected):
    u = parse_units(spec)
    assert (u.length, u.angle) == expected


@pytest.mark.parametrize("spec", ["furlong", "mm, cm", ["mm", "um"], {"length": "deg"}, {"lenght": "mm"}, 3])
def test_bad_report_units_are_named_errors(spec):
    with pytest.raises(ValidationError, match="report.units"):
        parse_units(spec)


def test_default_units_come_from_the_mechanism_display():
    # planar 3-RRR: x, y shown in mm and phi in deg (robots/mechanisms/planar3rrr.toml)
    spec, P = _problem("planar3rrr")
    assert report_units(spec, P) == DisplayUnits("mm", "deg")
    # the built-in UCR3 shows alpha, beta in deg and Zc in m: lengths fall back to µm
    assert default_units(("deg", "deg", "m")) == DisplayUnits("µm", "deg")
    spec, P = _problem("ucr3_example", report={"units": "mm, mrad"})
    assert report_units(spec, P) == DisplayUnits("mm", "mrad")
    with pytest.raises(ValidationError, match="report.unit"):         # a typo is an error, not ignored
        check_study_keys({**spec, "report": {"unit": "mm"}})


def test_summary_and_contributions_show_display_units_and_the_worst_pose_where_it_is():
    spec, P = _problem("planar3rrr")
    r = allocate_optimum(P)
    text = r.summary()
    p = r.worst_pose()
    x_mm, y_mm, phi_deg = P.poses[p][0] * 1e3, P.poses[p][1] * 1e3, math.degrees(P.poses[p][2])
    assert f"max position error {number(r.max_error() * 1e3)} mm (requirement 0.1000 mm)" in text
    assert f"x = {number(x_mm)} mm, y = {number(y_mm)} mm, phi = {number(phi_deg)} deg" in text
    assert "e-0" not in text.splitlines()[1]               # no SI decimals like 4.4665e-05
    c = r.contributions()
    for _, row in c.iterrows():
        unit = "mm" if row["unit"] == "m" else "deg"
        factor = 1e3 if row["unit"] == "m" else 180 / math.pi
        assert row["±"] == f"±{number(row['tolerance'] * factor)} {unit}"
    assert c["tolerance"].to_numpy() == pytest.approx(r.t[[P.names.index(n) for n in c["source"]]], rel=0)  # SI kept
    # the certificate decides, and the solver's exit message is explained next to it
    if r.info.get("solver_message"):
        assert "note: the solver's exit message" in text and "certifies the cost" in text
        assert "solver_message_meaning" in r.to_dict()["diagnostics"]


def test_budget_mode_says_within_budget_and_whether_the_requirement_is_met():
    spec, P = _problem("ucr3_example")
    cheap = allocate_equal(P, budget=float(P.cost(P.full(P.upper[P.free][None]))[0]) * 1.0001)
    assert cheap.feasible and not cheap.info["meets_requirement"]
    s = cheap.summary()
    assert "within budget" in s and "misses the requirement" in s and "feasible True" not in s
    m = re.search(r"position (\S+) µm, (\S+) % above 50.00 µm", s)
    assert float(m.group(1)) == pytest.approx(cheap.max_error() * 1e6, rel=1e-3)
    assert cheap.to_dict()["status"].startswith("within budget")


def test_yield_design_summary_prints_the_yield():
    spec, P = _problem("ucr3_yield")
    r = allocate_equal(P)
    s = r.summary()
    y = float(np.min(r.errors.probability[0]))
    assert f"yield (first-order, lower bound) at the worst pose {y:.6g} (required 0.9973)" in s


def test_linearisation_check_has_a_verdict():
    mc = MonteCarloResult("lhs", 10, 0, {"position": np.zeros(1)}, {"position": np.zeros(1)}, {"position": np.zeros(1)},
                          linearisation_error=5.03e-05)
    assert mc.linearisation_verdict.startswith("first-order model adequate") and "0.00503 %" in mc.linearisation_verdict
    assert mc.to_dict()["linearisation_verdict"] == mc.linearisation_verdict
    mc.linearisation_error = 0.3
    assert mc.linearisation_verdict.startswith("first-order model unreliable")


def test_pose_text_uses_the_workspace_display_scale():
    spec, P = _problem("ucr3_example")
    assert pose_text(P.model.workspace, [math.radians(5), -math.radians(2.5), 0.3]) == \
        "alpha = 5.000 deg, beta = -2.500 deg, Zc = 0.3000 m"
