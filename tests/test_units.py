"""Issue 15: results say their units (docs/units.md) and the certificate, not SLSQP's message, is
the verdict."""
from __future__ import annotations

import dataclasses
import json
from pathlib import Path

import pytest

from evotol.studyfile import run_study_file
from evotol.units import numbers_without_unit, unit_of

EXAMPLE = Path(__file__).resolve().parents[1] / "reports" / "studies" / "ucr3_example.toml"


@pytest.fixture(scope="module")
def run_json(tmp_path_factory):
    d = tmp_path_factory.mktemp("units")
    text = EXAMPLE.read_text().replace("grid = [5, 5, 3]", "grid = [2, 2, 2]")
    text = text[:text.index("[methods]")] + (
        "[methods]\nsensitivity = {}\noptimum = {}\nga = { pop_size = 12, n_gen = 5 }\n"
        "nsga2 = { pop_size = 12, n_gen = 5 }\nequal = { budget = 40.0 }\n\n[verify]\nn_samples = 30\n")
    (d / "s.toml").write_text(text)
    run_study_file(d / "s.toml", out=d)
    return json.loads((d / "ucr3_example.json").read_text())


def test_every_number_of_evotol_run_has_a_unit(run_json):
    block = run_json["units"]
    assert numbers_without_unit(run_json, block) == []
    assert block["tolerances"]["l1"] == "m" and block["tolerances"]["R1"] == "m"


def test_unit_of_resolves_sources_suffixes_and_refuses_unknown_keys(run_json):
    block = run_json["units"]
    assert unit_of(["results", "ga", "tolerances", "U1a"], block) == "m"
    assert unit_of(["pareto_front", "l2", 3], block) == "m"
    assert unit_of(["results", "optimum", "max_position_error"], block) == "m"
    assert unit_of(["entries", "p_max_mm"], block) == "mm"
    assert unit_of(["entries", "r_max_deg"], block) == "deg"
    assert unit_of(["results", "optimum", "wobble"], block) is None
    assert numbers_without_unit({"wobble": 1.0}, block) == ["wobble"]


def test_certificate_is_the_verdict_and_solver_message_a_diagnostic(run_json):
    opt = run_json["results"]["optimum"]
    assert opt["verdict"].startswith("certified optimal")
    assert opt["certificate"]["gap"] <= 1e-6
    assert "solver_message" not in opt and isinstance(opt["diagnostics"]["solver_message"], str)


def test_a_large_gap_is_not_certified(run_json):
    from evotol.allocators import allocate_sensitivity
    from evotol.studyfile import load_problem
    import tomllib

    P = load_problem(tomllib.loads(EXAMPLE.read_text().replace("grid = [5, 5, 3]", "grid = [2, 2, 2]")))
    r = allocate_sensitivity(P)
    assert r.verdict is None and "verdict" not in r.to_dict()       # no certificate, no verdict
    r = dataclasses.replace(r, certificate={"lower_bound": 0.9 * r.cost, "gap": 0.1, "kkt_residual": 1e-9})
    assert r.verdict.startswith("not certified: relative gap 1.00e-01")


def test_budget_mode_json_reports_budget_and_requirement_separately(run_json):
    eq = run_json["results"]["equal"]
    assert eq["budget"] == 40.0 and eq["cost"] <= 40.0 * (1 + 1e-9)
    assert eq["feasible"] is eq["within_budget"] is True
    assert isinstance(eq["meets_requirement"], bool)
