"""Nonlinear worst case of assembly functions over the tolerance box (evotol/measures/nonlinear/interval.py,
evotol/measures/nonlinear/worst_case.py) and the allocation holding the nonlinear limit
(evotol/allocators/nonlinear_limit.py): enclosures against sampling and finite differences, the
proven bound against closed forms, the allocation against an independent vertex-constrained solve."""
import itertools

import numpy as np
import pytest
from scipy.optimize import minimize

from evotol.allocators import allocate_optimum
from evotol.allocators.nonlinear_limit import allocate_nonlinear_limit
from evotol.allocators.process import allocate_process_optimum
from evotol.errors import ValidationError
from evotol.measures.nonlinear.interval import Dual, Interval
from evotol.measures.nonlinear.worst_case import nonlinear_worst_case
from evotol.studies._process_benchmarks import clutch_angle, clutch_problem
from evotol.verification.nonlinear import verify_nonlinear
from evotol.robots.assembly import AssemblyFunction
from evotol.units import MM


def _mixed(a, b, c):
    return np.sqrt(a) * np.exp(-b) / (1.0 + c * c) + np.log(a + b) - np.sin(3 * c) * np.cos(b) + np.arctan(a - c)


@pytest.mark.parametrize("f, lo, hi", [
    (clutch_angle, [27.60e-3, 11.42e-3, 50.78e-3], [27.70e-3, 11.44e-3, 50.82e-3]),
    (_mixed, [0.5, -0.3, -1.0], [2.0, 0.4, 1.5]),
])
def test_interval_and_gradient_enclosures_contain_sampled_values(f, lo, hi):
    """Natural extension over sub-boxes holds every sampled value; the Dual gradient enclosure holds
    central-difference gradients at every sample (Moore 1966)."""
    rng = np.random.default_rng(0)
    lo, hi = np.array(lo), np.array(hi)
    edges = rng.uniform(lo, hi, size=(200, 2, 3))
    blo, bhi = edges.min(1), edges.max(1)
    I = f(*[Interval(blo[:, j], bhi[:, j]) for j in range(3)])
    D = f(*Dual.variables(blo, bhi))
    for _ in range(20):
        x = rng.uniform(blo, bhi)
        y = f(*x.T)
        assert np.all((I.lo <= y) & (y <= I.hi))
        h = 1e-7 * (hi - lo)
        for j in range(3):
            e = np.zeros(3)
            e[j] = h[j]
            g = (f(*(x + e).T) - f(*(x - e).T)) / (2 * h[j])
            tol = 1e-5 * (np.abs(g) + 1)
            assert np.all((D.grad.lo[:, j] - tol <= g) & (g <= D.grad.hi[:, j] + tol))
    assert np.allclose(D.val.lo, I.lo) and np.allclose(D.val.hi, I.hi)


def _powers(a, b, c):
    return a ** 0.5 + b ** -1.5 * np.power(c, 2.5) + (a * c) ** -2 + np.power(b, 3)


def test_fractional_and_negative_powers_are_enclosed_not_truncated():
    """``x ** 0.5`` is ``sqrt`` (a fractional exponent used to be cut to an integer: ``x ** 0.5``
    gave [1, 1] with a zero gradient, a wrong "proof"); negative and fractional exponents
    enclose sampled values and central-difference gradients; below 0 a fractional power has no
    bound (the whole line), as ``sqrt`` of a negative."""
    rng = np.random.default_rng(3)
    lo, hi = np.array([0.2, 0.5, 0.1]), np.array([3.0, 2.0, 1.5])
    edges = rng.uniform(lo, hi, size=(100, 2, 3))
    blo, bhi = edges.min(1), edges.max(1)
    I = _powers(*[Interval(blo[:, j], bhi[:, j]) for j in range(3)])
    D = _powers(*Dual.variables(blo, bhi))
    np.testing.assert_allclose(D.val.lo, I.lo, rtol=1e-12)
    for _ in range(20):
        x = rng.uniform(blo, bhi)
        y = _powers(*x.T)
        assert np.all((I.lo <= y) & (y <= I.hi))
        for j in range(3):
            e = np.zeros(3)
            e[j] = 1e-7
            g = (_powers(*(x + e).T) - _powers(*(x - e).T)) / 2e-7
            tol = 1e-5 * (np.abs(g) + 1)
            assert np.all((D.grad.lo[:, j] - tol <= g) & (g <= D.grad.hi[:, j] + tol))
    half = Interval(np.array([0.25]), np.array([4.0])) ** 0.5
    assert half.lo[0] == pytest.approx(0.5, rel=1e-15) and half.hi[0] == pytest.approx(2.0, rel=1e-15)
    assert half.lo[0] <= 0.5 <= 2.0 <= half.hi[0]
    d = Dual.variables(np.array([[4.0]]), np.array([[4.0]]))[0] ** 0.5
    assert d.val.lo[0] == pytest.approx(2.0) and d.grad.lo[0, 0] == pytest.approx(0.25)
    neg = Interval(np.array([-1.0]), np.array([4.0])) ** 0.5
    assert neg.lo[0] == -np.inf and neg.hi[0] == np.inf
    with pytest.raises(TypeError, match="real constant"):
        Interval(np.array([1.0]), np.array([2.0])) ** np.array([1.0, 2.0])


def test_clutch_worst_case_is_monotone_and_attained_at_a_vertex():
    """The Chase clutch's first-order worst-case optimum: proven monotone on its box, exact worst case
    1.2103 × the limit at a vertex (the 1.187 of 10⁵ uniform samples is below it), none of 2·10⁵
    samples above it; the linear stack says 1."""
    pp = clutch_problem("worst_case")
    r = allocate_process_optimum(pp)
    t = np.array([r.tolerances[n] for n in pp.names])
    wc = nonlinear_worst_case(pp.robot, t)
    resp = wc["responses"][0]
    assert resp["method"].startswith("monotone")
    assert resp["linear_over_limit"] == pytest.approx(1.0, abs=1e-7)
    V = np.array(list(itertools.product((-1, 1), repeat=3))) * t
    y0 = pp.robot.y0[0]
    L = pp.robot.limits[0]
    assert wc["max_over_limit"] == pytest.approx(np.max(np.abs(clutch_angle(*(pp.robot.x0 + V).T) - y0)) / L, rel=1e-12)
    assert wc["max_over_limit"] == pytest.approx(1.2103, abs=1e-4)
    S = pp.robot.x0 + np.random.default_rng(1).uniform(-t, t, size=(200_000, 3))
    assert np.max(np.abs(clutch_angle(*S.T) - y0)) / L <= wc["max_over_limit"]


def test_branch_and_bound_bound_of_a_non_monotone_response():
    """y = cos(a)·b at a = 0 (not monotone in a): max |y − 1| over a ∈ ±0.2, b ∈ 1 ± 0.01 is
    1 − 0.99 cos 0.2 (closed form); the proven bound is within 1e-6 × L of it and not below."""
    asm = AssemblyFunction(lambda a, b: np.cos(a) * b, {"a": 0.0, "b": 1.0}, {"y": 0.01})
    wc = nonlinear_worst_case(asm, [0.2, 0.01], rtol=1e-6)
    exact = (1 - 0.99 * np.cos(0.2)) / 0.01
    r = wc["responses"][0]
    assert r["method"].startswith("branch and bound")
    assert exact * (1 - 1e-12) <= r["proven_bound_over_limit"] <= exact + 2e-6
    assert r["attained_over_limit"] == pytest.approx(exact, rel=1e-12)


def _vertex_constrained_optimum(pp):
    """Independent: per process combination, SLSQP (variables in mm) on the cost subject to
    |φ(vertex) − φ0| <= L at all 8 vertices (exact for a monotone response)."""
    asm = pp.robot
    V = np.array(list(itertools.product((-1, 1), repeat=3)), float)
    best = np.inf
    for ch in itertools.product(*[range(k) for k in pp.n_processes]):
        P = [pp.processes[n][k] for n, k in zip(pp.names, ch)]
        lo, hi = np.array([p.lower for p in P]) / MM, np.array([p.upper for p in P]) / MM

        def g(u):       # outside arccos's domain (NaN) the vertex is infeasible: -1
            with np.errstate(invalid="ignore"):
                return np.nan_to_num(1 - np.abs(clutch_angle(*(asm.x0 + V * u * MM).T) - asm.y0[0]) / asm.limits[0],
                                     nan=-1.0)

        def f(u):
            return sum(float(p.total(x * MM)) for p, x in zip(P, u))

        if np.min(g(lo)) < 0:
            continue
        for w in (0.0, 0.05, 0.2, 0.5):
            with np.errstate(all="ignore"):
                r = minimize(f, lo + w * (hi - lo), method="SLSQP", bounds=list(zip(lo, hi)),
                             constraints=[{"type": "ineq", "fun": g}], options={"ftol": 1e-15, "maxiter": 1000})
            if np.min(g(r.x)) >= -1e-9:
                best = min(best, f(r.x))
    return best


def test_allocation_holding_the_nonlinear_limit_matches_an_independent_solve():
    """Chase clutch, worst case: re-linearising at the worst point converges to the cheapest design whose
    nonlinear worst case holds (12.65238 against the independent vertex-constrained solve, 1e-6), at
    +4.35 % over the first-order optimum; Monte Carlo stays inside."""
    pp = clutch_problem("worst_case")
    r = allocate_nonlinear_limit(pp, allocate_process_optimum)
    assert r.converged
    assert r.linear_worst_case["max_over_limit"] > 1.2
    assert 1 - 1e-6 <= r.worst_case["max_over_limit"] <= 1 + 1e-9
    ref = _vertex_constrained_optimum(pp)
    assert r.result.cost == pytest.approx(ref, rel=1e-6)
    assert r.cost_difference / r.linear.cost == pytest.approx(0.0435, abs=5e-4)
    # Monte Carlo through the nonlinear angle (uniform in ±t) on the chosen processes' problem
    mc = verify_nonlinear(pp.subproblem(pp.choice_index(r.result.processes)), r.result.tolerances, n_samples=50_000)
    assert mc.mc_exceed_rate["position"] == 0 and mc.mc_max["position"] <= 1


def test_nonlinear_limit_on_a_tolerance_problem_and_bad_input():
    """Without process choice (allocate_optimum) the same holds; an RSS problem is refused."""
    from evotol.allocators.process import assembly_problem
    from evotol.core.problem import Tolerance
    from evotol.cost_models import ReciprocalCost

    pp = clutch_problem("worst_case")
    tol = {n: Tolerance(ReciprocalCost(2.0, 0.12, scale=MM), 2e-6, 1.5e-4) for n in pp.names}
    tp = assembly_problem(pp.robot, tol, "worst_case")
    r = allocate_nonlinear_limit(tp, allocate_optimum)
    assert r.converged and r.worst_case["max_over_limit"] <= 1 + 1e-9
    assert r.result.cost > r.linear.cost
    with pytest.raises(ValidationError, match="requirement.measure"):
        allocate_nonlinear_limit(assembly_problem(pp.robot, tol, "rss"), allocate_optimum)
    with pytest.raises(ValidationError, match="tolerances"):
        nonlinear_worst_case(pp.robot, [1e-5, -1e-5, 1e-5])


@pytest.mark.parametrize("max_boxes", [0, -5, 2.5, "many", True, None])
def test_nonlinear_worst_case_refuses_a_max_boxes_that_is_not_a_positive_integer(max_boxes):
    """``max_boxes`` <= 0 (which used to stop branch and bound before any point was evaluated and
    fail with KeyError: 'point'), a non-integer float, text, a bool or None: a one-line
    ValidationError naming ``max_boxes`` and the value. One box is enough to get the proven bound
    (>= the closed form 1 - 0.99 cos 0.2, over L = 0.01) with 2 boxes explored."""
    asm = AssemblyFunction(lambda a, b: np.cos(a) * b, {"a": 0.0, "b": 1.0}, {"y": 0.01})
    with pytest.raises(ValidationError) as exc:
        nonlinear_worst_case(asm, [0.2, 0.01], max_boxes=max_boxes)
    assert exc.value.field == "max_boxes" and exc.value.value == max_boxes
    assert str(exc.value) == f"max_boxes = {max_boxes!r}: expected a positive integer"
    r = nonlinear_worst_case(asm, [0.2, 0.01], max_boxes=1)["responses"][0]
    assert r["n_boxes"] == 2
    assert r["proven_bound_over_limit"] >= (1 - 0.99 * np.cos(0.2)) / 0.01 * (1 - 1e-12)


@pytest.mark.parametrize("rtol", [-1e-3, float("nan"), float("inf"), "tight", True, None])
def test_nonlinear_worst_case_refuses_an_rtol_that_is_not_a_finite_non_negative_number(rtol):
    """A negative or NaN ``rtol`` never satisfies the stopping test, so branch and bound ran its
    whole box budget (200 000 boxes) before answering; text or None failed inside the loop. Each is
    refused first in one line naming ``rtol``; rtol = 0 is allowed (stop at the budget or exactly)."""
    asm = AssemblyFunction(lambda a, b: np.cos(a) * b, {"a": 0.0, "b": 1.0}, {"y": 0.01})
    with pytest.raises(ValidationError) as exc:
        nonlinear_worst_case(asm, [0.2, 0.01], rtol=rtol)
    assert str(exc.value) == f"rtol = {rtol!r}: expected a finite non-negative tolerance relative to the limit"
    r = nonlinear_worst_case(asm, [0.2, 0.01], rtol=0, max_boxes=50)["responses"][0]
    assert r["proven_bound_over_limit"] >= (1 - 0.99 * np.cos(0.2)) / 0.01 * (1 - 1e-12)
