"""The combination matrix of docs/combinations.md: every pair (and the listed triples) of capabilities
either runs, with its numbers checked against an independent route, or is refused before any work
with one line naming both (issue 39).

The independent routes used here:

* **finite differences**: the composed first-order map equals central differences of the composed
  nonlinear model (``pose_error``), which goes through other code (the perturbed chain, not the
  sensitivity kernels) -- so a part lost or applied twice in either path shows;
* **joint configurations vs task poses**: a study on joint configurations equals the same study on
  the task poses those configurations reach (forward kinematics outside the joint-space part; the
  inverse geometry holds the posture), optimum to 1e-6;
* **ties**: a callout is one variable, costed once, whatever wraps the model (the cost of a design
  recomputed by hand from the cost models);
* **a simulated calibration**: robots drawn within the optimum's tolerances, calibrated on the
  nonlinear model, stay within the requirement.
"""
from __future__ import annotations

import copy
from pathlib import Path

import numpy as np
import pytest

from evotol.allocators import allocate_optimum
from evotol.errors import ValidationError
from evotol.studyfile.problem import load_problem
from evotol.verification.montecarlo import verify

ROOT = Path(__file__).resolve().parents[1]
STUDIES = ROOT / "reports" / "studies"

#: UR5 (URDF), two joint configurations inside the joint limits (rad): elbow up, wrist down
JOINTS = [[0.0, -1.0, 1.5, -2.0, -1.5, 0.3], [0.6, -1.4, 1.9, -1.8, -1.6, -0.4]]
COST = {"model": "exponential", "a0": 1.9, "a1": 0.5, "scale": 1e-5}


def ur5(**extra) -> dict:
    """A small UR5 study (as a parsed study file): norm requirement 0.5 mm, worst case."""
    spec = {"name": "combo", "seed": 0, "robot": {"mechanism": "ur5"},
            "poses": {"list": [[0.35, -0.05, 0.25], [0.45, 0.05, 0.35]]},
            "requirement": {"position": 5e-4, "measure": "worst_case"},
            "bounds": {"lower": 1e-6, "upper": 1e-3},
            "cost": {"length": COST, "angle": COST, "actuator": {"model": "reciprocal", "a0": 0.2, "a1": 1.0,
                                                                  "scale": 1e-4},
                     "position": COST, "axial": COST}}
    spec.update(copy.deepcopy(extra))
    return spec


def with_joints(spec):
    spec["poses"] = {"joints": copy.deepcopy(JOINTS)}
    return spec


def with_callouts(spec):
    spec["robot"]["callouts"] = [{"joint": "shoulder_lift_joint", "kind": "position", "length": "60 mm"},
                                 {"joint": "elbow_joint", "kind": "position", "length": "50 mm"},
                                 {"joint": "elbow_joint", "kind": "axial", "length": "75 mm"}]
    return spec


def with_axes(spec):
    spec["requirement"]["position"] = {"x": "0.5*mm", "y": "0.5*mm", "z": "0.3*mm"}
    return spec


def with_calibration(spec):
    spec["calibration"] = {"count": 24, "over": "joints", "measure": "position", "noise": "20 um",
                           "identify": "identifiable", "k": 3, "linear_fraction": 0.1, "simulate": 40}
    return spec


def with_given(spec):
    p = load_problem({k: v for k, v in copy.deepcopy(spec).items() if k != "calibration"}, base_dir=STUDIES)
    spec["sources"] = {n: {"fixed": 2e-5} for n in p.model.source_names}
    return spec


CAPABILITIES = {"joints": with_joints, "callouts": with_callouts, "per-axis": with_axes,
                "calibration": with_calibration, "analysis": with_given}


def build(*caps):
    spec = ur5()
    for c in sorted(caps, key=list(CAPABILITIES).index):     # analysis last: it reads the composed sources
        spec = CAPABILITIES[c](spec)
    return load_problem(spec, base_dir=STUDIES)


def fd_check(problem, h=1e-7, n_dirs=3, seed=0):
    """Largest relative difference between the composed first-order map and central differences of the
    composed nonlinear model, over a few random source-error directions at the problem's poses."""
    robot, poses = problem.model, problem.poses[:4]
    J = robot.sensitivity(poses)
    rng = np.random.default_rng(seed)
    worst = 0.0
    for _ in range(n_dirs):
        d = rng.standard_normal(robot.n_columns)
        E = np.broadcast_to(np.stack([h * d, -h * d]), (len(poses), 2, robot.n_columns))
        P = robot.pose_error(poses, E)
        fd = (P[:, 0] - P[:, 1]) / (2 * h)
        lin = J @ d
        worst = max(worst, float(np.abs(fd - lin).max() / np.abs(lin).max()))
    return worst


# --- pairs that run -------------------------------------------------------------------------------
@pytest.mark.parametrize("caps", [("joints",), ("callouts",), ("joints", "callouts"), ("joints", "per-axis"),
                                  ("callouts", "per-axis"), ("joints", "callouts", "per-axis")],
                         ids=lambda c: "+".join(c))
def test_composed_first_order_map_equals_finite_differences_of_the_composed_nonlinear_model(caps):
    problem = build(*caps)
    assert problem.model.described.part is None
    # problem.robot is the robot the user described: the URDF arm read alone, its own sources
    assert problem.robot is problem.model.described and problem.robot.part is None
    if "callouts" not in caps:      # (callouts read the seats' tilts too: the zones cover them)
        assert problem.robot.source_names == build().model.source_names      # the arm with no part composed
    for c, part in (("callouts", "callouts"), ("joints", "joint_space"), ("per-axis", "axis_limits")):
        assert (problem.model.part_of(part) is not None) == (c in caps), (c, [m.part for m in problem.model.parts()])
    assert fd_check(problem) < 1e-5


@pytest.mark.parametrize("extra", [(), ("per-axis",)], ids=["norm", "per-axis"])
def test_callouts_on_joint_configurations_keep_their_ties_and_equal_the_task_pose_study(extra):
    """Issue 39: under joint configurations the two end discs of a position zone were two costed variables
    (20.65 'certified' vs 13.14). Now: one variable per callout, and the optimum equals the same study on
    the task poses the configurations reach (an independent route: inverse geometry, posture held)."""
    spec = with_callouts(ur5())
    if extra:
        spec = with_axes(spec)
    pt = load_problem(copy.deepcopy(spec), base_dir=STUDIES)            # task poses (inverse geometry)
    arm = pt.model.described
    q = arm.joint_values(ur5()["poses"]["list"])                         # the posture the task study holds
    spec["poses"] = {"joints": np.stack([q[v] for v in arm.kin.variables], axis=1).tolist()}
    pj = load_problem(spec, base_dir=STUDIES)                             # the same arm on those configurations
    callouts = pj.model.part_of("callouts")
    ties = callouts.tied_sources
    assert set(ties) == {"shoulder_lift_joint.position", "elbow_joint.position"}
    assert pj.n_variables == pj.n_sources - sum(len(m) - 1 for m in ties.values())
    rj, rt = allocate_optimum(pj), allocate_optimum(pt)
    assert rj.feasible and rt.feasible
    assert rj.cost == pytest.approx(rt.cost, rel=1e-6)
    # the cost counts each callout once: recomputed from the cost models by hand
    t = rj.tolerances
    by_hand = sum(pj.tolerances[n].cost.cost(t[n]) for n in pj.names
                  if not any(n in m[1:] for m in ties.values()))
    assert rj.cost == pytest.approx(by_hand, rel=1e-9)


def test_exact_zones_vs_boxes_comparison_kept_under_joint_configurations():
    """The exact-zone optimum is never dearer than the independent-box rule's, and both are computed on the
    joint configurations (the joint-space part rebuilt around the boxes)."""
    from evotol.studyfile.callouts import zone_comparison, twin_problem

    pj = build("joints", "callouts")
    boxes = twin_problem(pj, "boxes")
    assert boxes.model.part_of("joint_space") is not None and boxes.model.part_of("callouts").zones == "boxes"
    assert np.array_equal(boxes.poses, pj.poses)
    cmp = zone_comparison(pj)
    assert cmp["exact"]["feasible"] and cmp["boxes"]["feasible"]
    assert cmp["exact"]["cost"] <= cmp["boxes"]["cost"] * (1 + 1e-9)


def test_calibration_on_joint_configurations_keeps_its_linear_range_bound_and_simulation():
    """Issue 39: over joint configurations the linear-range bound was dropped and the study printed
    'certified optimal, meets' at 8.8e-21. Issue 44: the bound is derived from the iterated fit the simulation
    uses; every identifiable source identified, it leaves no second-order term, so the identified sources keep
    the user's 1 mm / 1 mrad (checked at the corners by the iterated fit) -- bounded, never free -- and a
    calibration simulated on the nonlinear model (robots drawn within the optimum's tolerances, each fitted and
    compensated) stays within the requirement."""
    from evotol.calibration import simulate_calibration

    pc = build("joints", "calibration")
    info = pc.calibration
    ident = info.identification.identified_names
    assert all(info.bounds[n]["upper"] == info.bounds[n]["upper_before"] == 1e-3 for n in ident)
    assert all("checked_range" not in info.bounds[n] for n in ident)
    r = allocate_optimum(pc)
    assert r.feasible and r.cost > 1e-3           # bounded by the user's bounds, not ~0
    sim = simulate_calibration(pc, r.tolerances, n_samples=60, seed=1)
    assert sim.simulated["position"]["max"] <= 5e-4
    # the calibrated model has no nonlinear pose_error (its nonlinear check is the simulation above): the
    # refusal names the part that has none, not the UR5, which has one
    with pytest.raises(ValidationError, match=r"UR5 has one, but not with its calibration part\)$"):
        verify(pc, r.tolerances, 10, model="nonlinear")


def test_calibration_with_a_binding_orientation_requirement_holds_on_the_simulated_calibration():
    """Calibration (position measured, over joint configurations) + an orientation requirement that binds:
    the fit's noise reaches the orientation too, so the allocator's orientation limit is the user's less the
    noise allowance (propagated through the fit, not only the position's); the optimum's first-order
    orientation residual sits at that limit, and robots drawn within its tolerances, calibrated on the
    nonlinear model, stay within both of the user's limits. (0.3 x what the position optimum turns.)"""
    from evotol.calibration import simulate_calibration

    turned = float(allocate_optimum(build("joints", "calibration")).errors.orientation.max())
    spec = with_calibration(with_joints(ur5()))
    spec["requirement"]["orientation"] = limit = 0.3 * turned
    p = load_problem(spec, base_dir=STUDIES)
    held = dict(p.components)
    assert held["position"] < 5e-4 and held["orientation"] < limit           # both keep a noise allowance
    r = allocate_optimum(p)
    assert r.feasible
    assert float(r.errors.orientation.max()) / held["orientation"] == pytest.approx(1.0, abs=1e-9)   # binds
    sim = simulate_calibration(p, r.tolerances, n_samples=60, seed=1)
    assert sim.simulated["position"]["max"] <= 5e-4 and sim.simulated["orientation"]["max"] <= limit


@pytest.mark.parametrize("caps", [("joints",), ("callouts",), ("per-axis",), ("joints", "callouts"), ("joints", "per-axis")])
def test_nonlinear_verification_on_each_composition_agrees_with_its_first_order_worst_case(caps):
    """verify(model="nonlinear") on each composition it can meet runs through that composition's own
    pose_error (tied callout ends, joint configurations, the per-axis frame), not the described robot's: at
    small tolerances (30x the lower bounds) its worst-vertex error equals the linear worst case of the
    composed first-order map (support function over directions, an independent computation) to 1e-3 at every
    pose, and no interval sample exceeds that worst case. Calibration and clearances are refused (above, and
    tests/test_montecarlo.py)."""
    p = build(*caps)
    t = np.minimum(p.lower * 30, p.upper)
    chk = verify(p, t, 50, model="nonlinear")
    ev = p.evaluate(t[None], "worst_case")
    for c, _ in p.components:
        np.testing.assert_allclose(chk.worst_vertex[c], chk.linear_worst_case[c], rtol=1e-3)
        # the linear worst case it reports is the worst_case measure's value, bit for bit (computed once, by
        # the call whose maximisers are the worst vertices)
        np.testing.assert_array_equal(chk.linear_worst_case[c], getattr(ev, c)[0])
        assert chk.mc_max[c] <= chk.linear_worst_case[c].max() * (1 + 1e-3)

def test_nonlinear_verification_with_clearances_is_refused_naming_both():
    """The pair (nonlinear verification, clearances) is refused in one line before any sample: by verify
    (the clearance model is first order) and by verify_nonlinear (the clearances part has no pose_error)."""
    from evotol.verification.nonlinear import verify_nonlinear
    from tests.test_combination_matrix import study

    p = load_problem(study("closed-loop", ["clearances"]))
    with pytest.raises(ValidationError, match=r"^model = 'nonlinear': expected 'linear' with clearance sources"):
        verify(p, p.lower, 10, model="nonlinear")
    with pytest.raises(ValidationError, match=r"5-bar has one, but not with its clearances part\)$"):
        verify_nonlinear(p, p.lower, n_samples=10)

def test_a_nonlinear_yield_requirement_with_calibration_names_the_calibration_part():
    """The pair (requirement model = "nonlinear", calibration) is refused in one line naming both: the
    requirement's model and the calibration part that has no nonlinear pose_error (it said "UR5 has none",
    of a UR5 that has one)."""
    spec = with_calibration(with_joints(ur5()))
    spec["requirement"] = {**spec["requirement"], "measure": "yield", "probability": 0.99, "model": "nonlinear"}
    p = load_problem(spec, base_dir=STUDIES)
    with pytest.raises(ValidationError, match=r"^requirement\.model = 'nonlinear': .*UR5 has one, but not with its "
                                              r"calibration part\)$"):
        p.evaluate(p.upper[None] * 0.01)


# Slow (~8 s alone) because its check is strong: the calibrated problem's linear-range caps from iterated fits, two
# optima and a calibration simulated on the nonlinear model (60 robots, each identified and compensated).
def test_puma560_calibrated_on_its_joint_configurations_costs_less_than_uncalibrated():
    """The PUMA 560 (standard DH) on the five configurations of reports/studies/puma560_axes.toml, a norm
    requirement of 0.5 mm, calibrated over the workspace (40 configurations, 20 um): its linear-range caps
    came from second differences of iterated fits that did not all converge (stencil 1 mm / 1 mrad) and
    were 1-4 um, the calibrated optimum costing 28.9 against 1.93 uncalibrated. Here: every stencil fit
    of the cap's derivatives converges but a handful; the calibrated optimum costs less than the
    uncalibrated one, and a calibration simulated on the nonlinear model (robots drawn within its
    tolerances, each identified and compensated) stays within the requirement."""
    import tomllib

    from evotol.calibration import simulate_calibration

    spec = tomllib.loads((STUDIES / "puma560_axes.toml").read_text(encoding="utf-8"))
    spec["requirement"]["position"] = "0.5 mm"
    spec["calibration"] = {"count": 40, "over": "workspace", "measure": "position", "noise": "20 um", "simulate": 0}
    pc = load_problem(spec, base_dir=STUDIES)
    r, u = allocate_optimum(pc), allocate_optimum(pc.uncalibrated)
    assert r.feasible and u.feasible and r.cost < u.cost
    assert min(pc.tolerances[n].upper for n in pc.calibration.identification.identified_names) > 1e-4   # caps not at um
    sim = simulate_calibration(pc, r.tolerances, n_samples=60, seed=1)
    assert sim.simulated["position"]["max"] <= 5e-4


# --- pairs that are refused before any work, with one line naming both ------------------------------
@pytest.mark.parametrize("caps, other", [(("calibration", "callouts"), r"\[\[robot\.callouts\]\]"),
                                         (("calibration", "per-axis"), "requirement per axis"),
                                         (("calibration", "analysis"), "every tolerance given"),
                                         (("calibration", "callouts", "joints"), r"\[\[robot\.callouts\]\]")],
                         ids=lambda c: "+".join(c) if isinstance(c, tuple) else "")
def test_refused_pairs_name_both_capabilities_before_any_work(caps, other, monkeypatch):
    import evotol.calibration.problem as cp

    def no_work(*a, **k):                         # the identification is the first piece of work
        raise AssertionError("the calibration was identified before the refusal")

    monkeypatch.setattr(cp, "identify", no_work)
    with pytest.raises(ValidationError, match=rf"^calibration = '{other}': expected .*") as exc:
        build(*caps)
    assert "\n" not in str(exc.value)


# --- ISO 9283 figures and shop floors with the other parts ----------------------------------------
ISO = {"AP": "0.5 mm", "RP": "0.05 mm"}


@pytest.mark.parametrize("cap, other", [("callouts", r"\[\[robot\.callouts\]\]"), ("per-axis", "requirement per axis")])
def test_iso9283_with_a_part_it_does_not_compose_with_is_refused_before_any_work(cap, other, monkeypatch):
    """[requirement] iso9283 beside callouts or per-axis limits: one line naming both, before the robot is even
    read (the spy fails on any description read). [calibration] composes (tests/test_calibration_random.py) but
    for the case below; joint configurations compose (tests/test_iso9283_given.py)."""
    import evotol.studyfile.problem as sp

    monkeypatch.setattr(sp, "read_robot", lambda *a, **k: (_ for _ in ()).throw(AssertionError("robot read")))
    spec = CAPABILITIES[cap](ur5())
    spec["requirement"]["iso9283"] = dict(ISO)
    with pytest.raises(ValidationError, match=rf"^iso9283 = '{other}': expected a study without it") as exc:
        load_problem(spec, base_dir=STUDIES)
    assert "\n" not in str(exc.value)


@pytest.mark.parametrize("table, field", [({"calibrate": {"configurations": 40}}, "iso9283.calibrate")],
                         ids=["second-calibration"])
def test_iso9283_with_calibration_refuses_what_it_does_not_compose_before_any_work(table, field, monkeypatch):
    """[calibration] with [iso9283] calibrate (a second, simulated calibration): one line naming the field, before
    the robot is read. (ISO AP/RP requirements allocated in the calibrated budget now work:
    tests/test_iso9283_calibrated_budget.py.)"""
    import evotol.studyfile.problem as sp

    monkeypatch.setattr(sp, "read_robot", lambda *a, **k: (_ for _ in ()).throw(AssertionError("robot read")))
    spec = CAPABILITIES["calibration"](ur5())
    spec["requirement"]["iso9283"] = dict(ISO)
    spec["iso9283"] = table
    with pytest.raises(ValidationError, match=rf"^{field} = ") as exc:
        load_problem(spec, base_dir=STUDIES)
    assert "\n" not in str(exc.value)


@pytest.mark.parametrize("caps, floors, binds", [(("joints", "callouts"), {"position": "10 um", "axial": "20 um"}, True),
                                                 (("joints", "calibration"), {"length": "20 um"}, False)],
                         ids=["joints+callouts+shop", "joints+calibration+shop"])
def test_shop_floors_compose_as_lower_bounds(caps, floors, binds):
    """[shop] floors beside joint configurations with callouts, and beside calibration (where the first-order
    map is ~0, so the floors hold but never bind): the floors are the
    allocation's lower bounds, so the optimum equals the one of the same study with those lower bounds
    written per source in [sources] instead (an independent route through the reader), and no tolerance
    of the optimum is below its floor."""
    spec = ur5()
    for c in caps:
        spec = CAPABILITIES[c](spec)
    with_shop = {**copy.deepcopy(spec), "shop": {"floors": floors}}
    from evotol.core.shop import apply_shop

    p = apply_shop(with_shop, load_problem(copy.deepcopy(with_shop), base_dir=STUDIES))    # as evotol run does
    r = allocate_optimum(p)
    assert p.shop_floors and r.feasible
    for n, (floor, _) in p.shop_floors.items():            # (floor in m, the [shop] key that set it)
        assert r.tolerances[n] >= floor * (1 - 1e-12), n
    # with callouts 4 of the 5 members sit at their floor; calibrated, every source runs to its upper bound
    assert any(r.tolerances[n] <= f * (1 + 1e-6) for n, (f, _) in p.shop_floors.items()) is binds
    by_source = copy.deepcopy(spec)
    by_source["sources"] = {n: {"lower": f} for n, (f, _) in p.shop_floors.items()}
    q = load_problem(by_source, base_dir=STUDIES)
    assert allocate_optimum(q).cost == pytest.approx(r.cost, rel=1e-9)
