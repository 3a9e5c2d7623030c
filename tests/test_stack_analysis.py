"""Stack analysis (evotol.measures.stack_analysis) against closed forms, brute force, sampling and
the Dimensioning & Tolerancing Handbook's motor assembly (Drake 1999 ch. 9; inputs
shared/data/motor_assembly_handbook.json, as coded in phcreery/dimstack tests/test_McGrawHill.py).
"""
from __future__ import annotations

import itertools
import json
from pathlib import Path

import numpy as np
import pytest
from scipy import stats

from evotol.errors import ValidationError
from evotol.measures.stack_analysis import (Stack, StackDimension, StackModel, analyse_stack, capability,
                                            contributions, fraction_outside, gap_moments, mrss_factor,
                                            rss_half_width, sample_gap, worst_case)

DATA = Path(__file__).resolve().parents[1] / "evotol" / "studies" / "data" / "motor_assembly_handbook.json"


def motor(lower=0.0, upper=0.12, distribution="normal") -> Stack:
    d = json.loads(DATA.read_text())
    return Stack(tuple(StackDimension(x["name"], x["nominal"], x["plus"], -x["minus"], x["direction"], distribution,
                                      x.get("same_part_as")) for x in d["dimensions"]), "gap", lower, upper, "in")


def random_stack(n=6, seed=1, distribution="normal", limits=(-0.05, 0.08)) -> Stack:
    rng = np.random.default_rng(seed)
    dims = []
    for i in range(n):
        lo, up = sorted(rng.uniform(-0.02, 0.02, 2))
        if i == 0:
            lo, up = -0.03, 0.0                            # one-sided
        dims.append(StackDimension(f"x{i}", float(rng.uniform(1, 5)), float(up), float(lo),
                                   float(rng.choice([-1.0, 1.0]) * rng.uniform(0.5, 2)), distribution))
    return Stack(tuple(dims), "g", *limits, "mm")


def corner_gaps(stack: Stack) -> np.ndarray:
    a, n, _, _ = stack.arrays()
    ends = [(d.nominal + d.lower, d.nominal + d.upper) for d in stack.dimensions]
    return np.array([a @ np.array(c) for c in itertools.product(*ends)])


@pytest.mark.parametrize("stack", [motor(), random_stack()], ids=["motor", "random"])
def test_worst_case_is_the_extreme_corner(stack):
    """Worst case μ ± Σ|a|h equals the extremes over every corner of the tolerance box (brute force)."""
    g = corner_gaps(stack)
    lo, hi = worst_case(stack)
    assert lo == pytest.approx(g.min(), abs=1e-12) and hi == pytest.approx(g.max(), abs=1e-12)


def test_motor_assembly_matches_the_handbook():
    """Drake ch. 9 motor assembly: worst case −0.034/+0.157, RSS 0.0234/0.0996 (±0.0381), MRSS
    ±0.0505 → 0.0110/0.1120, mean gap 0.0615 (in; the figures the dimstack test suite quotes)."""
    r = analyse_stack(motor()).to_dict()
    assert round(r["mean"], 4) == 0.0615 and round(r["nominal"], 4) == 0.064
    assert [round(v, 3) for v in r["worst_case"]["limits"]] == [-0.034, 0.157]
    assert round(r["worst_case"]["half_width"], 4) == 0.0955
    assert round(r["rss"]["half_width"], 4) == 0.0381
    assert [round(v, 4) for v in r["rss"]["limits"]] == [0.0234, 0.0996]
    assert round(r["mrss"]["half_width"], 4) == 0.0505
    assert [round(v, 4) for v in r["mrss"]["limits"]] == [0.0110, 0.1120]


def test_mrss_factor_closed_form():
    """C_f = 1 + 0.5 (T_wc − T_rss)/(T_rss(√n − 1)). Equal tolerances (T_wc = n h, T_rss = √n h)
    give Bender's 1.5 for every n; one dimension gives 1; the motor's by hand 1.3255."""
    for n in (2, 4, 9):
        s = Stack(tuple(StackDimension(f"d{i}", 1.0, 0.1, -0.1) for i in range(n)))
        assert mrss_factor(s) == pytest.approx(1.5)
    h = np.array([0.0155, 0.002, 0.003, 0.0075, 0.005, 0.007, 0.005, 0.0075, 0.007, 0.006, 0.03])
    t_rss = np.sqrt(np.sum(h ** 2))
    assert mrss_factor(motor()) == pytest.approx(1 + 0.5 * (h.sum() - t_rss) / (t_rss * (np.sqrt(11) - 1)))
    assert mrss_factor(Stack((StackDimension("d", 1.0, 0.1, -0.1),))) == 1.0


def test_rss_is_three_sigma_of_sampled_normal_gap():
    """RSS half-width = 3σ of the gap when every tolerance is ±3σ: sampled σ within 1 %."""
    s = random_stack()
    g = sample_gap(s, StackModel(), 400_000, seed=3)
    assert np.std(g) * 3 == pytest.approx(rss_half_width(s), rel=0.01)
    assert np.mean(g) == pytest.approx(gap_moments(s)["mean"], abs=0.002 * rss_half_width(s))


def test_exact_fraction_agrees_with_sampling():
    """The exact normal fractions lie in the Clopper–Pearson interval of a sampled normal gap."""
    s = random_stack(limits=(None, None))
    mo = gap_moments(s)
    s = Stack(s.dimensions, "g", mo["mean"] - 2.2 * mo["sigma"], mo["mean"] + 2.5 * mo["sigma"], "mm")
    ex = fraction_outside(s)
    assert ex["method"] == "exact normal"
    assert ex["below"] == pytest.approx(stats.norm.cdf(-2.2)) and ex["above"] == pytest.approx(stats.norm.sf(2.5))
    g = sample_gap(s, StackModel(), 400_000, seed=5)
    for side, k in (("below", np.sum(g < s.lower_limit)), ("above", np.sum(g > s.upper_limit))):
        ci = stats.binomtest(int(k), g.size).proportion_ci(0.999, method="exact")
        assert ci.low <= ex[side] <= ci.high


def test_monte_carlo_interval_covers_the_uniform_closed_form():
    """Two uniforms on [−1, 1]: P(g > 1.5) = 0.5²/8 = 1/32, P(g < −1) = 1/8 (triangular
    distribution); the Clopper–Pearson interval of the Monte Carlo covers both."""
    s = Stack((StackDimension("a", 0.0, 1.0, -1.0, 1.0, "uniform"), StackDimension("b", 0.0, 1.0, -1.0, 1.0, "uniform")),
              "g", -1.0, 1.5)
    r = fraction_outside(s, n_samples=200_000, seed=2, confidence=0.999)
    assert r["method"] == "Monte Carlo"
    assert r["above_interval"][0] <= 1 / 32 <= r["above_interval"][1]
    assert r["below_interval"][0] <= 1 / 8 <= r["below_interval"][1]


def test_static_shift_is_the_worst_direction_per_limit():
    """Static mean shift: above-USL fraction = that of a sample whose every mean is moved by k·h
    toward USL (sign of a), below-LSL toward LSL; checked by sampling shifted normal inputs."""
    s = random_stack(limits=(None, None))
    mo = StackModel(cp=1.5, k=0.3, shift_model="static")
    g0 = gap_moments(s, mo)
    s = Stack(s.dimensions, "g", g0["mean"] - 5 * g0["sigma"], g0["mean"] + 4 * g0["sigma"], "mm")
    r = fraction_outside(s, mo)
    a, _, m, h = s.arrays()
    rng = np.random.default_rng(7)
    x = m + rng.normal(0, 1, (400_000, a.size)) * h / (3 * mo.cp)
    up = (x + np.sign(a) * mo.k * h) @ a
    down = (x - np.sign(a) * mo.k * h) @ a
    for side, k in (("above", np.sum(up > s.upper_limit)), ("below", np.sum(down < s.lower_limit))):
        ci = stats.binomtest(int(k), up.size).proportion_ci(0.999, method="exact")
        assert ci.low <= r[side] <= ci.high


def test_dynamic_shift_inflates_sigma_and_cpk():
    """Dynamic RSS: σ_eff = h/(3 Cp (1−k)); Cpk = min(USL − μ, μ − LSL)/(3σ), Cp = (USL−LSL)/(6σ)."""
    s = motor()
    a, _, m, h = s.arrays()
    mo = StackModel(cp=2.0, k=0.25)
    sig = np.sqrt(np.sum((a * h / (3 * 2.0 * 0.75)) ** 2))
    r = analyse_stack(s, {"six sigma": mo}).to_dict()["models"]["six sigma"]
    assert r["sigma"] == pytest.approx(sig)
    mu = a @ m
    assert r["cp"] == pytest.approx(0.12 / (6 * sig))
    assert r["cpk"] == pytest.approx(min(0.12 - mu, mu) / (3 * sig))
    assert r["outside"]["above"] == pytest.approx(stats.norm.sf(3 * r["cpu"]))


def test_capability_one_sided_limit():
    """With only LSL, Cp is undefined and Cpk = Cpl."""
    c = capability(1.0, 0.1, 0.4, None)
    assert c["cp"] is None and c["cpk"] == pytest.approx(2.0) and c["cpu"] is None


def test_contributions_account_for_the_side_that_binds():
    """A +0/−0.031 dimension with direction −1 adds 0 below and 0.031 above; each side sums to
    the worst-case deviation from the nominal gap."""
    s = motor()
    c = {x["name"]: x for x in contributions(s)}
    assert c["A"]["below"] == 0.0 and c["A"]["above"] == pytest.approx(0.031)
    assert c["J"]["above"] == 0.0 and c["J"]["below"] == pytest.approx(-0.012)
    lo, hi = worst_case(s)
    g0 = analyse_stack(s).to_dict()["nominal"]
    assert sum(x["below"] for x in c.values()) == pytest.approx(lo - g0)
    assert sum(x["above"] for x in c.values()) == pytest.approx(hi - g0)
    assert sum(x["below_percent"] for x in c.values()) == pytest.approx(100)


def test_bad_input_refused_before_work():
    """Inverted deviations, a zero direction, an unknown distribution, inverted limits, a dynamic
    shift on uniform inputs (checked for every model before the first is computed)."""
    with pytest.raises(ValidationError, match="lower"):
        StackDimension("a", 1.0, -0.01, 0.01)
    with pytest.raises(ValidationError, match="sensitivity"):
        StackDimension("a", 1.0, 0.01, -0.01, 0.0)
    with pytest.raises(ValidationError, match="distribution"):
        StackDimension("a", 1.0, 0.01, -0.01, 1.0, "lognormal")
    with pytest.raises(ValidationError, match="lower_limit"):
        Stack((StackDimension("a", 1.0, 0.01, -0.01),), "g", 1.0, 0.5)
    s = motor(distribution="uniform")
    with pytest.raises(ValidationError, match="shift_model"):
        analyse_stack(s, {"rss": StackModel(), "six sigma": StackModel(2.0, 0.25)})
    with pytest.raises(ValidationError, match="model.k"):
        StackModel(k=1.0)
