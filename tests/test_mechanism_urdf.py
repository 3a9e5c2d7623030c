"""Serial arms from URDF (issue 12 item 7): the UR5 of example-robot-data read with Pinocchio.

Independent checks: Pinocchio's own forward kinematics (1e-12), central finite differences of the
nonlinear model (check_robot), the description's inverse geometry closing on the task pose.
"""
from pathlib import Path

import numpy as np
import pytest

from evotol.errors import ValidationError
from evotol.robots.base import check_robot
from evotol.robots.mechanism import MechanismModel, mechanism_from_dict
from evotol.robots.mechanism.kinematics.placement import PLACEMENT_FIELDS
from evotol.robots.mechanism.urdf.reader import pinocchio_tip_pose, resolve_urdf

HERE = Path(__file__).resolve().parents[1] / "robots" / "mechanisms"
UR5 = "example-robot-data:ur_description/urdf/ur5_robot.urdf"


@pytest.fixture(scope="module")
def ur5():
    return MechanismModel(HERE / "ur5.toml")


def test_forward_kinematics_equals_pinocchio_1e_12(ur5):
    rng = np.random.default_rng(0)
    Q = rng.uniform(-np.pi, np.pi, (50, 6))
    kin = ur5.kin
    T = kin.state({v: Q[:, i] for i, v in enumerate(kin.variables)}, 50, twists=False).world[ur5.mechanism.end_effector]
    P = pinocchio_tip_pose(resolve_urdf(UR5), "tool0", Q)
    assert np.abs(T - P).max() < 1e-12


def test_ur5_default_sources_are_placement_twists_and_joint_offsets(ur5):
    """Per joint: the six placement errors of its origin less the one its joint offset duplicates
    (the rotation about its own axis: y for the lift/elbow/wrist-1/wrist-3 joints, z for pan and
    wrist 2), plus the joint offset."""
    names = ur5.source_names
    assert len(names) == 36
    assert {"shoulder_lift_joint.tilt_x", "shoulder_lift_joint.tilt_z", "shoulder_pan_joint.tilt_y", "elbow_joint"} <= set(names)
    assert not {"shoulder_lift_joint.tilt_y", "shoulder_pan_joint.tilt_z"} & set(names)
    assert {s.group for s in ur5.sources} == {"length", "angle", "actuator"}


def test_ur5_inverse_geometry_reaches_the_task_box_and_matches_fd(ur5):
    poses = ur5.workspace.latin_hypercube(6, seed=2)
    assert ur5.closure_residual(poses) < 1e-12
    rep = check_robot(ur5, poses)
    assert rep["fd_relative_mismatch"] < 1e-6
    # encoder offset of the base joint moves the tool tangentially by r * dq (closed form)
    S = ur5.sensitivity(poses)
    j = ur5.source_names.index("shoulder_pan_joint")
    r = np.hypot(poses[:, 0], poses[:, 1])
    assert np.allclose(np.linalg.norm(S[:, :3, j], axis=1), r, rtol=1e-12)


def test_urdf_errors_name_the_field(tmp_path):
    with pytest.raises(ValidationError, match="tip"):
        mechanism_from_dict({"urdf": UR5, "tip": "no_such_link",
                             "end_effector": {"coordinates": [{"name": "x", "axis": "x", "low": 0.3, "high": 0.5}]}})
    with pytest.raises(ValidationError, match="urdf"):
        mechanism_from_dict({"urdf": str(tmp_path / "missing.urdf"), "tip": "tool0",
                             "end_effector": {"coordinates": [{"name": "x", "axis": "x", "low": 0.3, "high": 0.5}]}})


def test_study_file_with_urdf_in_the_robot_table(tmp_path):
    """[robot] urdf = ... with the description inline: evotol run end to end on the UR5."""
    import json

    from evotol.studyfile import run_study_file

    (tmp_path / "study.toml").write_text(f'''name = "ur5_inline"
[robot]
urdf = "{UR5}"
tip = "tool0"
sources = ["elbow_joint_z", "wrist_1_joint_z", "shoulder_lift_joint", "elbow_joint"]
[robot.end_effector]
coordinates = [
  {{ name = "x", axis = "x", low = 0.35, high = 0.45 }},
  {{ name = "y", axis = "y", low = -0.05, high = 0.05 }},
  {{ name = "z", axis = "z", low = 0.25, high = 0.35 }},
]
orientation = [["x", "pi"]]
[robot.assembly]
pose = [0.4, 0.0, 0.3]
joints = {{ shoulder_lift_joint = -1.2, elbow_joint = 1.6, wrist_1_joint = -1.9, wrist_2_joint = -1.57 }}
[poses]
grid = [2, 2, 2]
[requirement]
position = 5e-4
[cost.default]
model = "exponential"
a0 = 1.9
a1 = 0.5
scale = 1e-5
[methods]
optimum = {{}}
[verify]
n_samples = 10
''')
    summary = run_study_file(tmp_path / "study.toml", out=tmp_path)
    data = json.loads(Path(summary["json"]).read_text())
    opt = data["results"]["optimum"]
    assert set(opt["tolerances"]) == {"elbow_joint_z", "wrist_1_joint_z", "shoulder_lift_joint", "elbow_joint"}
    assert opt["feasible"]


# ---------------------------------------------------------------------------- placement twists (issue 23 item 1)
JOINTS = ["shoulder_pan_joint", "shoulder_lift_joint", "elbow_joint", "wrist_1_joint", "wrist_2_joint", "wrist_3_joint"]


def pinocchio_placement_regressor(path, tip, Q):
    """Pinocchio's joint placement regressor of the tip frame (LOCAL_WORLD_ALIGNED), (n, 6, 6 n_joints),
    then the tip frame's own placement twist (6 columns: [R 0; 0 R] in the same reference)."""
    import pinocchio as pin

    model = pin.buildModelFromUrdf(str(path))
    data = model.createData()
    fid = model.getFrameId(tip)
    out = []
    for q in Q:
        pin.framesForwardKinematics(model, data, q)
        R = data.oMf[fid].rotation
        tool = np.zeros((6, 6))
        tool[:3, :3] = tool[3:, 3:] = R
        out.append(np.hstack([pin.computeFrameKinematicRegressor(model, data, fid, pin.LOCAL_WORLD_ALIGNED), tool]))
    return np.array(out)


def stacked_rank(S):
    from evotol.robots.mechanism.model.identifiability import stacked_rank as rank

    return rank(S)


@pytest.fixture(scope="module")
def ur5_all_twists():
    return MechanismModel(HERE / "ur5.toml", sources=[f"{j}.{k}" for j in JOINTS + ["tool0"] for k in PLACEMENT_FIELDS])


def test_placement_columns_equal_pinocchio_regressor_and_fd(ur5_all_twists):
    """Every placement column (6 joints + tool0) equals Pinocchio's computeFrameKinematicRegressor
    column (M_i exp(delta), delta = [v; omega] local) to 1e-12, and central FD of the nonlinear
    model (the perturbed placement M exp(delta)) to 1e-6."""
    m = ur5_all_twists
    Q = np.random.default_rng(3).uniform(-np.pi, np.pi, (40, 6))
    S = m.sensitivity_at_joints(Q)
    R = pinocchio_placement_regressor(resolve_urdf(UR5), "tool0", Q)
    assert np.abs(S - R).max() < 1e-12
    rep = check_robot(m, m.workspace.latin_hypercube(5, seed=4))
    assert rep["n_columns"] == 42 and rep["fd_relative_mismatch"] < 1e-6


def test_ur5_sources_span_pinocchio_placement_space_26_and_30(ur5, ur5_all_twists):
    """Stacked over 200 random configurations: the default sources (5 twists + offset per joint)
    span rank 26, the same space as Pinocchio's 36 joint placement columns (rank of both together
    also 26); with tool0's six twists, 30. The old roll/pitch/yaw parameters span only 24 (roll and
    yaw of the pitch = pi/2 origins are exact negatives)."""
    Q = np.random.default_rng(0).uniform(-np.pi, np.pi, (200, 6))
    R = pinocchio_placement_regressor(resolve_urdf(UR5), "tool0", Q)
    S = ur5.sensitivity_at_joints(Q)
    assert stacked_rank(R[:, :, :36]) == stacked_rank(S) == stacked_rank(np.concatenate([S, R[:, :, :36]], 2)) == 26
    T = ur5_all_twists.sensitivity_at_joints(Q)
    assert stacked_rank(R) == stacked_rank(T) == stacked_rank(np.concatenate([S, T, R], 2)) == 30
    old = MechanismModel(HERE / "ur5.toml", sources=[f"{j}_{k}" for j in JOINTS for k in ("x", "y", "z", "roll", "pitch", "yaw")] + JOINTS)
    So = old.sensitivity_at_joints(Q)
    assert stacked_rank(So) == 24
    i, k = old.source_names.index("shoulder_lift_joint_roll"), old.source_names.index("shoulder_lift_joint_yaw")
    assert np.allclose(So[..., i], -So[..., k], atol=1e-10)


def test_placement_errors_of_a_dh_row_equal_its_entries():
    """Closed form in a TOML description (3-UCR, a closed loop): for a joint row with d = 0 the
    placement (the frame before Rot(z, theta) Trans(z, r)) tilts about x as the row's alpha, shifts
    along x and z as its d and r; a fixed row's placement is the frame itself, whose tilt about z is
    its theta -- at every pose."""
    pairs = [("R1.tilt_x", "R1.alpha"), ("U1b.shift_x", "U1b.d"), ("C1.shift_z", "C1.r"), ("P1.tilt_z", "P1.theta")]
    m = MechanismModel(HERE / "ucr3.toml", sources=[x for p in pairs for x in p] + ["P1.shift_y", "C1r.tilt_y"])
    S = m.sensitivity(m.workspace.latin_hypercube(8, seed=1))
    for c in range(0, 8, 2):
        assert np.abs(S[..., c + 1]).max() > 0.1
        assert np.abs(S[..., c] - S[..., c + 1]).max() < 1e-12 * np.abs(S[..., c + 1]).max()
    rep = check_robot(m, m.workspace.latin_hypercube(4, seed=2))
    assert rep["fd_relative_mismatch"] < 1e-6
