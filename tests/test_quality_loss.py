"""Taguchi quality loss as a cost term (evotol/core/quality_loss.py, cost_models/quality_loss.py):
the first-order expected loss against Monte Carlo, and allocators minimising machining + loss
against brute force."""
import numpy as np
import pytest

from evotol.cost_models import PowerCost
from evotol.cost_models.quality_loss import QualityLossCost
from evotol.allocators import allocate_ga, allocate_optimum
from evotol.allocators.process import assembly_problem
from evotol.errors import ValidationError
from evotol.core.problem import Requirement, Tolerance, ToleranceProblem
from evotol.core.quality_loss import expected_loss, loss_coefficients, with_quality_loss
from evotol.robots.assembly import LinearStack
from evotol.units import MM
from tests.toy_robot import ToyRobot


def _stack_problem(measure="rss"):
    stack = LinearStack({"a": 1.0, "b": -2.0, "c": 0.5}, {"gap": 0.2 * MM})
    tol = {n: Tolerance(PowerCost(0.1, 1.0, scale=MM), 0.005 * MM, 0.3 * MM) for n in "abc"}
    return stack, assembly_problem(stack, tol, measure)


def test_expected_loss_of_a_linear_stack_equals_monte_carlo():
    """K E[(Y − Y0)²] with Y = Σ a_j x_j, x_j ~ N(0, (t_j/3)²): the formula against 4·10⁵ samples (1 %)."""
    stack, tp = _stack_problem()
    A, L = 7.0, 0.2 * MM
    t = np.array([0.05, 0.02, 0.1]) * MM
    rng = np.random.default_rng(1)
    dx = rng.normal(0.0, t / 3, size=(400_000, 3))
    dy = dx @ np.array([1.0, -2.0, 0.5])
    mc = A / L ** 2 * np.mean(dy ** 2)
    assert expected_loss(tp, A, t)[0] == pytest.approx(mc, rel=0.01)
    # closed form: (A/L²) Σ a_j² t_j² / 9
    closed = A / L ** 2 * np.sum((np.array([1.0, -2.0, 0.5]) * t) ** 2) / 9
    assert expected_loss(tp, A, t)[0] == pytest.approx(closed, rel=1e-12)
    # per-response coefficients: {"gap": A} is the same as A
    assert np.allclose(loss_coefficients(tp, {"gap": A}), loss_coefficients(tp, A))


def test_robot_loss_is_the_mean_over_poses_of_the_position_error_squared():
    """Robot convention: responses are the x, y, z position errors, mean over poses, K = A / L²;
    Monte Carlo over normal sources (each component of a multi-dimensional source σ = t/3)."""
    robot = ToyRobot(dims=(1, 2, 1), seed=3)
    poses = np.linspace(0, 1, 5)[:, None]
    tol = {s.name: Tolerance(PowerCost(1.0, 1.0, scale=1e-5), 1e-6, 1e-3) for s in robot.sources}
    tp = ToleranceProblem(robot, tol, Requirement(position=1e-4), poses)
    t = np.array([2e-5, 1e-5, 3e-5])
    A, L = 3.0, 1e-4
    rng = np.random.default_rng(0)
    sig = np.repeat(t, [1, 2, 1]) / 3
    E = rng.normal(0.0, sig, size=(200_000, 4))
    J = robot.sensitivity(poses)[:, 0:3, :]                  # (poses, 3, columns)
    dp = np.einsum("pcj,nj->pnc", J, E)
    mc = A / L ** 2 * np.mean(np.sum(dp ** 2, axis=2))
    assert expected_loss(tp, A, t)[0] == pytest.approx(mc, rel=0.01)


def test_optimum_with_loss_equals_a_brute_force_grid():
    """min Σ b/t_j + q_j t_j² s.t. RSS <= L on a 3-D log grid (120³, refined): allocate_optimum agrees to 1e-4,
    and the loss moves the optimum inside the limit when it is large (A = 50)."""
    _, tp = _stack_problem()
    for A in (0.5, 50.0):
        lp = with_quality_loss(tp, A)
        r = allocate_optimum(lp)
        q = loss_coefficients(tp, A)
        g = [np.geomspace(0.005 * MM, 0.3 * MM, 120)] * 3
        for _ in range(2):                               # a coarse grid, then a fine one around its best point
            T = np.stack(np.meshgrid(*g, indexing="ij"), -1).reshape(-1, 3)
            rss = np.sqrt(np.sum((T * np.array([1.0, 2.0, 0.5])) ** 2, 1))
            c = np.where(rss <= 0.2 * MM, np.sum(0.1 * MM / T + q * T ** 2, 1), np.inf)
            i = int(np.argmin(c))
            best = float(c[i])
            g = [np.clip(np.geomspace(x / 1.08, x * 1.08, 80), 0.005 * MM, 0.3 * MM) for x in T[i]]
        assert r.cost <= best * (1 + 1e-9)
        assert r.cost >= best * (1 - 1e-4)
        assert r.certificate["gap"] < 1e-6
    r50 = allocate_optimum(with_quality_loss(tp, 50.0))
    assert tp.evaluate(r50.t[None]).violation[0] + 1 < 0.99        # limit inactive: the loss decides


def test_ga_with_loss_is_not_pushed_onto_the_limit():
    _, tp = _stack_problem()
    lp = with_quality_loss(tp, 50.0)
    opt = allocate_optimum(lp)
    ga = allocate_ga(lp, pop_size=40, n_gen=60, seed=0)
    assert ga.feasible
    assert opt.cost * (1 - 1e-9) <= ga.cost <= opt.cost * 1.01


def test_quality_loss_cost_derivatives_and_bad_input():
    m = QualityLossCost(PowerCost(0.1, 1.0, scale=MM), 4e6)
    t = np.array([0.01, 0.1]) * MM
    h = 1e-9 * MM
    assert np.allclose(m.dcost(t), (m.cost(t + h) - m.cost(t - h)) / (2 * h), rtol=1e-6)
    assert m.is_convex(0.005 * MM, 0.3 * MM)
    with pytest.raises(ValidationError, match="QualityLossCost q"):
        QualityLossCost(PowerCost(0.1, 1.0, scale=MM), -1.0)
    _, tp = _stack_problem()
    with pytest.raises(ValidationError, match="quality_loss"):
        loss_coefficients(tp, {"nope": 1.0})
    with pytest.raises(ValidationError, match="quality_loss"):
        loss_coefficients(tp, float("nan"))


def test_budget_mode_refuses_a_quality_loss_problem():
    """Best accuracy at a budget assumes cost falls with t (cheapest design = upper bounds); with a loss
    term it does not, so every allocator's budget mode refuses it by name."""
    from evotol.allocators import allocate_lagrange

    _, tp = _stack_problem()
    lp = with_quality_loss(tp, 5.0)
    for fn in (allocate_optimum, allocate_lagrange):
        with pytest.raises(ValidationError, match="budget"):
            fn(lp, budget=100.0)


def test_one_entry_point_for_tolerance_and_process_problems():
    """``with_quality_loss(problem, A)`` is the one entry point (issue 32 item 5): on a process
    problem it gives what ``pp.with_quality_loss(A)`` gives (same coefficients q_j as on the plain
    problem of the same geometry, every process's cost wrapped); another kind of problem, or a
    second loss on a process problem, is refused in one line."""
    from evotol.allocators.process import Process, ProcessProblem, allocate_process_optimum

    stack, tp = _stack_problem()
    procs = {n: [Process("fine", PowerCost(0.2, 1.0, scale=MM), 0.005 * MM, 0.05 * MM),
                 Process("rough", PowerCost(0.1, 1.0, scale=MM), 0.04 * MM, 0.3 * MM)] for n in "abc"}
    pp = ProcessProblem(stack, procs, tp.requirement, tp.poses)
    a, b = with_quality_loss(pp, 50.0), pp.with_quality_loss(50.0)
    assert isinstance(a, ProcessProblem) and a.quality_loss_A == b.quality_loss_A == 50.0
    np.testing.assert_array_equal(a.loss_coefficients, loss_coefficients(tp, 50.0))
    np.testing.assert_array_equal(a.loss_coefficients, b.loss_coefficients)
    assert all(isinstance(p.cost, QualityLossCost) and p.cost.q == q
               for n, q in zip(a.names, a.loss_coefficients) for p in a.processes[n])
    assert allocate_process_optimum(a).cost == allocate_process_optimum(b).cost
    t = np.array([0.05, 0.02, 0.1]) * MM
    assert a.quality_loss(t)[0] == pytest.approx(expected_loss(tp, 50.0, t)[0], rel=1e-12)
    with pytest.raises(ValidationError, match="a problem without a loss term"):
        with_quality_loss(a, 1.0)
    with pytest.raises(ValidationError, match="^problem = 'LinearStack'"):
        with_quality_loss(stack, 1.0)
