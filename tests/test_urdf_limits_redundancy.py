"""Joint limits (issue 23 item 3) and redundancy resolution (item 4) of URDF arms.

Independent checks: the URDF's own ``<limit>`` numbers (Pinocchio's ``lowerPositionLimit``); for the
redundant Panda, the posture nearest to the assembly posture found by a general constrained
optimiser (scipy SLSQP on Pinocchio's forward kinematics) and Pinocchio's placement regressor there.
"""
from pathlib import Path

import numpy as np
import pytest
import tomllib

from evotol.errors import KinematicsError, ValidationError
from evotol.robots.mechanism import MechanismModel, mechanism_from_dict

HERE = Path(__file__).resolve().parents[1] / "robots" / "mechanisms"


def ur5_spec(**changes):
    spec = tomllib.loads((HERE / "ur5.toml").read_text())
    spec.update(changes)
    return spec


def test_limits_are_read_from_the_urdf():
    import pinocchio as pin

    from evotol.robots.mechanism.urdf.reader import resolve_urdf

    robot = MechanismModel(HERE / "panda.toml")
    model = pin.buildModelFromUrdf(str(resolve_urdf("example-robot-data:panda_description/urdf/panda.urdf")))
    for j in range(1, 8):
        name = f"panda_joint{j}"
        jid = model.getJointId(name)
        lo, hi = model.lowerPositionLimit[model.idx_qs[jid]], model.upperPositionLimit[model.idx_qs[jid]]
        assert robot.mechanism.limits[name] == pytest.approx((lo, hi), abs=0)
    assert robot.mechanism.limits["panda_joint4"][1] < 0          # the elbow only bends one way


def test_a_pose_outside_a_joint_range_names_the_pose_and_the_joint():
    """[limits] overrides the URDF: with the base joint in [-0.5, 0] rad the arm reaches (400, 0,
    300) mm (pan -0.28 rad) but not (300, -100, 200) mm (pan -0.67 rad; the shoulder offset of the
    UR5 shifts both from atan2(y, x))."""
    robot = MechanismModel(mechanism_from_dict(ur5_spec(limits={"shoulder_pan_joint": [-0.5, 0.0]}), str(HERE / "ur5.toml")))
    assert robot.mechanism.limits["shoulder_pan_joint"] == (-0.5, 0.0)
    assert robot.mechanism.limits["elbow_joint"] == pytest.approx((-np.pi, np.pi))      # the URDF's
    robot.joint_values(np.array([[0.4, 0.0, 0.3], [0.3, 0.1, 0.2]]))                      # inside: fine
    with pytest.raises(KinematicsError, match=r"pose \[0\.3, -0\.1, 0\.2\].*joint shoulder_pan_joint = -0\.67.*outside its limits \[-0\.5, 0\]"):
        robot.joint_values(np.array([[0.4, 0.0, 0.3], [0.3, -0.1, 0.2]]))


def test_assembly_outside_the_limits_and_unknown_limit_names_are_errors():
    with pytest.raises(KinematicsError, match=r"assembly pose .* joint elbow_joint = 2\.08.* outside its limits \[0, 1\]"):
        MechanismModel(mechanism_from_dict(ur5_spec(limits={"elbow_joint": [0, 1]}), str(HERE / "ur5.toml"))).kin.assembly()
    with pytest.raises(ValidationError, match="limits.elbow"):
        MechanismModel(mechanism_from_dict(ur5_spec(limits={"elbow": [0, 1]}), str(HERE / "ur5.toml")))
    with pytest.raises(ValidationError, match="limits.elbow_joint"):
        mechanism_from_dict(ur5_spec(limits={"elbow_joint": [1, 0]}), str(HERE / "ur5.toml"))


@pytest.fixture(scope="module")
def panda():
    return MechanismModel(HERE / "panda.toml")


def test_redundant_panda_posture_is_the_one_nearest_the_assembly_posture(panda):
    """7 joints, 6-D task: the inverse geometry returns the configuration nearest (Euclidean, rad)
    to the assembly posture that reaches the pose. Checked two ways: the first-order condition
    (q - q_asm has no component along the self-motion, the null space of the task Jacobian), and
    scipy's SLSQP minimising |q - q_asm|^2 subject to Pinocchio's forward kinematics = the pose,
    started elsewhere on the self-motion. Then the sensitivities there equal Pinocchio's placement
    regressor at SLSQP's posture."""
    import pinocchio as pin
    from scipy.optimize import minimize

    from evotol.robots.mechanism.urdf.reader import frame_id, resolve_urdf
    from evotol.robots.mechanism.urdf.reader import pinocchio_placement_regressor

    poses = panda.workspace.latin_hypercube(5, seed=3)
    q = panda.joint_values(poses)
    names = panda.kin.variables
    Q = np.stack([q[v] for v in names], 1)
    _, qa = panda.kin.assembly()
    qa = np.array([qa[v] for v in names])
    model = pin.buildModelFromUrdf(str(resolve_urdf("example-robot-data:panda_description/urdf/panda.urdf")))
    data = model.createData()
    fid = frame_id(model, "panda_hand_tcp")

    def full(x):
        return np.concatenate([x, np.zeros(model.nq - 7)])

    def pose_residual(x, target):
        pin.framesForwardKinematics(model, data, full(x))
        M = data.oMf[fid]
        return np.concatenate([M.translation - target[:3], pin.log3(M.rotation @ np.diag([1.0, -1.0, -1.0]).T)])

    for i, (x, qi) in enumerate(zip(poses, Q)):
        pin.computeJointJacobians(model, data, full(qi))
        pin.framesForwardKinematics(model, data, full(qi))
        J = pin.getFrameJacobian(model, data, fid, pin.LOCAL_WORLD_ALIGNED)[:, :7]
        null = np.linalg.svd(J)[2][-1]                                     # the self-motion direction
        assert abs(null @ (qi - qa)) < 1e-9 * max(np.linalg.norm(qi - qa), 1.0)
        start = qi + 0.3 * null                                            # elsewhere on (near) the self-motion
        sol = minimize(lambda z: np.sum((z - qa) ** 2), start, jac=lambda z: 2 * (z - qa), method="SLSQP",
                       constraints=[{"type": "eq", "fun": pose_residual, "args": (x,)}], options={"ftol": 1e-15, "maxiter": 500})
        assert np.abs(pose_residual(sol.x, x)).max() < 1e-9
        assert np.abs(sol.x - qi).max() < 1e-6, (i, sol.x - qi)
    S = MechanismModel(HERE / "panda.toml", sources=[f"panda_joint{j}.{k}" for j in range(1, 8) for k in
                                                     ("shift_x", "shift_y", "shift_z", "tilt_x", "tilt_y", "tilt_z")]).sensitivity(poses)
    R = pinocchio_placement_regressor(model, fid, np.hstack([Q, np.zeros((len(Q), model.nq - 7))]))[:, :, :42]
    assert np.abs(S - R).max() < 1e-12


def test_panda_sources_match_fd_and_span_pinocchio(panda):
    from evotol.robots.base import check_robot
    from evotol.robots.mechanism.urdf.check import check_urdf_chain

    rep = check_robot(panda, panda.workspace.latin_hypercube(4, seed=1))
    assert rep["fd_relative_mismatch"] < 1e-6
    r = check_urdf_chain(panda, n=40)
    assert r["rank"] == r["pinocchio_rank"] == r["combined_rank"]
    assert r["rank_with_tip"] == r["pinocchio_rank_with_tip"] == r["combined_rank_with_tip"]


def test_the_report_states_the_redundancy_resolution(panda, tmp_path):
    """check-mechanism, the mechanisms study and an `evotol run` report say which posture was used."""
    import json

    from evotol.studyfile import run_study_file

    r = panda.redundancy
    assert (r["joint_variables"], r["task_equations"], r["resolution"]) == (7, 6, "nearest to the assembly posture")
    assert MechanismModel(HERE / "ur5.toml").redundancy is None
    (tmp_path / "s.toml").write_text('''name = "panda_small"
[robot]
mechanism = "panda"
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
optimum = {}
[verify]
n_samples = 10
''')
    summary = run_study_file(tmp_path / "s.toml", out=tmp_path)
    data = json.loads(Path(summary["json"]).read_text())
    assert data["notes"] == [r["text"]] and "nearest to the assembly posture" in r["text"]
    assert "nearest to the assembly posture" in Path(summary["html"]).read_text()


def test_random_joint_values_keep_each_joint_in_its_own_units():
    """The configurations of the URDF check: a revolute joint without limits is drawn from
    [-pi, pi] rad, one with limits from its limits within [-pi, pi]; a prismatic joint without
    limits from [-0.1, 0.1] m (it was drawn from [-pi, pi] *metres*), one with limits from them."""
    from evotol.robots.mechanism.urdf.check import UNLIMITED_PRISMATIC, random_joints

    limits = {"r_lim": (-0.5, 4.0), "p_lim": (0.0, 0.5)}
    units = {"p_free": "m", "p_lim": "m"}
    q = random_joints(["r_free", "r_lim", "p_free", "p_lim"], limits, 4000, seed=1, units=units)
    span = {k: (v.min(), v.max()) for k, v in q.items()}
    for name, (lo, hi) in {"r_free": (-np.pi, np.pi), "r_lim": (-0.5, np.pi),
                           "p_free": (-UNLIMITED_PRISMATIC, UNLIMITED_PRISMATIC), "p_lim": (0.0, 0.5)}.items():
        assert lo <= span[name][0] < lo + 0.01 * (hi - lo) and hi - 0.01 * (hi - lo) < span[name][1] <= hi, (name, span[name])
