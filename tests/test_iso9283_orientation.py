"""ISO 9283 orientation figures AP_a, AP_b, AP_c and RP_a, RP_b, RP_c (issue 44 item 2; ISO 9283 §7.2,
evotol/measures/iso9283/budget.py::predict_orientation).

References written here: the standard's formulas by loops over the cycles; RP_a = 3 S_a against our own
sampling of the joint errors (uniform quantisation, lost-motion variation, bearing-play discs) pushed through
Pinocchio's Jacobian of the shipped UR5 URDF; the worst-case AP_a against enumeration of every corner of the
tolerance box; the simulated test on the nonlinear model within the predictions.
"""
from __future__ import annotations

import itertools
from pathlib import Path

import numpy as np
import pytest

from evotol.measures.iso9283 import (TestCube, iso_positions, orientation_figures_of_test, predict_orientation,
                                     simulate)
from evotol.measures.iso9283.budget import joints_and_maps
from evotol.robots.mechanism import MechanismModel
from evotol.robots.mechanism.model.random_sources import RandomSource, encoder_count

ROOT = Path(__file__).resolve().parents[1]
ARCMIN = np.pi / 180 / 60
P = iso_positions(TestCube((0.4, 0.0, 0.3), 0.2))


@pytest.fixture(scope="module")
def ur5():
    return MechanismModel(ROOT / "robots" / "mechanisms" / "ur5.toml")


def test_orientation_figures_follow_the_standards_formulas():
    rng = np.random.default_rng(0)
    a = rng.normal(1e-4, 2e-5, (30, 3))
    f = orientation_figures_of_test(a)
    for k in range(3):
        mean = sum(a[j, k] for j in range(30)) / 30
        s = (sum((a[j, k] - mean) ** 2 for j in range(30)) / 29) ** 0.5
        assert f["AP"][k] == pytest.approx(mean, rel=1e-12) and f["RP"][k] == pytest.approx(3 * s, rel=1e-12)


def test_rp_per_angle_equals_our_sampling_through_pinocchio(ur5):
    """Encoder counts and lost-motion variation on the six joints: 3 S_a of a = J_rot δq, δq drawn here."""
    import pinocchio as pin

    joints = list(ur5.kin.actuated)
    src = [RandomSource("encoder", j, encoder_count(14)) for j in joints] + \
          [RandomSource("backlash", j, 2 * ARCMIN, 0.2) for j in joints]
    pred = predict_orientation(ur5, P, np.zeros(ur5.n_columns), src)["RP"]
    q, _ = joints_and_maps(ur5, P)
    model = pin.buildModelFromUrdf(str(ROOT / "robots/urdf/ur_description/urdf/ur5_robot.urdf"))
    data, frame = model.createData(), model.getFrameId("tool0")
    rng = np.random.default_rng(5)
    n = 400000
    dq = encoder_count(14) * rng.uniform(-0.5, 0.5, (n, 6)) + 2 * ARCMIN * 0.2 * rng.uniform(-0.5, 0.5, (n, 6))
    for i in range(len(P)):
        qi = np.array([q[v][i] for v in ur5.kin.variables])
        J = pin.computeFrameJacobian(model, data, qi, frame, pin.LOCAL_WORLD_ALIGNED)[3:]     # rotation rows, base axes
        a = dq @ J.T
        assert pred[i] == pytest.approx(3 * a.std(axis=0, ddof=1), rel=5e-3)


def test_worst_case_ap_per_angle_is_the_largest_corner(ur5):
    names = list(ur5.source_names)
    t = np.zeros(ur5.n_columns)
    picked = [names.index(n) for n in names if n.endswith(".tilt_x") or n in ur5.kin.actuated][:10]
    t[picked] = 1e-4
    src = [RandomSource("backlash", "elbow_joint", 3 * ARCMIN, 0.1)]
    pred = predict_orientation(ur5, P, t, src)["AP"]
    _, S = joints_and_maps(ur5, P)
    e = names.index("elbow_joint")
    for i in range(len(P)):
        # the elbow's lost motion at pose i: the offset from its approach side over [0, b], enumerated at the ends
        best = np.zeros(3)
        for signs in itertools.product((-1.0, 1.0), repeat=len(picked)):
            d = np.zeros(ur5.n_columns)
            d[picked] = np.array(signs) * 1e-4
            for lost in (0.0, 1.0):
                dd = d.copy()
                dd[e] += lost * 3 * ARCMIN / 2 * _elbow_offset_sign(ur5, S[i])
                best = np.maximum(best, np.abs(S[i, 3:] @ dd))
        assert pred[i] == pytest.approx(best, rel=1e-9, abs=1e-15), i


def _elbow_offset_sign(ur5, S):
    """−s for the elbow's approach sign s (the joint lags its motion), the tool moving down."""
    act = list(ur5.kin.actuated)
    names = list(ur5.source_names)
    dq = np.linalg.lstsq(S[:, [names.index(j) for j in act]], [0, 0, -1, 0, 0, 0], rcond=None)[0]
    return -np.sign(dq[act.index("elbow_joint")])


def test_simulated_orientation_figures_lie_within_the_predictions(ur5):
    joints = list(ur5.kin.actuated)
    src = [RandomSource("encoder", j, encoder_count(15)) for j in joints] + \
          [RandomSource("radial_play", j, 20e-6) for j in joints[:3]]
    t = np.full(ur5.n_columns, 20e-6)
    pred = predict_orientation(ur5, P, t, src)
    sim = simulate(ur5, P, t, src, n_robots=300, n_cycles=30, seed=2)
    assert sim["AP_abc"].shape == (300, 5, 3) and sim["RP_abc"].shape == (300, 5, 3)
    assert np.all(np.abs(sim["AP_abc"]).max(axis=0) <= pred["AP"] * (1 + 1e-3))
    assert np.all(np.abs(sim["AP_abc"]).max(axis=0) >= 0.3 * pred["AP"])
    # the mean of 3 S_a over 300 tests of 30 cycles: E S = c4(30) σ = 0.9914 σ; sampling error ~1 %
    assert sim["RP_abc"].mean(axis=0) == pytest.approx(0.9914 * pred["RP"], rel=0.03)


def test_a_study_with_an_orientation_requirement_writes_the_figures_beside_the_positional_ones(tmp_path):
    """The example with [requirement] orientation: per pose AP_orientation / RP_orientation {a, b, c} in the JSON
    beside AP and RP, the page's table; the simulated figures within their predictions (AP_a at most the worst
    case, the mean 3 S_a at c4(30) times the predicted 3 sigma, within the sampling error of 40 tests)."""
    import json

    from evotol.studyfile import run_study_file

    spec = (ROOT / "reports/studies/iso9283_example.toml").read_text()
    spec = spec.replace('measure = "worst_case"', 'measure = "worst_case"\norientation = 2e-3')
    spec = spec.replace("allocate = true", "allocate = false").replace("calibrate = {", "# calibrate = {")
    spec = spec.replace("simulate = { robots = 200, cycles = 30, multidirectional = true }",
                        "simulate = { robots = 40, cycles = 30, multidirectional = false }")
    spec = spec.replace("grid = [3, 3, 3]", "grid = [2, 2, 2]").replace('RP = "0.05 mm"', 'RP = "0.1 mm"')
    (tmp_path / "s.toml").write_text(spec)
    run_study_file(tmp_path / "s.toml", out=tmp_path)
    data = json.loads((tmp_path / "iso9283_example.json").read_text())
    page = (tmp_path / "iso9283_example.html").read_text()
    for p in data["iso9283"]["poses"]:
        assert set(p["AP_orientation"]) == set(p["RP_orientation"]) == {"a", "b", "c"}
        for a in "abc":
            o, r = p["AP_orientation"][a], p["RP_orientation"][a]
            assert 0 < o["simulated"] <= o["predicted"] * (1 + 1e-3)
            assert r["interval"][0] <= r["simulated"] <= r["interval"][1]
            assert r["simulated"] == pytest.approx(0.9914 * r["predicted"], rel=0.06)
    assert "iso9283-orientation" in page and "RPa predicted / simulated" in page


# --- orientation figures as allocation constraints (issue 44): [requirement] iso9283 = { APa = ..., RPc = ... } ---

def _allocation_with_orientation(ur5_joints, orientation):
    import evotol.cost_models as cm
    from evotol.allocators.iso9283 import allocate_iso9283
    srcs = [RandomSource("backlash", j, ARCMIN) for j in JOINTS] + [RandomSource("encoder", j, encoder_count(14, 50))
                                                                    for j in JOINTS]
    sc = [cm.ReciprocalCost(0.1, 1.0, scale=1e-5)] * 6
    rc = [cm.ReciprocalCost(0.2, 1.0, scale=s.tolerance) for s in srcs]
    return srcs, allocate_iso9283(ur5_joints, P, sc, [[1e-6] * 6, [1e-3] * 6], np.ones(6, bool), srcs, rc,
                                  [[s.tolerance / 10 for s in srcs], [s.tolerance * 10 for s in srcs]], 4e-4, 4e-5,
                                  n_samples=5000, orientation=orientation)


JOINTS = ["shoulder_pan_joint", "shoulder_lift_joint", "elbow_joint", "wrist_1_joint", "wrist_2_joint", "wrist_3_joint"]


@pytest.fixture(scope="module")
def ur5_joints():
    return MechanismModel(ROOT / "robots" / "mechanisms" / "ur5.toml", sources=JOINTS)


def test_allocated_orientation_figures_hold_by_enumeration_and_our_own_sampling(ur5_joints):
    """APc (about the base z) and RPa (about x) bound at 70 % of what the AP/RP allocation alone gives: both bind;
    APc at every pose is the largest of the 2^6 x 2^6 corners (encoder offsets ±t, lost motion taken up against
    the approach: 0 or −s b/2, a joint that does not move anywhere in ±b/2) through Pinocchio's rotation rows, and
    RPa is 3 S of our own draws of lost-motion variation (±0.1 b/2) and encoder counts (±q/2)."""
    from tests.test_iso9283 import pinocchio_position_jacobian
    srcs, free = _allocation_with_orientation(ur5_joints, None)
    o = predict_orientation(ur5_joints, P, free["systematic"], srcs, free["random"])
    limits = {"APc": 0.7 * o["AP"][:, 2].max(), "RPa": 0.7 * o["RP"][:, 0].max()}
    _, res = _allocation_with_orientation(ur5_joints, limits)
    assert res["feasible"] and all(v["active"] for v in res["orientation"].values())
    assert res["cost"] > free["cost"]
    t, b, c = res["systematic"], res["random"][:6], res["random"][6:]
    q, _ = joints_and_maps(ur5_joints, P)
    rng = np.random.default_rng(9)
    dq = rng.uniform(-0.5, 0.5, (400000, 6)) * 0.1 * b + rng.uniform(-0.5, 0.5, (400000, 6)) * c
    for i in range(len(P)):
        J6 = pinocchio_position_jacobian({j: q[j][i:i + 1] for j in JOINTS})
        d = np.linalg.solve(J6, [0, 0, -1.0, 0, 0, 0])
        s = np.where(np.abs(d) > 1e-9 * np.abs(d).max(), np.sign(d), 0.0)
        ends = [(0.0, -sj * bj / 2) if sj else (-bj / 2, bj / 2) for sj, bj in zip(s, b)]
        best = max(abs(J6[5] @ (np.array(e) * t + np.array(k)))
                   for e in itertools.product((-1.0, 1.0), repeat=6) for k in itertools.product(*ends))
        assert res["orientation"]["APc"]["value"][i] == pytest.approx(best, rel=1e-9)
        assert best <= limits["APc"]
        own = 3 * (dq @ J6[3]).std(ddof=1)
        assert res["orientation"]["RPa"]["value"][i] == pytest.approx(own, rel=5e-3)
        assert own <= limits["RPa"] * 1.005


def test_a_study_allocates_to_orientation_figures_and_states_their_verdicts(tmp_path):
    import json

    from evotol.studyfile import run_study_file

    spec = (ROOT / "reports/studies/iso9283_example.toml").read_text()
    spec = spec.replace("calibrate = {", "# calibrate = {").replace("grid = [3, 3, 3]", "grid = [2, 2, 2]")
    spec = spec.replace("simulate = { robots = 200, cycles = 30, multidirectional = true }",
                        "simulate = { robots = 10, cycles = 30, multidirectional = false }")
    spec = spec.replace('iso9283 = { AP = "0.5 mm", RP = "0.05 mm" }',
                        'iso9283 = { AP = "0.5 mm", RP = "0.05 mm", APa = "0.9 mrad", RPc = "0.3 mrad" }')
    (tmp_path / "s.toml").write_text(spec)
    run_study_file(tmp_path / "s.toml", out=tmp_path)
    block = json.loads((tmp_path / "iso9283_example.json").read_text())["iso9283"]
    al = block["allocation"]
    assert al["feasible"] and al["orientation"]["APa"]["active"] and al["orientation"]["RPc"]["active"]
    assert block["requirement"]["APa"] == pytest.approx(9e-4) and block["requirement"]["RPc"] == pytest.approx(3e-4)
    for p, a, r in zip(block["poses"], al["orientation"]["APa"]["value"], al["orientation"]["RPc"]["value"]):
        assert p["AP_orientation"]["a"]["predicted"] == pytest.approx(a, rel=1e-9) and a <= 9e-4
        assert p["RP_orientation"]["c"]["predicted"] == pytest.approx(r, rel=1e-9) and r <= 3e-4
        assert p["AP_orientation"]["a"]["simulated"] <= a * (1 + 1e-3)
    v = block["verdict"]
    assert v["APa"]["meets"] is True and v["RPc"]["meets"] is True and "exact" in v["RPc"]["model"]
    page = (tmp_path / "iso9283_example.html").read_text()
    assert "APa ≤ 185.6 arcsec: the design <b>meets</b> it" in page and "iso9283-orientation" in page   # 0.9 mrad


@pytest.mark.parametrize("change, field", [
    ({"requirement": {"iso9283": {"AP": "0.5 mm", "RPa": "0.1 mrad"}}, "iso9283": {"random": None}},
     "requirement.iso9283.RPa"),
    ({"requirement": {"iso9283": {"AP": "0.5 mm", "APb": "1 urad"}}}, "requirement.iso9283.APb"),
    ({"requirement": {"iso9283": {"AP": "0.5 mm", "APd": "1 mrad"}}}, "requirement.iso9283.APd")],
    ids=["RPa-without-random-sources", "APb-below-its-floor", "unknown-figure"])
def test_orientation_requirements_refused_in_one_line(change, field):
    import tomllib

    from evotol.errors import ValidationError
    from evotol.studyfile.iso9283 import read_iso9283
    from evotol.studyfile.problem import load_problem
    spec = tomllib.loads((ROOT / "reports/studies/iso9283_example.toml").read_text())
    spec["requirement"]["iso9283"] = change["requirement"]["iso9283"]
    if "iso9283" in change:
        del spec["iso9283"]["random"]
        spec["iso9283"]["allocate"] = False
    with pytest.raises(ValidationError) as e:
        read_iso9283(spec, load_problem(spec))
    assert e.value.field == field and "\n" not in str(e.value)


def test_orientation_figures_beside_calibration_are_refused_before_the_robot_is_read():
    import tomllib

    from evotol.errors import ValidationError
    from evotol.studyfile.problem import load_problem
    spec = tomllib.loads((ROOT / "reports/studies/ur5_calibrated.toml").read_text())
    spec["requirement"]["iso9283"] = {"AP": "0.3 mm", "RPa": "0.1 mrad"}
    with pytest.raises(ValidationError, match=r"^requirement\.iso9283\.RPa = ") as e:
        load_problem(spec, base_dir=ROOT / "reports/studies")
    assert "\n" not in str(e.value)
