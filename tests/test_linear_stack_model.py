"""One linear-stack model (issue 39 item 5): the stack analysis (evotol.measures.stack_analysis) and the
allocation's robot (evotol.robots.assembly.LinearStack, built by Stack.linear_stack) take their worst case
and RSS from the same two functions (evotol.robots.assembly.linear_stack), checked here against an
enumeration of every corner of the tolerance box and against the problem's own measures, which the
allocation is judged by."""
from __future__ import annotations

import itertools

import numpy as np
import pytest

from evotol import LinearStack
from evotol.allocators.stack_allocation import stack_problem
from evotol.cost_models.reciprocal import ReciprocalCost
from evotol.errors import ValidationError
from evotol.measures.stack_analysis import rss_half_width, worst_case
from evotol.measures.stack_model import Stack, StackDimension
from evotol.robots.assembly import linear_stack as ls


def _stack(seed, n=10, limits=(-0.2, 0.3)):
    rng = np.random.default_rng(seed)
    a = rng.choice([-1.0, 1.0], n) * rng.uniform(0.5, 2.0, n)
    lower = -rng.uniform(0.0, 0.05, n)
    upper = rng.uniform(0.0, 0.05, n) * (np.arange(n) % 4 != 0)         # every fourth zone one-sided +0/-l
    dims = tuple(StackDimension(f"d{j}", float(rng.uniform(1, 5)), float(upper[j]), float(lower[j]), float(a[j]))
                 for j in range(n))
    return Stack(dims, "gap", *limits), a, lower, upper


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_worst_case_equals_every_corner_of_the_box(seed):
    st, a, lower, upper = _stack(seed)
    corners = np.array(list(itertools.product(*zip(lower, upper))))      # all 2^10 corners of the deviations
    dev = corners @ a
    below, above = ls.worst_case_deviation(a, lower, upper)
    assert below == pytest.approx(dev.min(), rel=1e-13) and above == pytest.approx(dev.max(), rel=1e-13)
    g0 = sum(d.sensitivity * d.nominal for d in st.dimensions)
    lo, hi = worst_case(st)                                               # the analysis
    assert lo == pytest.approx(g0 + dev.min(), rel=1e-13) and hi == pytest.approx(g0 + dev.max(), rel=1e-13)
    robot = st.linear_stack()                                             # the model an allocation works on
    rb, ra = robot.worst_case(lower, upper)
    assert rb[0] == pytest.approx(dev.min(), rel=1e-13) and ra[0] == pytest.approx(dev.max(), rel=1e-13)


@pytest.mark.parametrize("seed", [0, 1])
def test_the_allocation_judges_the_drawn_stack_as_the_analysis_does(seed):
    """Worst case: the problem's measure (the allocation's verdict) at the drawn zones equals the analysis's
    limits against [LSL, USL]; RSS of centred zones: the problem's rss measure equals T_rss of the analysis."""
    st, a, lower, upper = _stack(seed, limits=(-30.0, 30.0))
    g0 = float(a @ np.array([d.nominal for d in st.dimensions]))
    st = Stack(st.dimensions, "gap", g0 - 0.2, g0 + 0.3)                    # limits off the nominal gap
    h = 0.5 * (upper - lower)
    cost = ReciprocalCost(1.0, 0.5, scale=1e-3)
    names = st.names
    p = stack_problem(st, {n: cost for n in names}, {n: 1e-4 for n in names}, {n: 1.0 for n in names})
    t = p.as_array({**dict(zip(names, h)), **{n: p.tolerances[n].locked for n in p.names if n not in names}})
    lo, hi = worst_case(st)
    centre, half = 0.5 * (st.lower_limit + st.upper_limit), 0.5 * (st.upper_limit - st.lower_limit)
    assert float(p.evaluate(t[None]).position.max()) == pytest.approx(max(hi - centre, centre - lo) / half, rel=1e-9)
    sym = Stack(tuple(StackDimension(d.name, d.nominal, float(x), -float(x), d.sensitivity) for d, x in zip(st.dimensions, h)),
                "gap", g0 - 0.25, g0 + 0.25)
    pr = stack_problem(sym, {n: cost for n in names}, {n: 1e-4 for n in names}, {n: 1.0 for n in names}, measure="rss")
    assert float(pr.evaluate(h[None]).position.max()) * 0.25 == pytest.approx(rss_half_width(sym), rel=1e-12)
    assert float(sym.linear_stack().rss(h)[0]) == pytest.approx(float(np.sqrt(np.sum((a * h) ** 2))), rel=1e-14)


def test_linear_stack_takes_its_sensitivities_as_given():
    """No differentiation: the robot's sensitivity row is a_j / L exactly, at any size."""
    a = np.linspace(-2.0, 2.0, 4001)
    a[a == 0] = 0.5
    robot = LinearStack({f"x{j}": float(v) for j, v in enumerate(a)}, {"gap": 1e-4})
    assert np.array_equal(robot.sensitivity([[0]])[0, 2], a / 1e-4)
    assert np.array_equal(robot.jacobian(np.ones(a.size))[0, 0], a)


def test_linear_stack_of_a_stack_without_limits_is_refused_naming_the_limit():
    st = Stack((StackDimension("A", 1.0, 0.1, -0.1),), "gap", lower_limit=0.0)
    with pytest.raises(ValidationError, match="upper_limit"):
        st.linear_stack()
    assert st.linear_stack(0.5).limits[0] == 0.5
