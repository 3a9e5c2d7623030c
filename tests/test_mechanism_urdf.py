"""Serial arms from URDF (issue 12 item 7): the UR5 of example-robot-data read with Pinocchio.

Independent checks: Pinocchio's own forward kinematics (1e-12), central finite differences of the
nonlinear model (check_robot), the description's inverse geometry closing on the task pose.
"""
from pathlib import Path

import numpy as np
import pytest

from evotol.errors import ValidationError
from robots.base import check_robot
from robots.mechanism import MechanismModel, mechanism_from_dict
from robots.mechanism.urdf import pinocchio_tip_pose, resolve_urdf

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


def test_ur5_sources_are_link_lengths_link_angles_and_encoders(ur5):
    names = ur5.source_names
    assert len(names) == 42
    assert {"shoulder_lift_joint_y", "elbow_joint_z", "wrist_1_joint_pitch", "elbow_joint"} <= set(names)
    groups = {s.group for s in ur5.sources}
    assert groups == {"length", "angle", "actuator"}


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
