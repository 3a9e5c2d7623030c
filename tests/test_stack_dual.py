"""The stack's optimum by a one-dimensional dual search (evotol.allocators.stack_dual, issue 43 item 4),
against references computed here: the water-filling closed form of the reciprocal cost (Boyd &
Vandenberghe 2004, Example 5.2, with c = a1·s/t: t_j ∝ 1/sqrt(|a_j|)), an independent SciPy SLSQP solve of
the same program written from the drawing (both sides of an asymmetric stack), and the KKT conditions at
5 000 dimensions checked from the cost formula by hand."""
from __future__ import annotations

import numpy as np
import pytest
from scipy.optimize import minimize

from evotol import LinearStack, Tolerance, assembly_problem
from evotol.allocators import allocate_optimum
from evotol.allocators.stack_allocation import stack_problem
from evotol.cost_models.exponential import ExponentialCost
from evotol.cost_models.power import PowerCost
from evotol.cost_models.reciprocal import ReciprocalCost
from evotol.measures.stack_model import Stack, StackDimension

L = 1e-4                                   # the gap's allowed deviation (m)


def _linear(a, cost, lo, hi, measure="worst_case"):
    stack = LinearStack({f"x{j}": float(v) for j, v in enumerate(a)}, {"gap": L})
    tol = {n: Tolerance(cost, lower=lo, upper=hi) for n in stack.source_names}
    return assembly_problem(stack, tol, measure)


def _slsqp(cost_fn, dcost_fn, cons, lo, hi, x0):
    """min Σ c(t) s.t. cons (each g(t) <= 1), lo <= t <= hi, in y = t / hi (SciPy SLSQP)."""
    c = [{"type": "ineq", "fun": lambda y, g=g: 1.0 - g(y * hi), "jac": lambda y, dg=dg: -dg(y * hi) * hi} for g, dg in cons]
    c0 = cost_fn(x0)
    r = minimize(lambda y: cost_fn(y * hi) / c0, x0 / hi, jac=lambda y: dcost_fn(y * hi) * hi / c0, method="SLSQP",
                 bounds=list(zip(lo / hi, np.ones_like(hi))), constraints=c, options={"ftol": 1e-16, "maxiter": 2000})
    return r.x * hi, cost_fn(r.x * hi)


def test_reciprocal_worst_case_equals_the_water_filling_closed_form_at_5000_dimensions():
    rng = np.random.default_rng(1)
    a = rng.choice([-1.0, 1.0], 5000) * rng.uniform(0.5, 2.0, 5000)
    s = 1e-5
    p = _linear(a, PowerCost(1.0, 1.0, scale=s), 1e-12, 1e-3)  # c = s/t; bounds far from the optimum
    r = allocate_optimum(p)
    # Σ|a_j| t_j = L with c'(t_j) = -s/t_j² = -λ|a_j|: t_j = sqrt(s/(λ|a_j|)), cost = (Σ sqrt(s|a_j|))² / L
    assert r.cost == pytest.approx(np.sum(np.sqrt(s * np.abs(a))) ** 2 / L, rel=1e-9)
    t_ref = L * np.sqrt(1 / np.abs(a)) / np.sum(np.sqrt(np.abs(a)))
    assert np.max(np.abs(r.t - t_ref) / t_ref) < 1e-9
    assert r.certificate["solver"].startswith("dual search")
    assert abs(r.certificate["gap"]) < 1e-12            # the dual bound meets the cost (rounding only)


@pytest.mark.parametrize("cost,measure", [(ReciprocalCost(1.0, 0.5, scale=1e-5), "worst_case"),
                                          (ExponentialCost(5.0, 0.2, scale=1e-5), "worst_case"),
                                          (PowerCost(2.0, 1.3, scale=1e-5), "rss"),
                                          (ExponentialCost(5.0, 0.2, scale=1e-5), "rss")])
@pytest.mark.parametrize("seed", [0, 1, 2])
def test_random_stacks_equal_an_independent_slsqp_solve(cost, measure, seed):
    rng = np.random.default_rng(seed)
    n = int(rng.integers(3, 51))
    a = rng.choice([-1.0, 1.0], n) * rng.uniform(0.2, 3.0, n)
    lo, hi = np.full(n, 2e-7), rng.uniform(2e-5, 1e-4, n)          # some tolerances end at their upper bound
    stack = LinearStack({f"x{j}": float(v) for j, v in enumerate(a)}, {"gap": L})
    p = assembly_problem(stack, {nm: Tolerance(cost, lower=2e-7, upper=float(hi[j]))
                                 for j, nm in enumerate(stack.source_names)}, measure)
    r = allocate_optimum(p)
    assert r.certificate["solver"].startswith("dual search")
    if measure == "worst_case":
        cons = [(lambda t: np.abs(a) @ t / L, lambda t: np.abs(a) / L)]
    else:
        cons = [(lambda t: (a ** 2) @ t ** 2 / L ** 2, lambda t: 2 * a ** 2 * t / L ** 2)]
    t_ref, c_ref = _slsqp(lambda t: float(np.sum(cost.cost(t))), cost.dcost, cons, lo, hi, np.sqrt(lo * hi))
    assert cons[0][0](t_ref) <= 1 + 1e-9
    assert r.cost == pytest.approx(c_ref, rel=1e-9)
    assert r.cost >= r.certificate["lower_bound"] * (1 - 1e-13) and r.certificate["gap"] < 1e-9     # rounding only


def test_asymmetric_stack_with_both_sides_active_equals_an_independent_solve():
    """One-sided zones and limits off the nominal gap: both worst-case sides bind (two multipliers)."""
    rng = np.random.default_rng(7)
    n = 12
    a = rng.choice([-1.0, 1.0], n) * rng.uniform(0.5, 2.0, n)
    minus = np.where(np.arange(n) % 3 == 0, 2.0, 1.0)            # +0/-2t (one-sided) or ±t, as drawn
    plus = np.where(np.arange(n) % 3 == 0, 0.0, 1.0)
    dims = tuple(StackDimension(f"d{j}", 0.01, plus[j] * 1e-5, -minus[j] * 1e-5, float(a[j])) for j in range(n))
    g0 = 0.01 * a.sum()
    lsl, usl = g0 - 1.1e-4, g0 + 0.9e-4
    st = Stack(dims, "gap", lsl, usl)
    cost = ReciprocalCost(1.0, 0.5, scale=1e-5)
    lo, hi = np.full(n, 1e-7), np.full(n, 1e-4)
    p = stack_problem(st, {d.name: cost for d in dims}, dict(zip(st.names, lo)), dict(zip(st.names, hi)))
    r = allocate_optimum(p)
    # the drawing: gap max = g0 + Σ max(a·plus·t, −a·minus·t) <= USL, gap min = g0 − Σ max(−a·plus·t, a·minus·t) >= LSL
    up = np.maximum(a * plus, -a * minus)
    down = np.maximum(-a * plus, a * minus)
    cons = [(lambda t: (g0 + up @ t - lsl) / (usl - lsl) * 2 - 1, lambda t: 2 * up / (usl - lsl)),
            (lambda t: (usl - g0 + down @ t) / (usl - lsl) * 2 - 1, lambda t: 2 * down / (usl - lsl))]
    t_ref, c_ref = _slsqp(lambda t: float(np.sum(cost.cost(t))), cost.dcost, cons, lo, hi, np.sqrt(lo * hi))
    assert r.cost == pytest.approx(c_ref, rel=1e-9)
    t = r.t[:n]
    assert g0 + up @ t == pytest.approx(usl, rel=1e-9) and g0 - down @ t == pytest.approx(lsl, rel=1e-9)
    assert r.certificate["active_rows"] == 2 and r.certificate["gap"] < 1e-9


def test_kkt_conditions_at_5000_dimensions_checked_by_hand():
    rng = np.random.default_rng(3)
    n = 5000
    a = rng.choice([-1.0, 1.0], n) * rng.uniform(0.5, 2.0, n)
    s, a0, a1 = 1e-5, 1.0, 0.5
    lo, hi = 1e-9, 1.8e-8                         # Σ|a|·t = L puts t near 1.6e-8: many tolerances at hi
    p = _linear(a, ReciprocalCost(a0, a1, scale=s), lo, hi)
    r = allocate_optimum(p)
    t = r.t
    g = np.abs(a) @ t / L
    assert g == pytest.approx(1.0, abs=1e-12)                        # the row is active
    dc = -a1 * s / t ** 2                                             # d/dt (a0 + a1 s / t)
    lam = -dc / (np.abs(a) / L)                                       # the multiplier each interior t implies
    inside = (t > lo * (1 + 1e-9)) & (t < hi * (1 - 1e-9))
    at_hi = t >= hi * (1 - 1e-9)
    assert inside.sum() > 100 and at_hi.sum() > 100
    lam0 = np.median(lam[inside])
    assert np.max(np.abs(lam[inside] - lam0)) / lam0 < 1e-8            # stationarity: one λ for every interior t
    assert np.all(lam[at_hi] >= lam0 * (1 - 1e-9))                    # at the upper bound: c' + λ|a|/L <= 0
    assert np.all(t >= lo) and np.all(t <= hi)
    assert r.cost == pytest.approx(float(np.sum(a0 + a1 * s / t)), rel=1e-12)


def test_quality_loss_optimum_inside_the_requirement_equals_each_sources_own_minimum():
    """A loss term q_j t² (Taguchi, evotol.core.quality_loss: q_j = A/9 (a_j/L)²) with a loose requirement:
    the row is inactive (λ = 0) and each tolerance minimises its own cost, found here by a bounded scalar
    search per source; every source has its own cost-model object (its own q_j)."""
    from scipy.optimize import minimize_scalar
    from evotol.core.quality_loss import with_quality_loss

    rng = np.random.default_rng(11)
    n, big = 20, 1e-2                                                # a 10 mm limit: the requirement does not bind
    a = rng.choice([-1.0, 1.0], n) * rng.uniform(0.5, 2.0, n)
    stack = LinearStack({f"x{j}": float(v) for j, v in enumerate(a)}, {"gap": big})
    cost = ReciprocalCost(1.0, 0.5, scale=1e-5)
    p = with_quality_loss(assembly_problem(stack, {nm: Tolerance(cost, lower=1e-7, upper=1e-3)
                                                   for nm in stack.source_names}), 50.0)
    r = allocate_optimum(p)
    assert r.certificate["solver"].startswith("dual search") and r.certificate["multipliers"] == [0.0]
    q = 50.0 / 9 * (a / big) ** 2
    own = [minimize_scalar(lambda t, qj=qj: 1.0 + 0.5e-5 / t + qj * t * t, bounds=(1e-7, 1e-3), method="bounded",
                           options={"xatol": 1e-16}) for qj in q]
    assert r.cost == pytest.approx(sum(o.fun for o in own), rel=1e-12)
    assert np.allclose(r.t, (0.5e-5 / (2 * q)) ** (1 / 3), rtol=1e-9)            # c' = 0: t³ = a1 s / (2 q)
    assert np.abs(a) @ r.t < big
