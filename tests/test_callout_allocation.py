"""Every allocator and measure on drawing callouts (issue 35 items 2, 3): the UR5 with a
position and an axial callout per joint seat (``reports/studies/ur5_callouts.toml`` on a 2x2x2
grid).

Independent checks: the cost of a callout counted once (its cost model at its value); the RSS
measure against its closed form over the zone's discs; the yield against direct sampling of
each zone (the stated in-zone distribution); every allocator against the certified optimum's
lower bound; the certified optimum on the nonlinear model; the independent-box rule's zone
containing the exact one (its design holds under the exact zones).
"""
import tomllib
from pathlib import Path

import numpy as np
import pytest

from evotol.allocators import allocate_ga, allocate_nsga2, allocate_optimum, allocate_sensitivity
from evotol.studyfile import load_problem
from evotol.studyfile.callouts import zone_comparison
from evotol.verification.nonlinear import worst_vertex_errors

STUDY = Path(__file__).resolve().parents[1] / "reports" / "studies" / "ur5_callouts.toml"


def _spec(**requirement):
    spec = tomllib.loads(STUDY.read_text())
    spec["poses"] = {"grid": 2}
    if requirement:
        spec["requirement"] = requirement
    return spec


@pytest.fixture(scope="module")
def problem():
    return load_problem(_spec(), STUDY.parent)


@pytest.fixture(scope="module")
def optimum(problem):
    return allocate_optimum(problem)


def test_a_callout_is_one_variable_costed_once(problem):
    assert problem.n_sources == 24 and problem.n_variables == 18
    assert "elbow_joint.position" in problem.variables
    x = np.linspace(5e-6, 5e-5, problem.n_variables)
    T = problem.full(x[None])
    by_var = dict(zip(problem.variables, x))
    want = sum(float(problem.tolerances[problem.model.tied_sources.get(v, (v,))[0]].cost_of(np.array([by_var[v]]))[0])
               for v in problem.variables)
    assert problem.cost(T)[0] == pytest.approx(want, rel=1e-12)


def test_certified_optimum_holds_on_the_nonlinear_model(problem, optimum):
    assert optimum.feasible and optimum.certificate is not None
    t = np.array([optimum.tolerances[n] for n in problem.names])
    nl = worst_vertex_errors(problem, t)["position"].max()
    assert nl == pytest.approx(5e-4, rel=1e-3)


# Slow (40 s in CI with two BLAS threads per worker; 5.7 s alone with one, tests/conftest.py) because its checks are strong: each allocator is held to the
# certified optimum's lower bound, and the budget mode is solved to its own certified optimum (SLSQP with
# cutting planes over the 8 poses' support rows of 18 callout variables) to meet the requirement to 1e-4.
def test_ga_nsga_sensitivity_and_budget_on_callouts(problem, optimum):
    lb = optimum.cost * (1 - 1e-6)
    ga = allocate_ga(problem, pop_size=30, n_gen=30, seed=0, progress=False)
    assert ga.feasible and ga.cost >= lb
    sens = allocate_sensitivity(problem)
    assert sens.feasible and sens.cost >= lb
    budget = allocate_optimum(problem, budget=optimum.cost)
    assert budget.errors.position.max() == pytest.approx(5e-4, rel=1e-4)


@pytest.mark.parametrize("zones", ["exact", "boxes"])
def test_certified_optimum_with_position_and_orientation_both_binding(zones):
    """Callouts with a position and an orientation requirement that both bind (2 mrad: the position optimum alone
    turns 2.4 mrad), on the shipped study's 27 poses, under exact zones and under the independent-box rule (the
    study's zone comparison). The working rows of one SLSQP solve were re-selected as the 400 largest at each pass:
    one component's rows crowded out the other's, whose variables ran to their upper bounds, and back; the boxes'
    cutting planes stopped with ``did not converge in 60 rounds (violation 2.49)``. The solve now keeps the rows
    it took. Checked: certified, each component at its limit (proven bound) and on the nonlinear model (worst
    vertex), and a GA not below the certified lower bound."""
    from evotol.studyfile.callouts import twin_problem
    spec = _spec(position=5e-4, orientation=2e-3, measure="worst_case")
    spec["poses"] = {"grid": 3}
    problem = load_problem(spec, STUDY.parent)
    problem = problem if zones == "exact" else twin_problem(problem, "boxes")
    opt = allocate_optimum(problem)
    assert opt.feasible and opt.certificate["gap"] <= 1e-6
    t = np.array([opt.tolerances[n] for n in problem.names])
    nl = worst_vertex_errors(problem, t)
    for comp, lim in (("position", 5e-4), ("orientation", 2e-3)):
        first = getattr(opt.errors, comp).max()
        assert lim * (1 - 1e-3) <= first <= lim * (1 + 1e-6), comp               # binds, and holds
        assert nl[comp].max() == pytest.approx(lim, rel=1e-3), comp
    ga = allocate_ga(problem, pop_size=30, n_gen=20, seed=0, progress=False)
    assert ga.feasible and ga.cost >= opt.certificate["lower_bound"] * (1 - 1e-6)


def test_best_accuracy_at_a_budget_with_position_and_orientation_both_binding():
    """The budget mode (least normalised error at a cost) on the same composition, 64 poses: it stopped after its
    60 rounds and returned the last round's design as the best accuracy, normalised error 2.87 at 1.05 times the
    certified optimum's cost (whose design has 1.0); now 0.914 in 22 rounds. A budget above the optimum's cost
    must give at most 1, both components at the same ratio (both bind), and a cost within the budget. Stopping
    at ``max_rounds`` is now a ``ConvergenceError`` naming the mode, not a result."""
    from evotol.errors import ConvergenceError
    spec = _spec(position=5e-4, orientation=2e-3, measure="worst_case")
    spec["poses"] = {"grid": 4}
    problem = load_problem(spec, STUDY.parent)
    opt = allocate_optimum(problem)
    best = allocate_optimum(problem, budget=opt.cost * 1.05)
    ratios = [getattr(best.errors, c).max() / lim for c, lim in problem.components]
    assert max(ratios) == pytest.approx(best.info["normalised_error"], rel=1e-9)
    assert best.info["normalised_error"] < 1 and ratios[0] == pytest.approx(ratios[1], rel=1e-6)
    assert best.cost <= opt.cost * 1.05 * (1 + 1e-9)
    with pytest.raises(ConvergenceError, match="best accuracy at budget"):
        allocate_optimum(problem, budget=opt.cost * 1.05, max_rounds=2)


def test_nsga2_front_is_non_dominated_and_bounded_by_the_optimum(problem, optimum):
    """The front (cost vs error / requirement), the certified optimum placed in its first population: no
    point dominates another; each point's cost is its cost models' sum; each point that meets the
    requirement does so in the nonlinear vertex check of its design (independent of the measure that
    ranked it; the first-order error agrees to 0.5 %); none is cheaper than the certified optimum (a
    proven lower bound), and the cheapest is within 5 % of it (NSGA-II's crowding may drop the seeded
    optimum itself from a full front of pop_size points; with this seed the cheapest is 2.7 % above)."""
    front = allocate_nsga2(problem, pop_size=20, n_gen=10, seed=0, progress=False, seeds=[optimum.tolerances])
    tab = front.table
    c, e = tab["cost"].to_numpy(), tab["normalised_error"].to_numpy()
    dominated = (c[:, None] <= c[None]) & (e[:, None] <= e[None]) & ((c[:, None] < c[None]) | (e[:, None] < e[None]))
    assert len(tab) >= 5 and not dominated.any()
    designs = np.array([[tab[n].iloc[i] for n in problem.names] for i in range(len(tab))])
    assert np.allclose(problem.cost(designs), c, rtol=1e-9)
    ok = e <= 1 + 1e-9
    assert ok.any()
    for t, ei in zip(designs[ok], e[ok]):
        nl = worst_vertex_errors(problem, t)["position"].max()
        assert nl == pytest.approx(ei * 5e-4, rel=5e-3) and nl <= 5e-4 * (1 + 5e-3)
    assert optimum.cost * (1 - 1e-6) <= c[ok].min() <= 1.05 * optimum.cost


def test_rss_is_the_closed_form_over_the_discs(problem):
    x = np.linspace(5e-6, 5e-5, problem.n_variables)
    T = problem.full(x[None])
    got = problem.evaluate(T, "rss").position[0]
    S = problem.jacobian[:, :3, :]
    want = np.sqrt(sum((T[0, j] * np.linalg.norm(S[:, :, sl], ord=2, axis=(1, 2))) ** 2
                       for j, sl in enumerate(problem.model.column_slices)))
    assert np.allclose(got, want, rtol=1e-12)


@pytest.mark.parametrize("kind", ["normal", "uniform"])
def test_yield_matches_direct_sampling_of_the_zones(kind):
    """In-zone distribution (docs/callouts.md): each end of the axis displaced independently and
    isotropically; ``normal``: components N(0, (t/2k)^2), k = 3; ``uniform``: radius uniform in
    [0, t/2], direction uniform. Sampled here from that statement, not from evotol's sampler."""
    m = 20_000                                          # evotol's own samples (nonlinear model only)
    spec = _spec(position=1.5e-4, measure="yield", probability=0.9, model="nonlinear" if kind == "uniform" else "linear",
                 **({"mc_samples": m} if kind == "uniform" else {}))
    spec["distribution"] = kind
    P = load_problem(spec, STUDY.parent)
    x = np.array([2e-5 if v.endswith("position") else (6e-5 if v.endswith("axial") else 1e-4) for v in P.variables])
    T = P.full(x[None])
    got = P.evaluate(T, "yield").probability[0]
    rng = np.random.default_rng(5)
    n, k = 60_000, 3.0
    cols = []
    for s, t in zip(P.model.sources, T[0]):
        if s.dim == 2:
            if kind == "normal":
                d = rng.normal(0, t / (2 * k), (n, 2))
            else:
                a, r = rng.uniform(0, 2 * np.pi, n), rng.uniform(0, t / 2, n)
                d = np.c_[r * np.cos(a), r * np.sin(a)]
            cols.append(2 * d)                         # a member's error is twice the end's displacement
        else:
            cols.append(rng.normal(0, t / k, (n, 1)) if kind == "normal" else rng.uniform(-t, t, (n, 1)))
    E = np.concatenate(cols, axis=1)
    err = np.linalg.norm(np.einsum("pij,nj->pni", P.jacobian[:, :3, :], E), axis=-1)
    sampled = (err <= 1.5e-4).mean(axis=1)
    assert 0.3 < sampled.min() and sampled.max() < 0.999          # a yield that can tell them apart
    # 4 standard errors of the difference: normal sources make the first-order yield exact, so only this
    # test's n draws vary; the uniform case is evotol's own count of m samples against these n, two
    # independent binomial estimates (its Latin hypercube only lowers its variance)
    var = sampled * (1 - sampled) * (1 / n + (1 / m if kind == "uniform" else 0.0))
    assert np.all(np.abs(got - sampled) <= 4 * np.sqrt(var))


def test_exact_zones_cost_less_than_boxes_and_boxes_hold_in_exact_zones(problem):
    out = zone_comparison(problem)
    assert out["exact"]["feasible"] and out["boxes"]["feasible"]
    assert out["exact"]["cost"] < out["boxes"]["cost"]
    assert out["saving"] > 0
    assert out["boxes"]["worst_in_exact_zones"]["position"]["linear"] <= 5e-4 * (1 + 1e-9)
    assert out["exact"]["worst"]["position"]["linear"] == pytest.approx(5e-4, rel=1e-6)


def test_the_drawing_table_in_page_terminal_csv_and_xlsx(tmp_path, capsys):
    """``evotol run`` of the callout study (2x2x2 grid, optimum only): the terminal, the page, the
    drawing CSV and the workbook carry each callout per part with its value, length, zone, datums,
    cost share and contribution, and the exact-zones comparison; the values are the optimum's."""
    import json

    import pandas as pd

    from evotol.cli import main

    text = STUDY.read_text().replace("grid = [3, 3, 3]", "grid = [2, 2, 2]")
    text = text[:text.index("[methods]")] + "[methods]\noptimum = {}\n\n[verify]\nn_samples = 50\n"
    f = tmp_path / "ur5_callouts.toml"
    f.write_text(text)
    assert main(["run", str(f), "--out", str(tmp_path)]) == 0
    out = capsys.readouterr().out
    assert "drawing callouts (optimum)" in out and "% saved" in out
    summary = json.loads((tmp_path / "ur5_callouts.json").read_text())
    t = summary["results"]["optimum"]["tolerances"]
    d = pd.read_csv(tmp_path / "ur5_callouts_drawing.csv")
    assert len(d) == 12 and set(d["part"]) >= {"upper_arm_link", "shoulder_link", "base_link"}
    row = d[d["feature"] == "bore axis of elbow_joint"].iloc[0]
    # the drawn value: the allocation rounded inward to the 0.1 µm drawing step (issue 41)
    import math
    drawn = math.floor(t["elbow_joint.position.end1"] * 1e7 + 1e-9) / 10
    assert row["value (µm)"] == pytest.approx(drawn) and drawn <= t["elbow_joint.position.end1"] * 1e6
    assert f"⌀{drawn:.1f} µm" in row["callout"]
    assert row["length (mm)"] == pytest.approx(50.0) and row["datums"] == "A|B"
    assert "from -25 to 25 mm along the axis (0, 1, 0)" in row["zone"]
    costs = summary["results"]["optimum"]["source_costs"]
    callout_cost = sum(costs[s] for s in costs if ".position" in s or ".axial" in s)
    assert d["cost share (%)"].sum() == pytest.approx(100 * callout_cost / sum(costs.values()))
    sheets = pd.read_excel(tmp_path / "ur5_callouts_tolerances.xlsx", sheet_name=None)
    assert {"drawing", "exact zones vs boxes"} <= set(sheets)
    html = (tmp_path / "ur5_callouts.html").read_text()
    assert "Drawing callouts" in html and "Exact zones against independent boxes" in html
    # issue 41: the symbols drawn as inline SVG (no font needed), no "nan" cell, datums named as features
    table = html[html.index("id='callouts'"):]
    table = table[:table.index("</table>")]
    assert "⌖" not in table and "⌀" not in table and 'aria-label="position"' in table and 'aria-label="diameter"' in table
    assert ">nan<" not in html
    assert "A = axis of upper_arm_link&#x27;s bore on shoulder_lift_joint" in table
    # the tolerance CSV: one row per callout with its frame and datums, not one ± row per zone member
    tol = pd.read_csv(tmp_path / "ur5_callouts_tolerances.csv")
    assert not tol["source"].str.endswith((".end1", ".end2")).any()
    row = tol[tol["source"] == "elbow_joint.position"].iloc[0]
    assert row["callout"] == f"⌖ | ⌀{drawn:.1f} µm | A | B" and row["datums"].startswith("A|B (A = axis of upper_arm_link")
    cmp_ = summary["callouts"]["comparison"]
    assert cmp_["exact"]["cost"] == pytest.approx(summary["results"]["optimum"]["cost"], rel=1e-9)


def test_sources_table_sets_a_whole_callout():
    """``[sources."elbow_joint.position"] locked = ...`` locks both end discs of that zone, which
    then count once in the cost and carry no variable."""
    spec = _spec()
    spec["sources"] = {"elbow_joint.position": {"locked": 1e-5}}
    P = load_problem(spec, STUDY.parent)
    j1, j2 = P.names.index("elbow_joint.position.end1"), P.names.index("elbow_joint.position.end2")
    assert P.locked_values[j1] == P.locked_values[j2] == 1e-5
    assert P.n_variables == 17 and "elbow_joint.position" not in P.variables
    T = P.full(np.full((1, P.n_variables), 2e-5))
    assert P.source_costs(T[0])[j2] == 0.0 and P.source_costs(T[0])[j1] > 0
