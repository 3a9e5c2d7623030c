"""The equal-effect (sensitivity) allocation under ISO 9283 AP and RP (issue 44 item 3,
evotol/allocators/iso9283_sensitivity.py, docs/iso9283.md).

Independent references written here: the UR5's joint Jacobian from Pinocchio (``computeFrameJacobian``) for
the rule's shares (each encoder offset's largest ‖J e_j‖ over the five poses), corner enumeration of AP and our
own sampling of RP (:func:`tests.test_iso9283.own_ap_and_rp`), and the certified optimum of the relaxed problem
(``allocate_iso9283``: attained AP ≤ AP, the same RP draws) as a lower bound of every feasible design's cost.
"""

import numpy as np
import pytest

from evotol.allocators.iso9283 import RP_MARGIN
from evotol.allocators.iso9283_sensitivity import allocate_iso9283_sensitivity
from evotol.errors import ValidationError
from evotol.measures.iso9283.budget import joints_and_maps

from tests.test_iso9283 import JOINTS, own_ap_and_rp, pinocchio_position_jacobian
from tests.test_iso9283_ga import AP, N_DRAWS, RP, example_spec, relaxed_optimum, small_ur5_case


@pytest.fixture(scope="module")
def case():
    args = small_ur5_case()
    return args[0], args[1], allocate_iso9283_sensitivity(*args, AP, RP, n_samples=N_DRAWS), relaxed_optimum(args)


def test_the_rules_design_meets_ap_and_rp_by_corner_enumeration_and_own_sampling(case):
    robot, P, rule, _ = case
    assert rule["feasible"]
    ap, rp = own_ap_and_rp(robot, P, rule["systematic"], rule["random"][:6], rule["random"][6:])
    assert ap.max() <= AP * (1 + 1e-9)                 # every corner, every pose
    assert ap.max() >= AP * 0.99                       # scaled onto the boundary: AP binds (measured 0.9975)
    assert rp.max() <= RP                              # measured 0.861 RP: RP does not bind here
    # evotol's RP on its 5 000 fixed draws, ours on 400 000: within about three standard errors of the
    # smaller sample (RP_MARGIN, the allocators' aim below RP for that reason; measured 0.7 %)
    assert rp == pytest.approx(rule["RP"], rel=RP_MARGIN)


def test_the_shares_are_equal_effects_by_pinocchios_jacobian(case):
    robot, P, rule, _ = case
    q, _ = joints_and_maps(robot, P)
    col = np.array([np.linalg.norm(pinocchio_position_jacobian({j: q[j][i:i + 1] for j in JOINTS})[:3], axis=0)
                    for i in range(len(P))]).max(0)                  # a_j = max_p ‖J_p e_j‖ (m/rad)
    moving = col > 1e-9 * col.max()                                  # wrist 3 does not move the flange's origin
    assert moving.sum() == 5
    t = rule["systematic"]
    effect = col[moving] * t[moving]
    assert effect == pytest.approx(np.full(5, effect[0]), rel=1e-9)  # the same share each, after one common factor
    assert t[~moving] == pytest.approx(1e-3)                         # no effect: the upper bound


def test_the_rule_costs_more_than_the_certified_optimum(case):
    _, _, rule, relaxed = case
    assert relaxed["feasible"]
    assert rule["cost"] >= relaxed["cost"] * (1 - 1e-6)              # a lower bound of every feasible design
    assert rule["cost"] >= relaxed["cost"] * 1.05                     # measured +20.6 %: the rule ignores cost


def test_a_study_with_sensitivity_writes_the_rules_iso_allocation(tmp_path):
    from evotol.studyfile.iso9283 import iso9283_block, read_iso9283
    from evotol.studyfile.problem import load_problem
    spec = example_spec({"optimum": {}, "sensitivity": {}})
    problem = load_problem(spec)
    iso = read_iso9283(spec, problem)
    assert iso.rules == ("sensitivity",)
    block = iso9283_block(iso, problem, {}, seed=0)
    g, opt = block["allocation_sensitivity"], block["allocation"]
    tols = problem.tolerances
    own = sum(float(tols[n].cost.cost(t)) for free, (n, t) in zip(problem.free, g["systematic"].items()) if free) \
        + sum(float(c.cost(g["random"][s.name])) for s, c in zip(iso.sources, iso.costs))
    assert g["cost"] == pytest.approx(own, rel=1e-12)
    assert g["gap_to_optimum"] == pytest.approx(g["cost"] / opt["cost"] - 1, rel=1e-12)
    assert g["feasible"] == (max(g["AP_bound"]) <= iso.AP * (1 + 1e-6) and max(g["RP_sampled"]) <= iso.RP * (1 + 1e-6))
    assert g["feasible"] and g["gap_to_optimum"] > 0
    from evotol.reporting.iso9283 import terminal_lines
    from evotol.units.display import DisplayUnits
    lines = terminal_lines({"iso9283": block, "display_units": DisplayUnits().to_dict()})
    assert any("equal-effect rule (sensitivity)" in line and f"{g['cost']:.6g}" in line for line in lines)


def test_without_sensitivity_there_is_no_rules_allocation_and_orientation_is_refused():
    from evotol.studyfile.iso9283 import read_iso9283
    from evotol.studyfile.problem import load_problem
    spec = example_spec({"optimum": {}})
    assert read_iso9283(spec, load_problem(spec)).rules == ()
    spec = example_spec({"optimum": {}, "sensitivity": {}})
    spec["requirement"]["iso9283"] = {"AP": "0.5 mm", "RP": "0.05 mm", "APa": "0.9 mrad"}
    with pytest.raises(ValidationError) as e:
        read_iso9283(spec, load_problem(spec))
    assert e.value.field == "requirement.iso9283.APa" and "\n" not in str(e.value) and "sensitivity" in str(e.value)


def test_the_block_maps_each_method_that_ran_to_its_allocation_to_ap_and_rp():
    from evotol.allocators import allocate_equal, allocate_sensitivity
    from evotol.reporting.iso9283 import terminal_lines
    from evotol.studyfile.iso9283 import iso9283_block, read_iso9283
    from evotol.studyfile.problem import load_problem
    from evotol.units.display import DisplayUnits
    spec = example_spec({"optimum": {}, "sensitivity": {}, "equal": {}})
    problem = load_problem(spec)
    iso = read_iso9283(spec, problem)
    results = {"sensitivity": allocate_sensitivity(problem), "equal": allocate_equal(problem)}
    block = iso9283_block(iso, problem, results, seed=0)
    # both allocate to AP/RP too (equal: evotol/allocators/iso9283_baselines.py); a method that does not is
    # named (tests/test_iso9283_baselines.py: monotone)
    assert block["methods"] == {"sensitivity": "allocation_sensitivity", "equal": "allocation_equal"}
    lines = terminal_lines({"iso9283": block, "display_units": DisplayUnits().to_dict()})
    assert not any("Not allocated to AP/RP" in line for line in lines)
    assert any(line.strip().startswith("equal tolerances (equal) allocated them too") for line in lines)
