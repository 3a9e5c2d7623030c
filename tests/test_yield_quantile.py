"""The yield column is the error at the required yield (issue 33 item 6): evotol/summaries/yield_quantile.py.

Checked against independent sampling of the first-order model with the stated distributions (a
different seed and 400 000 samples): with normal sources (t = 3σ) the exact bisection lies within
the sampled quantile's 95 % order-statistic interval; with uniform sources the Monte Carlo value
does too. The yield measure's own per-pose error (E·k_req/k(q)) is not that quantile off the
requirement -- the reason for the column change.
"""
from __future__ import annotations

import evotol.cost_models
import numpy as np
import pytest
from scipy.stats import binom

from evotol.measures.statistical.distributions import Distribution
from evotol.core.problem import Requirement, Tolerance, ToleranceProblem
from evotol.summaries.yield_quantile import largest_quantile
from evotol.robots.mechanism.model.joint_space import joint_configurations
from evotol.robots.mechanism.model.error_model import MechanismModel
from tests.test_standard_dh import PUMA

SOURCES = ["a2", "a3", "d3", "d4", "theta2", "theta3"]
CONFIGS = [[10, 10, -100, -20, 30, -60], [0, 45, 180, 0, 45, 0], [-30, 20, 150, 45, 60, 10]]


def problem_with(dist: str):
    jm, Q = joint_configurations(MechanismModel(PUMA, sources=SOURCES), [[f"{v}*deg" for v in c] for c in CONFIGS])
    cost = evotol.cost_models.from_dict({"model": "exponential", "a0": 1.9, "a1": 0.5, "scale": 1e-5})
    tol = {n: Tolerance(cost=cost, lower=1e-6, upper=1e-3,
                        distribution=Distribution(dist, 3.0)) for n in SOURCES}
    return ToleranceProblem(jm, tol, Requirement(position=2e-4, measure="yield", probability=0.9973), Q), jm, Q


def sampled_quantile(jm, Q, t, dist, p, n=400_000, seed=11):
    rng = np.random.default_rng(seed)
    e = (rng.normal(0, 1 / 3, (n, len(t))) if dist == "normal" else rng.uniform(-1, 1, (n, len(t)))) * t
    norms = np.sort(np.linalg.norm(np.einsum("pik,sk->psi", jm.sensitivity(Q)[:, :3], e), axis=2), axis=1)
    k, lo, hi = int(np.ceil(p * n)) - 1, int(binom.ppf(0.025, n, p)) - 1, int(binom.ppf(0.975, n, p))
    i = int(np.argmax(norms[:, k]))
    return norms[i, k], norms[i, lo], norms[i, hi]


@pytest.mark.parametrize("dist", ["normal", "uniform"])
def test_largest_quantile_matches_independent_sampling(dist):
    problem, jm, Q = problem_with(dist)
    t = np.array([1e-4, 6e-5, 8e-5, 1e-4, 1.5e-4, 1e-4])
    q = largest_quantile(problem, t, 0.9973)
    assert q["method"] == ("exact (normal sources)" if dist == "normal" else "Monte Carlo")
    value, lo, hi = sampled_quantile(jm, Q, t, dist, 0.9973)
    assert lo * (1 - 1e-3) <= q["position"]["value"] <= hi * (1 + 1e-3), (q["position"], value)
    if dist == "normal":
        # the measure's own error E·k_req/k(q) is not the quantile when the design is off the requirement
        ev = problem.evaluate(t[None])
        assert abs(float(np.max(ev.position[0])) - q["position"]["value"]) > 1e-3 * q["position"]["value"]
