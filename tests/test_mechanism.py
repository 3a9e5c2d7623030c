"""Mechanisms from a description file (issue 12): schema errors, kinematics, sources, sensitivities.

Independent checks: the hand-written models of the seed robots (5-bar closed forms Deng 2012 eqs.
IV.1-IV.19 and IV.27-IV.43; IRSBot-2 inverse geometry eqs. II.5-II.35 on Tabs. II.1-II.2; the
certified clearance engine on the hand-written ClearanceMechanisms), central finite differences of
the nonlinear loop closure (check_robot), and the closed form of a planar 2R arm.
"""
from pathlib import Path

import numpy as np
import pytest

from evotol.errors import KinematicsError, ValidationError
from evotol.robots.base import Workspace, check_robot
from evotol.robots.clearance import max_pose_error
from evotol.robots.fivebar import FiveBar, FiveBarGeometric
from evotol.robots.irsbot2 import IRSBot2, MAP_WORKSPACE
from evotol.robots.mechanism import MechanismModel, load_mechanism, mechanism_from_dict
from evotol.units import MM

HERE = Path(__file__).resolve().parents[1] / "robots" / "mechanisms"


@pytest.fixture(scope="module")
def fivebar():
    return MechanismModel(HERE / "fivebar.toml")


@pytest.fixture(scope="module")
def irsbot():
    return MechanismModel(HERE / "irsbot2.toml")


# ---------------------------------------------------------------------------------- 5-bar
def test_fivebar_newton_inverse_geometry_equals_closed_form_IV1_IV19(fivebar):
    poses = fivebar.workspace.latin_hypercube(50, seed=4)
    q, g = fivebar.joint_values(poses), FiveBar().joint_values(poses)
    for k in g:
        assert np.abs(q[k] - g[k]).max() < 1e-12, k


def test_fivebar_sensitivity_equals_hand_written_IV43_at_50_poses(fivebar):
    """Description-driven map vs FiveBarGeometric (eq. IV.43 + eq. IV.40), 1e-9 relative."""
    poses = fivebar.workspace.latin_hypercube(50, seed=5)
    S, H = fivebar.sensitivity(poses), FiveBarGeometric().sensitivity(poses)
    assert fivebar.source_names == ("L0", "L1", "L2", "L3", "L4", "L5", "theta1", "theta3")
    assert np.abs(S - H).max() <= 1e-9 * np.abs(H).max()


def test_fivebar_passes_check_robot_finite_differences(fivebar):
    rep = check_robot(fivebar)
    assert rep["fd_relative_mismatch"] < 1e-6


def test_fivebar_certified_clearance_maxima_equal_hand_written():
    """Deng 2012 Sec. IV.3 clearances at (0, 70) mm: same attained maxima within the certificate gap."""
    mech = MechanismModel(HERE / "fivebar.toml").clearance_mechanism()
    pose = [[0.0, 70 * MM]]
    a, b = max_pose_error(mech, pose), max_pose_error(FiveBar().clearance_mechanism(), pose)
    assert abs(a.p_max[0] - b.p_max[0]) <= max(a.p_upper[0] - a.p_max[0], b.p_upper[0] - b.p_max[0]) + 1e-12
    assert abs(a.r_max[0] - b.r_max[0]) <= max(a.r_upper[0] - a.r_max[0], b.r_upper[0] - b.r_max[0]) + 1e-12
    assert 1.4e-3 < a.p_max[0] < 1.6e-3


def test_sensitivity_at_parallel_singularity_raises_naming_the_pose():
    """C, E, D aligned (y = 50 mm at x = 0 for the thesis 5-bar): the passive joints do not
    determine the end-effector."""
    ws = Workspace(("x", "y"), (-20 * MM, 30 * MM), (20 * MM, 70 * MM), ("m", "m"))
    m = MechanismModel(HERE / "fivebar.toml", workspace=ws)
    y = FiveBar().singularity_locus([0.0], 40 * MM, 60 * MM)[0, 1]
    with pytest.raises(KinematicsError, match="parallel singularity"):
        m.sensitivity([[0.0, y]])


def test_unreachable_pose_raises_kinematics_error_naming_it():
    ws = Workspace(("x", "y"), (-20 * MM, 55 * MM), (20 * MM, 150 * MM), ("m", "m"))
    m = MechanismModel(HERE / "fivebar.toml", workspace=ws)
    with pytest.raises(KinematicsError, match=r"0\.14"):
        m.sensitivity([[0.0, 0.14]])


# ---------------------------------------------------------------------------------- IRSBot-2
def test_irsbot2_newton_inverse_geometry_equals_hand_written(irsbot):
    r = IRSBot2()
    poses = MAP_WORKSPACE.latin_hypercube(50, seed=6)
    poses = poses[r.reachable(poses)]
    q, h = irsbot.joint_values(poses), r.dh_values(poses)
    wrap = lambda a: np.abs((a + np.pi) % (2 * np.pi) - np.pi)   # angles equal modulo 2 pi
    assert wrap(q["q1"] - np.pi - h["t1"]).max() < 1e-12 and wrap(q["q2"] - h["t17"]).max() < 1e-12
    for k in ("t7", "t8", "t12", "t13", "t23", "t24", "t28", "t29", "t9", "t10", "t31"):
        assert wrap(q[k] - h[k]).max() < 1e-10, k
    assert irsbot.closure_residual() < 1e-12          # the description's own box, below the singularity


def test_irsbot2_passes_check_robot(irsbot):
    rep = check_robot(irsbot)
    assert rep["fd_relative_mismatch"] < 1e-6


def test_irsbot2_certified_clearance_maxima_equal_hand_written(irsbot):
    """Tab. VI.3 distal clearances: description vs hand-written mechanism, within the certificate gap."""
    pose = [[0.0, -40 * MM]]
    a, b = max_pose_error(irsbot.clearance_mechanism(), pose), max_pose_error(IRSBot2().clearance_mechanism(), pose)
    assert abs(a.p_max[0] - b.p_max[0]) <= max(a.p_upper[0] - a.p_max[0], b.p_upper[0] - b.p_max[0]) + 1e-12
    assert abs(a.r_max[0] - b.r_max[0]) <= max(a.r_upper[0] - a.r_max[0], b.r_upper[0] - b.r_max[0]) + 1e-12


def test_coupled_entry_error_opening_a_parallelogram_is_reported(irsbot):
    """An offset of frame 2's angle alone breaks the parallelogram written with coupled angles:
    no passive joint can close it (over-constrained loop), so the model says so."""
    m = MechanismModel(HERE / "irsbot2.toml", sources=["2.theta"])
    with pytest.raises(KinematicsError, match="2.theta"):
        m.sensitivity([[0.0, -50 * MM]])


# ---------------------------------------------------------------------------------- serial arm
ARM = {
    "name": "2R arm", "planar": True, "lengths": {"l1": 0.4, "l2": 0.3},
    "frame": [{"name": "1", "antecedent": "0", "joint": "revolute", "actuated": True, "theta": "q1"},
              {"name": "2", "antecedent": "1", "joint": "revolute", "actuated": True, "d": "l1", "theta": "q2"},
              {"name": "E", "antecedent": "2", "d": "l2"}],
    "end_effector": {"frame": "E", "coordinates": [{"name": "x", "axis": "x", "low": 0.3, "high": 0.5},
                                                    {"name": "y", "axis": "y", "low": 0.1, "high": 0.3}]},
    "assembly": {"joints": {"q1": 0.0, "q2": 1.2}},
}


def test_serial_2r_arm_sensitivity_is_the_closed_form():
    """x = l1 c1 + l2 c12, y = l1 s1 + l2 s12 (elbow q2 > 0 branch)."""
    m = MechanismModel(mechanism_from_dict(ARM))
    poses = m.workspace.latin_hypercube(20, seed=1)
    q = m.joint_values(poses)
    q1, q2 = q["q1"], q["q2"]
    assert np.all(q2 > 0)
    c1, s1, c12, s12 = np.cos(q1), np.sin(q1), np.cos(q1 + q2), np.sin(q1 + q2)
    assert np.allclose(0.4 * c1 + 0.3 * c12, poses[:, 0], atol=1e-13)
    S = m.sensitivity(poses)             # sources l1, l2, q1, q2
    assert m.source_names == ("l1", "l2", "q1", "q2")
    expect = np.zeros_like(S)
    expect[:, 0] = np.stack([c1, c12, -0.4 * s1 - 0.3 * s12, -0.3 * s12], 1)
    expect[:, 1] = np.stack([s1, s12, 0.4 * c1 + 0.3 * c12, 0.3 * c12], 1)
    expect[:, 5] = np.stack([0 * c1, 0 * c1, 1 + 0 * c1, 1 + 0 * c1], 1)
    assert np.abs(S - expect).max() < 1e-13


# ---------------------------------------------------------------------------------- schema
def _arm(**change):
    import copy
    d = copy.deepcopy(ARM)
    d.update(change)
    return d


@pytest.mark.parametrize("spec, field", [
    (_arm(colour="red"), "mechanism.colour"),
    (_arm(frame=[{"name": "1", "antecedent": "9", "joint": "revolute", "theta": "q1"}]), "antecedent"),
    (_arm(frame=[{"name": "1", "antecedent": "0", "joint": "ball", "theta": "q1"}]), "joint"),
    (_arm(frame=[{"name": "1", "antecedent": "0", "joint": "revolute", "theta": "__import__('os')"}]), "theta"),
    (_arm(frame=[{"name": "1", "antecedent": "0", "joint": "revolute", "thetta": "q1"}]), "frame[0].thetta"),
])
def test_schema_errors_name_the_field(spec, field):
    with pytest.raises(ValidationError, match=field.replace(".", r"\.").replace("[", r"\[").replace("]", r"\]")):
        mechanism_from_dict(spec)


def test_loop_without_actuated_joint_is_rejected():
    spec = _arm(frame=ARM["frame"] + [{"name": "3", "antecedent": "0", "joint": "revolute", "theta": "q3"},
                                      {"name": "4", "antecedent": "3", "d": 0.5}],
                loop=[{"frames": ["4", "E"]}], planar=True)
    spec["frame"][0] = {**spec["frame"][0], "actuated": False}
    spec["frame"][1] = {**spec["frame"][1], "actuated": False}
    with pytest.raises(ValidationError, match="actuated joint"):
        MechanismModel(mechanism_from_dict(spec))


def test_loop_that_cannot_close_is_reported_at_the_assembly_pose():
    spec = _arm(frame=ARM["frame"] + [{"name": "3", "antecedent": "0", "d": 5.0}], loop=[{"frames": ["3", "E"]}])
    with pytest.raises(KinematicsError, match="assembly pose"):
        MechanismModel(mechanism_from_dict(spec)).sensitivity([[0.4, 0.2]])


def test_source_patterns_and_their_errors(fivebar):
    m = load_mechanism(HERE / "fivebar.toml")
    assert m.select_sources(["*.d"])[:2] == ["A.d", "C.d"]
    assert m.select_sources(["L?"]) == ["L0", "L1", "L2", "L3", "L4", "L5"]
    with pytest.raises(ValidationError, match="Q9"):
        m.select_sources(["Q9"])
    with pytest.raises(ValidationError, match="C.alpha"):
        MechanismModel(HERE / "fivebar.toml", sources=["C.alpha"])   # out of plane in a planar mechanism


def test_description_model_works_with_allocators_and_monte_carlo(fivebar):
    """allocate_optimum on the description-driven 5-bar equals it on the hand-written model; the
    nonlinear Monte Carlo runs through the description's pose_error."""
    from evotol.cost_models import ExponentialCost
    from evotol.allocators import allocate_optimum
    from evotol.verification.montecarlo import verify
    from evotol.core.problem import Requirement, Tolerance, ToleranceProblem

    poses = fivebar.workspace.grid(3)
    tol = {s.name: Tolerance(ExponentialCost(1.0, 0.5, scale=1e-5), lower=1e-7, upper=1e-3) for s in fivebar.sources}
    req = Requirement(position=50e-6)
    a = allocate_optimum(ToleranceProblem(fivebar, tol, req, poses))
    b = allocate_optimum(ToleranceProblem(FiveBarGeometric(), tol, req, poses))
    assert abs(a.cost - b.cost) <= 1e-6 * b.cost
    mc = verify(ToleranceProblem(fivebar, tol, req, poses), a.tolerances, n_samples=50)
    assert mc.to_dict()["max_exceed_rate"] <= 0.05


def test_reproduce_mechanisms_fields_quick(tmp_path):
    """`evotol reproduce mechanisms`: the fields issue 12 lists, FD agreement and hand-written equality."""
    from evotol.studies import get
    from evotol.studies.mechanisms import compute

    study = get("mechanisms")
    res = compute(study.make_config(quick=True, map_grid=2))
    m = res.summary["mechanisms"]
    assert {"5-bar", "IRSBot-2"} <= set(m)
    from evotol.units import numbers_without_unit

    assert numbers_without_unit(res.summary, study.units_block()) == []  # docs/units.md (issue 15)
    for e in m.values():
        assert {"fd_rel_error", "builtin_rel_diff", "n_sources", "seconds"} <= set(e)
        assert e["fd_rel_error"] < 1e-6
    for name in ("5-bar", "IRSBot-2", "3-UCR", "Delta"):
        assert m[name]["builtin_rel_diff"] < 1e-9, name
    for arm, ranks in {"UR5": (36, 26, 30), "Panda": (42, 30, 34)}.items():    # issue 23 item 7
        e, c = m[arm], m[arm]["configurations"]
        assert e["n_sources"] == ranks[0] and e["rank"] == e["pinocchio_rank"]
        assert (c["rank"], c["rank_with_tip"]) == ranks[1:] == (c["pinocchio_rank"], c["pinocchio_rank_with_tip"])
        assert c["fd_rel_error"] < 1e-6 and c["fk_vs_pinocchio"] < 1e-12
    fb = m["5-bar"]
    assert fb["p_max_mm"] <= fb["p_upper_mm"] <= fb["p_max_mm"] * (1 + 1e-3)
    assert fb["r_max_rad"] <= fb["r_upper_rad"] <= fb["r_max_rad"] * (1 + 1e-3)


def test_check_mechanism_command_prints_sources_and_fd(capsys):
    from evotol.cli import main

    assert main(["check-mechanism", "fivebar", "--poses", "4"]) == 0
    out = capsys.readouterr().out
    assert "theta1" in out and "finite differences" in out and "loop-closure residual" in out


def test_study_file_with_a_description_runs_end_to_end(tmp_path):
    """docs/mechanisms.md tutorial: a study file naming a description file, no Python."""
    import json

    from evotol.studyfile import run_study_file

    (tmp_path / "my_3rrr.toml").write_text((HERE / "planar3rrr.toml").read_text())
    (tmp_path / "study.toml").write_text('''name = "t3rrr"
[robot]
mechanism = "my_3rrr.toml"
sources = ["l1_*", "q?"]
[poses]
grid = [2, 2, 1]
[requirement]
position = 1e-4
[cost.default]
model = "exponential"
a0 = 1.9
a1 = 0.5
scale = 1e-5
[methods]
sensitivity = {}
optimum = {}
[verify]
n_samples = 20
''')
    summary = run_study_file(tmp_path / "study.toml", out=tmp_path)
    data = json.loads(Path(summary["json"]).read_text())
    assert set(data["results"]["optimum"]["tolerances"]) == {"l1_1", "l1_2", "l1_3", "q1", "q2", "q3"}
    assert data["results"]["optimum"]["cost"] <= data["results"]["sensitivity"]["cost"] * (1 + 1e-9)
    assert data["monte_carlo"]["optimum"]["max_exceed_rate"] <= 0.1


# ---------------------------------------------------------------------------------- 3-UCR
def test_ucr3_description_equals_hand_written_all_21_columns_at_50_poses():
    """Yao 2013 3-UCR ('verified' J_x of eq. 10): the description gives every column of the
    hand-written map, column for column as :data:`evotol.robots.ucr3.DESCRIPTION_COLUMNS` pairs them (all
    21 used once)."""
    from evotol.robots.ucr3 import DESCRIPTION_COLUMNS, UCR3, columns_from_description

    m = MechanismModel(HERE / "ucr3.toml")
    r = UCR3()
    poses = r.workspace.latin_hypercube(50, seed=1)
    S, H = m.sensitivity(poses), r.sensitivity(poses)
    assert len({c for c, _ in DESCRIPTION_COLUMNS}) == 21 == H.shape[2]
    D = columns_from_description(S, m.source_names)
    assert np.abs(D - H).max() <= 1e-9 * np.abs(H).max()
    assert check_robot(m)["fd_relative_mismatch"] < 1e-6


# ---------------------------------------------------------------------------------- Delta
def test_delta_description_equals_hand_written_for_all_47_parameters():
    """Brahmia 2023 Delta: the description (both parallelogram rods of Tab. 1, the parallelogram
    relations as coupled angles, each leg closed at the midpoint of its rods -- a [[point]] --, legs
    meeting at the platform centre, eq. 3) gives the same position rows as robots/delta.py for all
    47 parameters of eq. (12) at 50 poses, and the same nonlinear closure with errors."""
    from evotol.studies.mechanisms import delta_columns
    from evotol.robots.delta import DeltaRobot

    m = MechanismModel(HERE / "delta.toml")
    r = DeltaRobot()
    cols = delta_columns(m, r)
    assert sorted(cols) == list(range(47))
    poses = r.workspace.latin_hypercube(50, seed=1)
    S, H = m.sensitivity(poses), r.sensitivity(poses)
    assert np.abs(S[:, :3] - H[:, :3, cols]).max() <= 1e-9 * np.abs(H[:, :3]).max()
    # dq2 (offset of the free passive joint 2) is absorbed and the bar half-width d keeps the
    # parallelogram one, to first order, in both models; the rod-2 twist alpha6 does act
    zero = [c for c, n in enumerate(m.source_names) if n.startswith(("dq2", "d_"))]
    assert np.abs(S[:, :3, zero]).max() <= 1e-12 * np.abs(H[:, :3]).max()
    assert np.abs(S[:, :3, m.source_names.index("alpha6_1")]).max() > 1e-4 * np.abs(H[:, :3]).max()
    E = np.random.default_rng(0).uniform(-1e-3, 1e-3, (10, 4, 47))
    Eh = np.zeros_like(E)
    Eh[..., cols] = E
    a, b = m.pose_error(poses[:10], E)[..., :3], r.pose_error(poses[:10], Eh)[..., :3]
    assert np.abs(a - b).max() <= 1e-9 * np.abs(b).max()
    assert check_robot(m)["fd_relative_mismatch"] < 1e-6


def test_point_is_the_mean_of_its_frames_and_is_checked():
    """A [[point]]'s position and motion are the means of its frames'; bad points are refused by name."""
    import copy
    import tomllib

    m = MechanismModel(HERE / "delta.toml")
    kin = m.kin
    poses = m.workspace.latin_hypercube(5, seed=3)
    q = kin.inverse_geometry(poses)
    st = kin.state(q, len(poses), wrt=kin.passive)
    assert np.allclose(st.world["P2"][:, :3, 3], (st.world["E2"][:, :3, 3] + st.world["Eb2"][:, :3, 3]) / 2, atol=1e-15)
    J = kin.frame_jacobian(st, "P2", kin.passive)
    Ja, Jb = kin.frame_jacobian(st, "E2", kin.passive), kin.frame_jacobian(st, "Eb2", kin.passive)
    assert np.allclose(J[:, :3], (Ja[:, :3] + Jb[:, :3]) / 2, atol=1e-15)
    spec = tomllib.loads((HERE / "delta.toml").read_text())
    for change, field in ((lambda s: s["point"][0].update(mean_of=["E1", "nowhere"]), "point 'P1'.mean_of"),
                          (lambda s: s["point"][0].update(mean_of=["E1"]), "point 'P1'.mean_of"),
                          (lambda s: s["point"][1].update(name="P1"), "point.name"),
                          (lambda s: s["loop"][0].update(components="all"), "loop P2-P1.components"),
                          (lambda s: s["end_effector"].update(orientation=[["z", "0"]]), "end_effector.orientation"),
                          (lambda s: s["point"][0].update(weights=[1, 1]), "point[0].weights")):
        bad = copy.deepcopy(spec)
        change(bad)
        with pytest.raises(ValidationError) as exc:
            mechanism_from_dict(bad)
        assert field in str(exc.value)
