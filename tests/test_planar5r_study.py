"""Study laramolina2019-5r (quick run) and its probabilistic clearance / actuator allocation."""
import json

import numpy as np
import pytest

from evotol import studies
from evotol.studies import laramolina2019_5r as L
from evotol.robots.planar5r import Planar5R
from evotol.robots.planar5r import uncertainty as U


@pytest.fixture(scope="module")
def quick_run(tmp_path_factory):
    out = tmp_path_factory.mktemp("laramolina2019_5r")
    summary = studies.get("laramolina2019-5r").run(out, quick=True, seed=0)
    return out, summary


def test_study_writes_html_and_json_with_issue_keys(quick_run):
    out, summary = quick_run
    html = (out / "laramolina2019-5r.html").read_text()
    data = json.loads((out / "laramolina2019-5r.json").read_text())
    assert '<script src="http' not in html and "Plotly" in html   # offline: plotly.js beside it, no CDN
    assert set(data["cases"]) == set("abcd")
    for case in data["cases"].values():
        for key in ("r1", "r2", "r3", "mic_radius", "mic_center_y", "lci_max"):
            assert isinstance(case[key], float)
        for key in ("mean_dx", "std_dx", "max_dev", "p_exceed"):
            assert len(case["poses"][key]) == 9


def test_study_mic_values_are_eqs21_22(quick_run):
    """Table 2 cases through eq. 21 (b, d) and eq. 22 (a, c), recomputed by hand here."""
    c = quick_run[1]["cases"]
    assert c["b"]["mic_radius"] == pytest.approx(0.47) and c["b"]["mic_center_y"] == pytest.approx(np.sqrt(1.73**2 - 0.8**2))
    assert c["d"]["mic_radius"] == pytest.approx(0.75) and c["d"]["mic_center_y"] == pytest.approx(np.sqrt(4 - 0.0625))
    for k, (r1, r2, r3) in {"a": (2.0, 0.2, 0.8), "c": (0.6, 1.1, 1.3)}.items():
        ycol = np.sqrt(r1**2 - (r2 - r3) ** 2)
        yc = ((r1 + r2 + ycol) ** 2 - r3**2) / (2 * (r1 + r2 + ycol))
        assert c[k]["mic_center_y"] == pytest.approx(yc) and c[k]["mic_radius"] == pytest.approx(yc - ycol)
        assert c[k]["mic_numeric"]["radius"] == pytest.approx(yc - ycol, abs=1e-5)


def test_study_reproduces_paper_trends(quick_run):
    c = quick_run[1]["cases"]
    # Sec. 3.2 / 3.4: case b well conditioned, case d max LCI ~ 0.55
    assert c["b"]["lci_at_mic_center"] > 0.9 and c["d"]["lci_max"] == pytest.approx(0.55, abs=0.035)
    # Sec. 3.2 / 3.4: every sample of cases b and d stays in its 0.005 circle
    assert max(c["b"]["poses"]["p_exceed"]) == 0 and max(c["d"]["poses"]["p_exceed"]) == 0
    # Sec. 3.1 / 3.3: cases a and c have poses near singular borders that leave the circle
    assert max(c["a"]["poses"]["p_exceed"]) > 0.1 and max(c["c"]["poses"]["p_exceed"]) > 0.1


def _design(P, clearance_A, clearance_B, theta_std):
    """Source tolerances (1, n_sources) of the study's three shared variables through the problem's
    own mapping (``P.variables``, ``P.full``); the actuator tolerance is SIGMA_K = 3 std."""
    values = {"clearance_A": clearance_A, "clearance_B": clearance_B, "theta": L.SIGMA_K * theta_std}
    return P.full([[values[v] for v in P.variables]])


def test_core_nonlinear_yield_agrees_with_the_direct_sampler():
    """The core's nonlinear yield of the study's problem (shared tolerances, fixed normal lengths,
    contact clearances, normal actuators) against the 5R's own sampler (evotol.robots.planar5r.uncertainty,
    independent code and samples): within 4 standard errors of the difference at every pose."""
    P = L.allocation_problem("d", 2048, 3, radius=0.1e-3)
    rc, sd = 20e-6, np.deg2rad(0.02)
    T = _design(P, rc, rc, sd)
    q = 1 - P.evaluate(T).probability[0]
    robot = P.model
    m = U.UncertaintyModel(theta_std=sd, clearance=rc, shared_lengths=False, renormalise=False)
    dp, ok = U.position_deviations(P.poses, robot.r1, robot.r2, robot.r3, m,
                                   U.unit_samples(8192, m.n_dims, "mc", 5), failures="mask")
    q_ref = np.mean(~(np.hypot(dp[..., 0], dp[..., 1]) <= 0.1e-3) | ~ok, axis=1)
    assert 0.005 < q.max() < 0.5
    qb = 0.5 * (q + q_ref)
    assert np.all(np.abs(q - q_ref) <= 4 * np.sqrt(qb * (1 - qb) * (1 / 2048 + 1 / 8192)) + 1e-12)


def test_exceedance_grows_with_every_tolerance():
    P = L.allocation_problem("b", 512, 0, radius=0.1e-3)
    base = np.array([20e-6, 20e-6, 2e-4])
    p0 = 1 - P.evaluate(_design(P, *base)).probability.min()
    for j in range(3):
        t = base.copy()
        t[j] *= 2
        assert 1 - P.evaluate(_design(P, *t)).probability.min() >= p0
    assert 1 - P.evaluate(_design(P, *(3 * base))).probability.min() > p0


def test_allocation_is_feasible_and_verified():
    cfg = dict(n_alloc_samples=256, pop=12, n_gen=8, n_verify=20000)
    res = L.allocate_case("b", cfg, 0, pareto=True, grid=5)
    assert res["feasible"]
    t = res["tolerances"]
    for v, (lo, hi) in L.BOUNDS.items():
        assert lo * (1 - 1e-12) <= t[v] <= hi * (1 + 1e-12)
    c = L.default_costs()
    by_hand = 2 * (c["clearance_A"].cost(t["clearance_A"]) + c["clearance_B"].cost(t["clearance_B"])
                   + c["theta"].cost(3 * t["theta"]))          # two parts per variable, t = 3 std
    assert res["cost"] == pytest.approx(float(by_hand))
    assert res["p_exceed_verified_max"] <= 0.0125          # 20 000 fresh samples, binomial noise ~7e-4
    assert len(res["pareto"]["cost"]) > 3 and np.all(np.diff(res["pareto"]["cost"]) >= 0)


def test_allocation_reports_infeasible_requirement():
    cfg = dict(n_alloc_samples=128, pop=8, n_gen=3, n_verify=1000)
    res = L.allocate_case("c", cfg, 0, pareto=False, grid=0, radius=0.1e-3)
    assert res["feasible"] is False and res["p_exceed_at_lower_bounds"] > 0.01


def test_worst_case_counterpart_through_the_core_holds_for_sampled_extreme_errors():
    """allocate_optimum's design: no admissible error (checked on the nonlinear model with errors
    on the tolerance boundaries) moves P by more than the radius; the probabilistic model never exceeds."""
    radius = 0.2e-3
    res = L.worst_case_case("b", 0)
    assert res["feasible"] and res["max_position_error"] <= radius * (1 + 1e-9)
    assert res["p_exceed_probabilistic_model"] == 0.0
    robot = Planar5R("b", D=0.2)
    poses = robot.miw_poses()
    rng = np.random.default_rng(0)
    n = 4000
    cols = []
    for s in robot.sources:
        t = res["tolerances"][s.name]
        if s.dim == 1:
            cols.append(t * rng.choice([-1.0, 1.0], size=(n, 1)))
        else:
            a = rng.uniform(0, 2 * np.pi, n)
            cols.append(t * np.stack([np.cos(a), np.sin(a)], -1))
    E = np.concatenate(cols, axis=1)
    dp = robot.pose_error(poses, np.broadcast_to(E, (len(poses),) + E.shape))
    assert np.max(np.hypot(dp[..., 0], dp[..., 1])) <= radius * 1.01      # linearisation error < 1 %


def test_report_is_drawn_from_the_json_alone(quick_run):
    """render() reads only the written JSON: redrawing from it gives the same page, byte for byte."""
    out, _ = quick_run
    d = json.loads((out / "laramolina2019-5r.json").read_text())
    page = studies.get("laramolina2019-5r").render(studies.StudyResult(d)).render()
    assert page == (out / "laramolina2019-5r.html").read_text()


def test_every_number_in_the_json_has_a_unit(quick_run):
    """docs/units.md: the file's ``units`` block resolves the unit of every number (issue 15)."""
    from evotol.units import numbers_without_unit

    data = quick_run[1]
    assert data["units"]["keys"] and numbers_without_unit(data, data["units"]) == []
