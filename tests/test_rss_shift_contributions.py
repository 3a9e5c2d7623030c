"""Contributions account for the side that binds (issue 34 item 4): under the rss measure with
asymmetric intervals the mean shift's norm is split among the sources that shift it, so a one-sided
tolerance gets its share and the shares sum to 1. Closed form for a linear stack gap = a − b + c."""
import numpy as np
import pytest

from evotol.cost_models.power import PowerCost
from evotol.core.problem import Requirement, Tolerance, ToleranceProblem
from evotol.robots.assembly import LinearStack


def test_rss_contributions_include_the_mean_shift():
    robot = LinearStack({"a": 1.0, "b": -1.0, "c": 1.0}, {"gap": 1e-4})
    cost = PowerCost(1.0, 1.0, scale=1e-3)
    tol = {"a": Tolerance(cost, 1e-6, 1e-3, minus=1.0, plus=0.0),       # +0/-40 µm: centre -20
           "b": Tolerance(cost, 1e-6, 1e-3, minus=0.4, plus=1.6),       # +32/-8 µm: centre +12, sensitivity -1
           "c": Tolerance(cost, 1e-6, 1e-3)}                            # ±25 µm
    p = ToleranceProblem(robot, tol, Requirement(position=1.0, measure="rss"), np.zeros((1, 1)))
    ev = p.evaluate(np.array([[40e-6, 20e-6, 25e-6]]))
    rss = np.sqrt(20.0 ** 2 + 20.0 ** 2 + 25.0 ** 2)                   # half-widths ρ t (µm)
    value = 32.0 + rss                                                  # |shift| = |-20 - 12| = 32 µm
    assert ev.position[0, 0] == pytest.approx(value / 100)            # normalised by the 100 µm limit
    want = [(20 + 400 / rss) / value, (12 + 400 / rss) / value, (625 / rss) / value]
    assert ev.position_contrib[0, 0] == pytest.approx(want, rel=1e-12)
    assert ev.position_contrib[0, 0].sum() == pytest.approx(1.0)
