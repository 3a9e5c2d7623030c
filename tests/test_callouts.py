"""GD&T callouts on joint seats (issue 35): zones, their map to placement errors, and the model.

Independent checks: brute-force sampling of a position zone (the axis ends on their circles, the
independent boxes at their 16 corners) against the issue's numbers and the closed form; the
sampled zone pushed through the nonlinear placement ``exp(delta)`` (the axis stays in its
cylinder to second order); central finite differences of the nonlinear model
(:func:`evotol.robots.base.check_robot`); a brute-force grid over the two end circles against the
worst-case measure, linear and nonlinear.
"""
import tomllib
from pathlib import Path

import numpy as np
import pytest

from evotol.errors import ValidationError
from evotol.robots.checks import check_robot
from evotol.robots.mechanism.callouts.model import CalloutModel
from evotol.robots.mechanism.callouts.table import callouts_from_tables, joint_seat, parse_length
from evotol.robots.mechanism.callouts.zones import (Callout, axis_displacement, lateral_basis, worst_axis_displacement,
                                       zone_members)
from evotol.robots.mechanism.description.reader import load_mechanism
from evotol.robots.mechanism.kinematics.placement import placement_error

UR5 = Path(__file__).resolve().parents[1] / "robots" / "mechanisms" / "ur5.toml"
JOINTS = ["shoulder_pan_joint", "shoulder_lift_joint", "elbow_joint", "wrist_1_joint", "wrist_2_joint", "wrist_3_joint"]


@pytest.fixture(scope="module")
def ur5():
    return load_mechanism(UR5)


def _circle(rng, n, r):
    a = rng.uniform(0, 2 * np.pi, n)
    return r * np.c_[np.cos(a), np.sin(a)]


@pytest.mark.parametrize("s, zone_um, boxes_um", [(20e-3, 10.0, 28.3), (200e-3, 100.0, 156.0)])
def test_position_zone_brute_force_matches_the_issue(s, zone_um, boxes_um):
    """t = 20 um over L = 40 mm: a point s from the zone centre moves <= 10 um (s = 20 mm) and
    <= 100 um (200 mm) in the true zone, 28.3 and 156 um under independent boxes."""
    t, L = 20e-6, 40e-3
    rng = np.random.default_rng(0)
    d1, d2 = _circle(rng, 200_000, t / 2), _circle(rng, 200_000, t / 2)      # extreme axes: ends on the circles
    zone = np.linalg.norm((0.5 - s / L) * d1 + (0.5 + s / L) * d2, axis=1).max()
    corners = np.array(np.meshgrid(*[[-1.0, 1.0]] * 4)).reshape(4, -1).T
    boxes = np.linalg.norm(corners[:, :2] * t / 2 + s * corners[:, 2:] * t / L, axis=1).max()
    assert zone * 1e6 == pytest.approx(zone_um, rel=1e-4)
    assert boxes * 1e6 == pytest.approx(boxes_um, abs=0.5)
    assert worst_axis_displacement(t, L, s) == pytest.approx(zone, rel=1e-4)
    assert worst_axis_displacement(t, L, s, "boxes") == pytest.approx(boxes, rel=1e-12)


@pytest.mark.parametrize("axis", [(0, 0, 1), (0, 1, 0), (1, 0, 0), (0.3, -0.5, 0.8)])
def test_members_move_the_axis_ends_exactly(axis):
    """Position: member errors e1, e2 put the axis at e_k/2 at the feature's ends, with no axial
    shift and no turn about the axis; orientation: the ends differ by e, the centre stays."""
    a = np.asarray(axis, float) / np.linalg.norm(axis)
    e1, e2 = lateral_basis(a)
    assert np.allclose(np.cross(e1, e2), a)
    rng = np.random.default_rng(1)
    c = Callout("J", "position", 0.04, 0.015)
    m1, m2 = zone_members(c, a)
    for _ in range(20):
        u, v = rng.normal(size=2), rng.normal(size=2)
        d = m1.matrix @ u + m2.matrix @ v
        s1, s2 = c.ends
        assert np.allclose(axis_displacement(d, a, s1), u / 2, atol=1e-14)
        assert np.allclose(axis_displacement(d, a, s2), v / 2, atol=1e-14)
        assert abs(d[:3] @ a) < 1e-14 and abs(d[3:] @ a) < 1e-14
    (mo,) = zone_members(Callout("J", "perpendicularity", 0.04, 0.015), a)
    d = mo.matrix @ u
    assert np.allclose(axis_displacement(d, a, c.ends[1]) - axis_displacement(d, a, c.ends[0]), u, atol=1e-14)
    assert np.allclose(axis_displacement(d, a, 0.015), 0.0, atol=1e-14)


def test_nonlinear_placement_keeps_the_sampled_axis_in_its_zone():
    """Sample the zone (ends uniform in their discs, and on the circles), map to the placement
    twist and apply ``exp(delta)`` (the nonlinear model's placement error): the perturbed axis
    crosses the planes of the feature's ends within t/2 + O(t^2/L)."""
    t, L, c = 20e-6, 40e-3, 15e-3
    a = np.array([0.0, 1.0, 0.0])
    m1, m2 = zone_members(Callout("J", "position", L, c), a)
    rng = np.random.default_rng(2)
    n = 2000
    r = t * np.sqrt(rng.uniform(0, 1, (n, 2)))
    r[: n // 2] = t                                   # half of them on the boundary
    ang = rng.uniform(0, 2 * np.pi, (n, 2))
    E1 = np.c_[r[:, 0] * np.cos(ang[:, 0]), r[:, 0] * np.sin(ang[:, 0])]     # member errors |e| <= t
    E2 = np.c_[r[:, 1] * np.cos(ang[:, 1]), r[:, 1] * np.sin(ang[:, 1])]
    delta = E1 @ m1.matrix.T + E2 @ m2.matrix.T
    T = placement_error({f: delta[:, i] for i, f in enumerate(
        ("shift_x", "shift_y", "shift_z", "tilt_x", "tilt_y", "tilt_z"))}, n)
    E = np.stack(lateral_basis(a), axis=1)
    worst = 0.0
    for s, want in zip(Callout("J", "position", L, c).ends, (E1 / 2, E2 / 2)):
        p = T[:, :3, :3] @ (s * a) + T[:, :3, 3]
        ax = T[:, :3, :3] @ a
        q = p + ((s - p @ a) / (ax @ a))[:, None] * ax              # where the axis crosses the end plane
        lat = q @ E
        assert np.linalg.norm(lat, axis=1).max() <= t / 2 * (1 + 1e-6)
        worst = max(worst, np.abs(lat - want).max())
    assert worst < 10 * t * t / L


def test_callout_model_finite_differences_and_sources(ur5):
    """The UR5 with a position and an axial callout per joint: the callouts take the place of
    the five placement errors of each origin (the offsets stay), and the first-order map agrees
    with central differences of the nonlinear model."""
    cs = [Callout(j, "position", 0.05) for j in JOINTS] + [Callout(j, "axial", 0.06) for j in JOINTS]
    m = CalloutModel(ur5, cs)
    assert len(m.sources) == 6 * 4 and m.n_columns == 36
    assert not any(".shift_" in n or ".tilt_" in n for n in m.source_names)
    assert set(m.tied_sources) == {f"{j}.position" for j in JOINTS}
    rep = check_robot(m, m.workspace.grid(2)[:4], rtol=1e-6)
    assert rep["fd_relative_mismatch"] < 1e-6


def test_worst_case_equals_brute_force_over_the_zone(ur5):
    """One position callout ⌀20 um on the elbow (the elbow's offset fixed at 0.1 nrad): the
    worst-case measure equals the largest error over a 181 x 181 grid of the two end circles
    (the extreme points of the zone), linear to 2e-4 and nonlinear to 1e-4 more."""
    from evotol.core.problem import Requirement, Tolerance, ToleranceProblem
    import evotol.cost_models

    m = CalloutModel(ur5, [Callout("elbow_joint", "position", 0.05, 0.01)], sources=["elbow_joint"])
    cost = evotol.cost_models.from_dict({"model": "reciprocal", "a0": 1.0, "a1": 1.0, "scale": 1e-5})
    tols = {n: Tolerance(cost=cost, lower=1e-6, upper=1e-3) for n in m.source_names}
    tols["elbow_joint"] = Tolerance.fixed(1e-10)
    poses = m.workspace.grid(2)[:3]
    P = ToleranceProblem(m, tols, Requirement(position=1e-3), poses)
    t = 20e-6
    T = P.full(np.array([t])[None])
    wc = P.evaluate(T, "worst_case").position[0]
    ang = np.linspace(0, 2 * np.pi, 181)
    circ = t * np.c_[np.cos(ang), np.sin(ang)]
    A, B = np.meshgrid(np.arange(181), np.arange(181))
    E = np.concatenate([circ[A.ravel()], circ[B.ravel()], np.zeros((A.size, 1))], axis=1)
    S = P.jacobian[:, :3, :]
    lin = np.linalg.norm(np.einsum("pij,nj->pni", S, E), axis=-1)
    assert np.all(lin.max(axis=1) <= wc * (1 + 1e-9))
    assert np.all(lin.max(axis=1) >= wc * (1 - 2e-4))
    best = np.argsort(lin, axis=1)[:, -50:]
    nl = m.pose_error(poses, E[best])
    assert np.abs(np.linalg.norm(nl[..., :3], axis=-1).max(axis=1) / lin.max(axis=1) - 1).max() < 1e-4


def test_joint_seat_axes_and_parts_of_the_ur5(ur5):
    """Axes in the origin frames as the URDF writes them (z for pan and wrist 2, y otherwise) and
    the parent link that carries each seat."""
    assert np.allclose(joint_seat(ur5, "shoulder_pan_joint")["axis"], [0, 0, 1])
    assert np.allclose(joint_seat(ur5, "elbow_joint")["axis"], [0, 1, 0])
    assert joint_seat(ur5, "elbow_joint")["part"] == "upper_arm_link"


@pytest.mark.parametrize("entry, field", [
    ({"joint": "elbow_joint", "kind": "position", "length": "0 mm"}, "length"),
    ({"joint": "elbow_joint", "kind": "position", "length": "-5 mm"}, "length"),
    ({"joint": "elbow_joint", "kind": "position", "length": 50}, "length"),
    ({"joint": "elbow_joint", "kind": "position", "length": "50 furlong"}, "length"),
    ({"joint": "elbo_joint", "kind": "position", "length": "50 mm"}, "callout joint"),
    ({"joint": "tool0", "kind": "position", "length": "50 mm"}, "callout tool0"),
    ({"joint": "elbow_joint", "kind": "straightness", "length": "50 mm"}, "kind"),
    ({"joint": "elbow_joint", "kind": "position", "length": "50 mm", "lenght": 1}, "lenght"),
    ({"joint": "elbow_joint", "kind": "parallelism", "length": "stroke"}, "length"),
])
def test_bad_callouts_are_one_line_errors(ur5, entry, field):
    with pytest.raises(ValidationError) as exc:
        callouts_from_tables([entry], ur5)
    assert field in str(exc.value) and "\n" not in str(exc.value)


def test_a_planar_mechanism_has_no_axis_to_place():
    from evotol.robots.mechanism.description.reader import load_mechanism as load
    from evotol.robots.mechanism.description.shipped import resolve_description

    mech = load(resolve_description("planar3rrr", None))
    with pytest.raises(ValidationError, match=r"callout A1 .* spatial mechanism"):
        callouts_from_tables([{"joint": "A1", "kind": "position", "length": "20 mm"}], mech)


def test_duplicate_callouts_on_one_seat_are_refused(ur5):
    e = {"joint": "elbow_joint", "kind": "position", "length": "50 mm"}
    with pytest.raises(ValidationError, match=r"one position callout per joint"):
        callouts_from_tables([e, dict(e)], ur5)
    o = [{"joint": "elbow_joint", "kind": k, "length": "50 mm"} for k in ("perpendicularity", "parallelism")]
    with pytest.raises(ValidationError, match=r"one orientation callout per joint"):
        callouts_from_tables(o, ur5)


def test_lengths_need_their_unit():
    assert parse_length("50 mm", "x") == pytest.approx(0.05)
    assert parse_length("50*mm", "x") == pytest.approx(0.05)
    assert parse_length("0.05 m", "x") == pytest.approx(0.05)
    assert parse_length("2 in", "x") == pytest.approx(0.0508)
    assert parse_length(0, "x") == 0.0
    with pytest.raises(ValidationError, match="with its unit"):
        parse_length(0.05, "x")


RP_ARM_TOML = """
name = "rp"
[lengths]
a = 0.2
e = 0.1
[[frame]]
name = "J1"
antecedent = "0"
joint = "revolute"
actuated = true
theta = "q1"
[[frame]]
name = "J2"
antecedent = "J1"
joint = "prismatic"
actuated = true
d = "a"
r = "q2"
[[frame]]
name = "E"
antecedent = "J2"
d = "e"
[end_effector]
frame = "E"
coordinates = [{ name = "y", low = -0.1, high = 0.1 }, { name = "z", low = 0.05, high = 0.25 }]
[assembly]
joints = { q1 = 0.0, q2 = 0.15 }
[limits]
q2 = [0.0, 0.3]
[tolerances]
sources = ["q1", "q2"]
[[callouts]]
joint = "J2"
kind = "parallelism"
length = "stroke"
[[callouts]]
joint = "J1"
kind = "position"
length = "30 mm"
offset = "-20 mm"
"""
RP_ARM = tomllib.loads(RP_ARM_TOML)


def test_description_callouts_and_a_prismatic_guide_over_its_stroke():
    """``[[callouts]]`` in a TOML description: a guide's parallelism over its 300 mm stroke is a
    tilt disc of radius t/L about the guide's centre, on a [[frame]] joint (axis z of its
    placement); the model agrees with finite differences."""
    from evotol.robots.mechanism.callouts.model import with_callouts
    from evotol.robots.mechanism.description.reader import mechanism_from_dict
    from evotol.robots.mechanism.model.error_model import MechanismModel

    mech = mechanism_from_dict(RP_ARM)
    assert [c.name for c in mech.callouts] == ["J2.parallelism", "J1.position"]
    assert mech.callouts[0].length == pytest.approx(0.3)
    m = with_callouts(MechanismModel(mech))
    assert isinstance(m, CalloutModel)
    assert m.source_names == ("q1", "q2", "J2.parallelism", "J1.position.end1", "J1.position.end2")
    (g,) = zone_members(mech.callouts[0], [0, 0, 1])
    assert np.allclose(g.matrix[3:], [[0, -1 / 0.3], [1 / 0.3, 0], [0, 0]])
    rep = check_robot(m, m.workspace.grid(2), rtol=1e-6)
    assert rep["fd_relative_mismatch"] < 1e-6


def test_check_mechanism_lists_the_callouts(tmp_path, capsys):
    from evotol.cli import main

    f = tmp_path / "rp.toml"
    f.write_text(RP_ARM_TOML)
    main(["check-mechanism", str(f), "--poses", "4"])
    out = capsys.readouterr().out
    assert "2 drawing callouts (exact zones" in out
    assert "J1.position" in out and "from -35 mm to -5 mm along (0, 0, 1)" in out
    assert "J2.parallelism" in out and "over 300 mm" in out


def test_position_refined_by_orientation_is_a_safe_outer_set(ur5):
    """Position ⌀t_p and perpendicularity ⌀t_o on one seat: sample the true zone (both ends in
    their discs and |d2 - d1| <= t_o) by rejection; the model's worst case bounds every sample and
    the model's own extreme points are in the zone only when t_o -> 0."""
    from evotol.core.problem import Requirement, Tolerance, ToleranceProblem
    import evotol.cost_models

    cs = [Callout("elbow_joint", "position", 0.05), Callout("elbow_joint", "perpendicularity", 0.05)]
    m = CalloutModel(ur5, cs, sources=["elbow_joint"])
    assert m.source_names == ("elbow_joint.position", "elbow_joint.perpendicularity", "elbow_joint")
    cost = evotol.cost_models.from_dict({"model": "reciprocal", "a0": 1.0, "a1": 1.0, "scale": 1e-5})
    tols = {n: Tolerance(cost=cost, lower=1e-7, upper=1e-3) for n in m.source_names}
    tols["elbow_joint"] = Tolerance.fixed(1e-12)
    poses = m.workspace.grid(2)[:2]
    P = ToleranceProblem(m, tols, Requirement(position=1e-3), poses)
    tp, to = 20e-6, 8e-6
    wc = P.evaluate(np.array([[tp, to, 1e-12]]), "worst_case").position[0]
    rng = np.random.default_rng(3)
    d1, d2 = _circle(rng, 400_000, tp / 2) * np.sqrt(rng.uniform(0, 1, (400_000, 1))), \
        _circle(rng, 400_000, tp / 2) * np.sqrt(rng.uniform(0, 1, (400_000, 1)))
    ok = np.linalg.norm(d2 - d1, axis=1) <= to
    d1, d2 = d1[ok], d2[ok]
    # the model's sources: centre displacement e_p = 2 d_c, orientation e_o = d2 - d1
    E = np.concatenate([d1 + d2, d2 - d1, np.zeros((len(d1), 1))], axis=1)
    err = np.linalg.norm(np.einsum("pij,nj->pni", P.jacobian[:, :3, :], E), axis=-1).max(axis=1)
    assert np.all(err <= wc * (1 + 1e-9))
    assert np.all(err >= 0.7 * wc)           # a bound, not a vast over-estimate here


def test_an_orientation_tighter_than_its_position_warns(tmp_path):
    from evotol.core.plausibility import PlausibilityWarning
    from evotol.studyfile import load_problem

    spec = {"robot": {"mechanism": "ur5", "sources": ["elbow_joint"],
                      "callouts": [{"joint": "elbow_joint", "kind": "position", "length": "50 mm"},
                                   {"joint": "elbow_joint", "kind": "perpendicularity", "length": "50 mm"}]},
            "poses": {"grid": 2}, "requirement": {"position": 5e-4},
            "bounds": {"position": {"lower": 2e-5, "upper": 1e-4}, "perpendicularity": {"lower": 1e-6, "upper": 1e-5}},
            "cost": {"default": {"model": "reciprocal", "a0": 1.0, "a1": 1.0, "scale": 1e-5}}}
    with pytest.warns(PlausibilityWarning, match="elbow_joint.perpendicularity: orientation .* binds the tilt"):
        load_problem(spec)


@pytest.mark.parametrize("robot, field", [
    ({"mechanism": "ur5", "zones": "cubes", "callouts": [{"joint": "elbow_joint", "kind": "position", "length": "5 mm"}]},
     "robot.zones"),
    ({"mechanism": "ur5", "callouts": {"joint": "elbow_joint"}}, "robot.callouts"),
    ({"mechanism": "ur5", "callouts": [{"joint": "elbow_joint", "kind": "position"}]}, "robot.callouts[0].length"),
])
def test_bad_callout_tables_in_a_study_file(robot, field):
    from evotol.studyfile import load_problem

    spec = {"robot": robot, "poses": {"grid": 2}, "requirement": {"position": 5e-4},
            "cost": {"default": {"model": "reciprocal", "a0": 1.0, "a1": 1.0, "scale": 1e-5}}}
    with pytest.raises(ValidationError) as exc:
        load_problem(spec)
    assert str(exc.value).startswith(field) and "\n" not in str(exc.value)


def test_callouts_replace_the_dh_entries_they_cover_on_a_standard_dh_arm():
    """Issue 39: on the PUMA 560 (standard DH) a position callout on J<i>'s seat takes the place of
    a_(i-1) and alpha_(i-1) (the seat's lateral shift and tilt along x), an axial one of d_i (shift
    along the axis); theta_i (the encoder zero, a turn about the axis) stays. The callout's error in
    each of those directions equals the replaced entry's: central differences of the textbook product
    A_1 ... A_6 with that entry moved (tests/test_standard_dh.py)."""
    from tests.test_standard_dh import PUMA, TABLE, textbook_fk

    puma = load_mechanism(PUMA)
    cs = [Callout("J2", "position", 0.05), Callout("J3", "position", 0.05), Callout("J3", "axial", 0.06)]
    m = CalloutModel(puma, cs)
    names = set(m.source_names)
    assert not names & {"a1", "alpha1", "a2", "alpha2", "d3"}                    # replaced, not added on top
    assert {"theta2", "theta3", "d2", "a3", "alpha3", "d4"} <= names
    assert not any(".shift_" in n or ".tilt_" in n for n in names)
    # 5 entries out; in: J2 and J3 position (two end discs each, tied) and J3 axial
    assert len(m.source_names) == 24 - 5 + 2 + 2 + 1 and set(m.tied_sources) == {"J2.position", "J3.position"}
    q = np.radians([10, 10, -100, -20, 30, -60])
    S = m.sensitivity_at_joints(q[None])[0, :3]       # (3, n_columns): position error per unit of each column
    base_names = list(m.base.source_names)
    h = 1e-7
    # entry -> (row, field in TABLE's (d, a, alpha)) and the seat's placement direction it equals
    for entry, (row, k), (joint, field) in [("a1", (0, 1), ("J2", "shift_x")), ("alpha1", (0, 2), ("J2", "tilt_x")),
                                           ("a2", (1, 1), ("J3", "shift_x")), ("alpha2", (1, 2), ("J3", "tilt_x")),
                                           ("d3", (2, 0), ("J3", "shift_z"))]:
        fields = [f for f in ("shift_x", "shift_y", "shift_z", "tilt_x", "tilt_y", "tilt_z") if f"{joint}.{f}" in base_names]
        rows = [base_names.index(f"{joint}.{f}") for f in fields]        # the seat's placement errors the zones move
        u = (np.array(fields) == field).astype(float)
        e = np.linalg.lstsq(m.C[rows], u, rcond=None)[0]                          # callout errors making that motion
        assert np.allclose(m.C[rows] @ e, u, atol=1e-12)                         # the callouts span it
        up, dn = [list(r) for r in TABLE], [list(r) for r in TABLE]
        up[row][k] += h
        dn[row][k] -= h
        fd = (textbook_fk(q, up)[:3, 3] - textbook_fk(q, dn)[:3, 3]) / (2 * h)
        assert np.allclose(S @ e, fd, atol=1e-8), entry
