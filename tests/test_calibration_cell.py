"""A calibration plan respects the cell (issue 44 item 4): no configuration puts a joint origin or the flange
below the floor (default: the mounting plane z = 0) or inside a stated obstacle box.

Independent check: the joint origins and tool0 of every configuration by Pinocchio's forward kinematics of the
UR5 URDF (not evotol's kinematics)."""
from __future__ import annotations

import tomllib
from pathlib import Path

import numpy as np
import pytest
from scipy.stats import qmc

from evotol.calibration import CalibrationPlan
from evotol.calibration.configurations import calibration_joints
from evotol.calibration.table import plan_from_table
from evotol.errors import ValidationError
from evotol.robots.mechanism.urdf.reader import resolve_urdf
from evotol.studyfile import load_problem

pin = pytest.importorskip("pinocchio")
ROOT = Path(__file__).resolve().parents[1]


@pytest.fixture(scope="module")
def ur5():
    spec = tomllib.loads((ROOT / "reports/studies/ur5_urdf.toml").read_text())
    return load_problem(spec, base_dir=ROOT / "reports/studies").robot


@pytest.fixture(scope="module")
def origins():
    """(n, 7, 3) heights of the six joint origins and tool0 per configuration, by Pinocchio."""
    model = pin.buildModelFromUrdf(str(resolve_urdf("example-robot-data:ur_description/urdf/ur5_robot.urdf")))
    data = model.createData()
    tool = model.getFrameId("tool0")

    def f(Q):
        out = []
        for q in Q:
            pin.framesForwardKinematics(model, data, np.asarray(q, float))
            out.append([data.oMi[j].translation.copy() for j in range(1, model.njoints)] + [data.oMf[tool].translation.copy()])
        return np.array(out)
    return f


def test_joint_space_plan_stays_above_the_floor(ur5, origins):
    """The example's 40 configurations over the joint limits: the Latin hypercube alone puts 20 of them below the
    mounting plane (an elbow or a wrist under the base); the plan keeps its 20 admissible ones and draws the rest,
    and Pinocchio finds none below z = 0. With floor = none the plan is the hypercube, as before."""
    plan = CalibrationPlan(count=40, over="joints", noise="20 um", seed=0)
    lo = np.array([ur5.mechanism.limits[v][0] for v in ur5.kin.variables])
    hi = np.array([ur5.mechanism.limits[v][1] for v in ur5.kin.variables])
    raw = lo + qmc.LatinHypercube(d=6, seed=0).random(40) * (hi - lo)
    below_raw = (origins(raw)[:, :, 2] < 0).any(axis=1)
    assert below_raw.sum() == 20
    Q = calibration_joints(ur5, plan)
    assert Q.shape == (40, 6) and not (origins(Q)[:, :, 2] < 0).any()
    assert np.allclose(Q[:20], raw[~below_raw])                 # the admissible ones of the first draw, in order
    assert np.allclose(calibration_joints(ur5, CalibrationPlan(count=40, over="joints", noise="20 um", floor="none")), raw)
    high = calibration_joints(ur5, CalibrationPlan(count=10, over="joints", noise="20 um", floor="50 mm"))
    assert (origins(high)[:, :, 2] >= 0.05 - 1e-9).all()
    with pytest.raises(ValidationError, match=r"^calibration.floor = 0.1: expected a cell in which 10 configurations"):
        calibration_joints(ur5, CalibrationPlan(count=10, over="joints", noise="20 um", floor="100 mm"))  # shoulder at 89 mm


def test_obstacle_box_is_avoided(ur5, origins):
    box = {"min": [0.3, -1.0, 0.0], "max": [1.0, 1.0, 1.0]}           # a table in front of the arm, x > 0.3 m
    Q = calibration_joints(ur5, CalibrationPlan(count=12, over="joints", noise="20 um", obstacles=[box]))
    P = origins(Q)
    inside = np.all((P >= box["min"]) & (P <= box["max"]), axis=2)
    assert not inside.any() and not (P[:, :, 2] < 0).any()


def test_given_configuration_below_the_floor_is_refused_in_one_line(ur5):
    down = [0.0, 0.5, 1.0, 0.0, 0.0, 0.0]                              # shoulder lifted below the base
    with pytest.raises(ValidationError, match=r"^calibration\.joints\[1\] = .*: expected a configuration inside the cell "
                                              r"\(\w+ at z = -[\d.]+ m is below the floor z = 0 m\)$"):
        calibration_joints(ur5, CalibrationPlan(joints=[[0, -1.2, 1.6, -1.9, -1.57, 0], down], noise="20 um"))


@pytest.mark.parametrize("table, words", [({"floor": True}, "calibration.floor = True"),
                                          ({"floor": "3 kg"}, "calibration.floor"),
                                          ({"obstacles": [{"min": [0, 0, 0], "max": [1, 1]}]}, r"calibration.obstacles\[0\]"),
                                          ({"obstacles": [{"min": [0, 0, 1], "max": [1, 1, 0]}]}, "min < max")])
def test_bad_cell_keys(table, words):
    with pytest.raises(ValidationError, match=words) as exc:
        plan_from_table({"count": 4, "noise": "20 um", **table})
    assert "\n" not in str(exc.value)
