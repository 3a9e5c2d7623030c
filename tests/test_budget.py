"""Best accuracy at a budget (issue 15), for every allocator that offers ``budget=``.

Checks: a budget below the cheapest design (every free tolerance at its upper bound; its cost is
computed here independently from the cost models) is a ValidationError naming the budget and
that cost; NaN, inf, negative and non-numbers are rejected; every returned design costs at most
the budget and ``feasible`` means "within the budget and the bounds"; the equal-tolerance rule
matches its closed form t = (σ/a1)·ln(n·a0/B); the Lagrange rule satisfies its stationarity
condition c_j'(t_j) = -λ s_j; the certified optimum's accuracy is the best of all methods.
"""
from __future__ import annotations

import numpy as np
import pytest

import evotol.cost_models as cm
from evotol.allocators import (aggregated_sensitivity, allocate_equal, allocate_ga, allocate_lagrange,
                               allocate_optimum, allocate_proportional, allocate_sensitivity)
from evotol.errors import ValidationError
from evotol.core.problem import Requirement, Tolerance, ToleranceProblem
from tests.toy_robot import ToyRobot


def _problem(measure="worst_case", same_cost=False, locked=None):
    r = ToyRobot(dims=(1, 1, 2, 2, 1))
    tol = {}
    for j, s in enumerate(r.sources):
        c = cm.ExponentialCost(2.0, 0.5, scale=1e-3) if same_cost else cm.ExponentialCost(1.0 + 0.3 * j, 0.5 + 0.1 * j, scale=1e-3)
        tol[s.name] = Tolerance(c, 1e-5, 1e-2, locked=(locked or {}).get(s.name))
    return ToleranceProblem(r, tol, Requirement(position=1e-3, measure=measure), np.array([[0.0], [0.5], [1.0]]))


def _cheapest_cost(P) -> float:
    """Σ c_j(upper_j) over free sources + Σ c_j(locked_j): straight from the cost models."""
    total = 0.0
    for n, tol in P.tolerances.items():
        t = tol.locked if tol.locked is not None else tol.upper
        total += float(tol.cost.cost(t))
    return total


FAST_GA = dict(pop_size=20, n_gen=15, seed=0)
ALLOCATORS = {
    "sensitivity": allocate_sensitivity,
    "equal": allocate_equal,
    "proportional": allocate_proportional,
    "lagrange": allocate_lagrange,
    "optimum": allocate_optimum,
    "ga": lambda P, budget: allocate_ga(P, budget=budget, **FAST_GA),
}


@pytest.mark.parametrize("name", list(ALLOCATORS))
def test_budget_below_the_cheapest_design_names_that_cost(name):
    P = _problem(locked={"s1": 2e-4})
    floor = _cheapest_cost(P)
    with pytest.raises(ValidationError) as info:
        ALLOCATORS[name](P, budget=floor * 0.5)
    msg = str(info.value)
    assert info.value.field == "budget" and info.value.value == pytest.approx(floor * 0.5)
    assert f"{floor:.6g}" in msg and "cheapest design" in msg


@pytest.mark.parametrize("name", list(ALLOCATORS))
@pytest.mark.parametrize("bad", [float("nan"), float("inf"), -1.0, 0.0, "10", True])
def test_budget_that_is_not_a_positive_number_is_rejected(name, bad):
    with pytest.raises(ValidationError) as info:
        ALLOCATORS[name](_problem(), budget=bad)
    assert info.value.field == "budget" and repr(bad) in str(info.value)


@pytest.mark.parametrize("name", list(ALLOCATORS))
def test_design_respects_the_budget_and_feasible_means_within_it(name):
    P = _problem()
    floor = _cheapest_cost(P)
    budget = 3.0 * floor
    r = ALLOCATORS[name](P, budget=budget)
    assert float(P.cost(r.t)) <= budget * (1 + 1e-9)
    assert r.feasible and r.info["within_budget"] and r.info["budget"] == budget
    assert np.all(r.t >= P.lower * (1 - 1e-12)) and np.all(r.t <= P.upper * (1 + 1e-12))
    # meets_requirement reports the requirement independently of `feasible`
    assert r.info["meets_requirement"] == bool(P.evaluate(r.t[None]).violation[0] <= 1e-9)
    if name != "ga":    # the deterministic rules spend the budget (a tighter design would not fit)
        assert float(P.cost(r.t)) >= budget * (1 - 1e-6)


def test_at_the_cheapest_budget_every_rule_returns_the_cheapest_design():
    P = _problem()
    floor = _cheapest_cost(P)
    for name in ("sensitivity", "equal", "proportional", "lagrange"):
        r = ALLOCATORS[name](P, budget=floor)
        np.testing.assert_allclose(r.t, P.upper, rtol=1e-9, err_msg=name)


def test_equal_tolerance_at_budget_matches_closed_form():
    """n identical costs a0·exp(-a1 t/σ) at one common t: n·a0·exp(-a1 t/σ) = B."""
    P = _problem(same_cost=True)
    n, a0, a1, sigma = P.n_sources, 2.0, 0.5, 1e-3
    budget = 4.0
    t_closed = sigma / a1 * np.log(n * a0 / budget)
    r = allocate_equal(P, budget=budget)
    np.testing.assert_allclose(r.t, t_closed, rtol=1e-9)


def test_lagrange_at_budget_satisfies_stationarity():
    """c_j'(t_j) / s_j is the same (= -λ) for every source strictly inside its bounds."""
    P = _problem()
    r = allocate_lagrange(P, budget=3.0 * _cheapest_cost(P))
    s = aggregated_sensitivity(P)
    inside = (r.t > P.lower * (1 + 1e-6)) & (r.t < P.upper * (1 - 1e-6))
    assert inside.sum() >= 3
    ratio = np.array([float(P.tolerances[n].cost.dcost(r.t[j])) / s[j] for j, n in enumerate(P.names)])[inside]
    np.testing.assert_allclose(ratio, ratio[0], rtol=1e-6)


def test_optimum_is_the_most_accurate_at_the_same_budget():
    P = _problem()
    budget = 3.0 * _cheapest_cost(P)
    err = lambda r: float(P.evaluate(r.t[None]).violation[0] + 1)  # noqa: E731 -- exact max error / bound
    opt = allocate_optimum(P, budget=budget)
    assert opt.info["normalised_error"] == pytest.approx(err(opt), rel=1e-12)
    for name in ("sensitivity", "equal", "proportional", "lagrange", "ga"):
        r = ALLOCATORS[name](P, budget=budget)
        assert err(r) >= err(opt) * (1 - 1e-6), name


def test_ga_budget_from_the_issue_is_an_error_not_a_feasible_overspend():
    """Issue 15: a budget of 1e-3 used to give a design costing far more, marked feasible."""
    P = _problem()
    with pytest.raises(ValidationError, match="cheapest design"):
        allocate_ga(P, budget=1e-3, **FAST_GA)
