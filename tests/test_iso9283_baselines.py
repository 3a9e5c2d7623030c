"""Equal tolerances and the Lagrange closed form under ISO 9283 AP and RP (issue 44 item 3, "every allocator":
evotol/allocators/iso9283_baselines.py, docs/iso9283.md).

Independent references written here: corner enumeration of AP and our own sampling of RP through Pinocchio's
Jacobian (:func:`tests.test_iso9283.own_ap_and_rp`), the stationarity of the Lagrange closed form checked with
Pinocchio's Jacobian (reciprocal costs ``c = a0 + a1 σ / t``: ``a1 σ / t_j² = λ a_j``, so ``t_j sqrt(a_j)`` is the
same for every encoder offset on the AP stack-up, and stays so under the common scaling onto the boundary), and
the certified optimum of the relaxed problem as a lower bound of every feasible design's cost.
"""

import numpy as np
import pytest

from evotol.allocators.iso9283 import RP_MARGIN
from evotol.allocators.iso9283_baselines import allocate_iso9283_equal, allocate_iso9283_lagrange
from evotol.allocators.iso9283_sensitivity import allocate_iso9283_sensitivity
from evotol.errors import ValidationError
from evotol.measures.iso9283.budget import joints_and_maps

from tests.test_iso9283 import JOINTS, own_ap_and_rp, pinocchio_position_jacobian
from tests.test_iso9283_ga import AP, N_DRAWS, RP, example_spec, relaxed_optimum, small_ur5_case


@pytest.fixture(scope="module")
def case():
    args = small_ur5_case()
    return (args, allocate_iso9283_equal(*args, AP, RP, n_samples=N_DRAWS),
            allocate_iso9283_lagrange(*args, AP, RP, n_samples=N_DRAWS), relaxed_optimum(args))


def own_check(args, design):
    """AP by every corner and RP by 400 000 own draws, per pose (m)."""
    return own_ap_and_rp(args[0], args[1], design["systematic"], design["random"][:6], design["random"][6:])


def test_equal_tolerances_are_one_value_the_largest_that_meets_ap_and_rp(case):
    args, equal, _, _ = case
    t = np.concatenate([equal["systematic"], equal["random"]])
    lo, hi = np.concatenate([args[3][0], args[7][0]]), np.concatenate([args[3][1], args[7][1]])
    c = t[(t > lo * (1 + 1e-12)) & (t < hi * (1 - 1e-12))]
    assert len(c) >= 6 and c == pytest.approx(np.full(len(c), c[0]), rel=1e-12)     # one value, where not clipped
    assert equal["feasible"]
    ap, rp = own_check(args, equal)
    assert ap.max() <= AP * (1 + 1e-9) and rp.max() <= RP
    # the largest: 2 % more on every unclipped tolerance misses RP by our own draws (RP binds here: measured
    # 0.985 RP, the aim, on evotol's draws; AP 0.33 of its requirement)
    grown = {k: np.where(np.abs(v - c[0]) < 1e-12 * c[0], v * 1.02, v) for k, v in equal.items()
             if k in ("systematic", "random")}
    assert own_check(args, grown)[1].max() > RP * (1 - RP_MARGIN)
    assert rp.max() == pytest.approx(RP * (1 - RP_MARGIN), rel=RP_MARGIN)


def test_lagranges_encoder_offsets_are_stationary_by_pinocchios_jacobian(case):
    args, _, lag, _ = case
    robot, P = args[:2]
    q, _ = joints_and_maps(robot, P)
    col = np.array([np.linalg.norm(pinocchio_position_jacobian({j: q[j][i:i + 1] for j in JOINTS})[:3], axis=0)
                    for i in range(len(P))]).max(0)                  # a_j = max_p ‖J_p e_j‖ (m/rad)
    moving = col > 1e-9 * col.max()
    t = lag["systematic"]
    inside = moving & (t < 1e-3 * (1 - 1e-9)) & (t > 1e-6 * (1 + 1e-9))
    assert inside.sum() >= 4                                          # measured 5: all but wrist 3
    k = t[inside] * np.sqrt(col[inside])                              # a1 σ / t² = λ a: t sqrt(a) the same for each
    assert k == pytest.approx(np.full(len(k), k[0]), rel=1e-6)       # bisection in log t to 1e-18 relative
    assert t[~moving] == pytest.approx(1e-3)                          # no effect: the upper bound


def test_both_meet_ap_and_rp_by_own_check_and_cost_at_least_the_optimum(case):
    args, equal, lag, relaxed = case
    assert lag["feasible"] and relaxed["feasible"]
    ap, rp = own_check(args, lag)
    assert ap.max() <= AP * (1 + 1e-9) and rp.max() <= RP
    # evotol's RP on its 5 000 draws, ours on 400 000: within the allocators' margin (about 3 standard errors)
    assert rp == pytest.approx(lag["RP"], rel=RP_MARGIN)
    for d in (equal, lag):
        assert d["cost"] >= relaxed["cost"] * (1 - 1e-6)             # a lower bound of every feasible design
    # measured: Lagrange 6.698 (+1.9 %), the equal-effect rule 7.941, equal 27.60 against the optimum's 6.576 --
    # the cost-aware closed form is the closest; equal tolerances pay for the cheap-to-loosen lost motion
    rule = allocate_iso9283_sensitivity(*args, AP, RP, n_samples=N_DRAWS)
    assert lag["cost"] < rule["cost"] < equal["cost"]


def test_a_study_with_equal_and_lagrange_writes_both_iso_allocations():
    from evotol.reporting.iso9283 import terminal_lines
    from evotol.studyfile.iso9283 import iso9283_block, read_iso9283
    from evotol.studyfile.iso9283_methods import methods_scope
    from evotol.studyfile.problem import load_problem
    from evotol.units.display import DisplayUnits
    spec = example_spec({"optimum": {}, "equal": {}, "lagrange": {}})
    problem = load_problem(spec)
    iso = read_iso9283(spec, problem)
    assert iso.rules == ("equal", "lagrange")
    block = iso9283_block(iso, problem, {}, seed=0)
    tols, opt = problem.tolerances, block["allocation"]
    for key in ("allocation_equal", "allocation_lagrange"):
        g = block[key]
        own = sum(float(tols[n].cost.cost(t)) for free, (n, t) in zip(problem.free, g["systematic"].items()) if free) \
            + sum(float(c.cost(g["random"][s.name])) for s, c in zip(iso.sources, iso.costs))
        assert g["cost"] == pytest.approx(own, rel=1e-12)
        assert g["gap_to_optimum"] == pytest.approx(g["cost"] / opt["cost"] - 1, rel=1e-12)
        assert g["feasible"] == (max(g["AP_bound"]) <= iso.AP * (1 + 1e-6) and max(g["RP_sampled"]) <= iso.RP * (1 + 1e-6))
        assert g["feasible"] and g["gap_to_optimum"] > -0.004             # the optimum's AP aim: at most 0.4 %
    # monotone allocates to AP/RP too now: tests/test_iso9283_monotone.py runs it in a study
    block["methods"] = methods_scope(["optimum", "equal", "lagrange"], block)
    assert block["methods"] == {"optimum": "allocation", "equal": "allocation_equal", "lagrange": "allocation_lagrange"}
    lines = terminal_lines({"iso9283": block, "display_units": DisplayUnits().to_dict()})
    for name, key in (("equal tolerances (equal)", "allocation_equal"),
                      ("the Lagrange closed form (lagrange)", "allocation_lagrange")):
        assert any(name in line and f"{block[key]['cost']:.6g}" in line for line in lines)
    assert not any("Not allocated to AP/RP" in line for line in lines)


def test_an_orientation_figure_beside_a_rule_is_refused_in_one_line_and_calibration_keeps_the_rules_out():
    from evotol.studyfile.iso9283_methods import iso_rules_wanted
    from evotol.studyfile.problem import load_problem
    spec = example_spec({"optimum": {}, "lagrange": {}})
    spec["requirement"]["iso9283"] = {"AP": "0.5 mm", "RP": "0.05 mm", "APa": "0.9 mrad"}
    problem = load_problem(spec)
    with pytest.raises(ValidationError) as e:
        iso_rules_wanted(spec, problem, {"APa": 9e-4})
    assert e.value.field == "requirement.iso9283.APa" and "\n" not in str(e.value) and "lagrange" in str(e.value)
    assert iso_rules_wanted({**spec, "calibration": {}}, problem, {}) == ()
