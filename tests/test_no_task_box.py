"""A serial arm described without a task box (issue 39 item 4): poses as joint configurations and
``check-mechanism --at`` need none; a task-pose grid over a box nobody stated is refused, and a
closed-loop mechanism still needs its task coordinates.

References: the textbook standard-DH product written out in this file (Corke's PUMA 560 table), and
the same study run on the shipped description that does state a box.
"""
from __future__ import annotations

import copy
import subprocess
import sys
import tomllib
from pathlib import Path

import numpy as np
import pytest

from evotol.allocators import allocate_optimum
from evotol.errors import ValidationError
from evotol.robots.mechanism import MechanismModel
from evotol.robots.mechanism.kinematics.forward_at import forward_at
from evotol.studyfile.problem import load_problem

ROOT = Path(__file__).resolve().parents[1]
PUMA = ROOT / "robots" / "mechanisms" / "puma560.toml"
#: Corke's PUMA 560 standard-DH table: (a, alpha, d) per joint, m and rad
DH = [(0.0, np.pi / 2, 0.0), (0.4318, 0.0, 0.0), (0.0203, -np.pi / 2, 0.15005),
      (0.0, np.pi / 2, 0.4318), (0.0, -np.pi / 2, 0.0), (0.0, 0.0, 0.0)]


def dh_position(q):
    """The flange position by the textbook product Rz(theta) Tz(d) Tx(a) Rx(alpha), m."""
    T = np.eye(4)
    for (a, al, d), th in zip(DH, q):
        ct, st, ca, sa = np.cos(th), np.sin(th), np.cos(al), np.sin(al)
        T = T @ np.array([[ct, -st * ca, st * sa, a * ct], [st, ct * ca, -ct * sa, a * st], [0, sa, ca, d], [0, 0, 0, 1]])
    return T[:3, 3]


@pytest.fixture(scope="module")
def nobox(tmp_path_factory):
    """The shipped PUMA 560 description with its [end_effector] box and assembly pose taken out."""
    text = PUMA.read_text(encoding="utf-8")
    text = text[:text.index("[end_effector]")] + text[text.index("[assembly]"):]
    text = "\n".join(line for line in text.splitlines() if not line.startswith("pose = "))
    f = tmp_path_factory.mktemp("nobox") / "puma_nobox.toml"
    f.write_text(text, encoding="utf-8")
    return f


def test_the_reach_box_bounds_every_position_the_arm_reaches(nobox):
    robot = MechanismModel(nobox)
    ws = robot.workspace
    R = 0.4318 + 0.0203 + 0.15005 + 0.4318          # sum of |a| + |d| of the table
    assert not ws.stated and ws.names == ("x", "y", "z")
    np.testing.assert_allclose(ws.low, [-R] * 3, rtol=1e-12)
    np.testing.assert_allclose(ws.high, [R] * 3, rtol=1e-12)
    Q = np.random.default_rng(0).uniform(-np.pi, np.pi, (2000, 6))
    P = np.array([dh_position(q) for q in Q])
    assert np.abs(P).max() <= R


def test_check_mechanism_at_joint_values_needs_no_task_box(nobox):
    q = [0.3, np.radians(45), np.radians(180), -0.2, np.radians(45), 0.1]
    at = forward_at(MechanismModel(nobox), ", ".join(map(str, q)))
    np.testing.assert_allclose(at["position"], dh_position(q), atol=1e-12)
    out = subprocess.run([sys.executable, "-m", "evotol.cli", "check-mechanism", str(nobox), "--at",
                          "0, 45*deg, 180*deg, 0, 45*deg, 0"], capture_output=True, text=True, cwd=ROOT)
    assert out.returncode == 0, out.stderr
    qn = dh_position([0, np.radians(45), np.pi, 0, np.radians(45), 0]) * 1e3
    assert "position ({:.6g}, {:.6g}, {:.6g}) mm".format(*qn) in out.stdout


def _study(mechanism):
    spec = tomllib.loads((ROOT / "reports" / "studies" / "puma560_axes.toml").read_text(encoding="utf-8"))
    spec["robot"]["mechanism"] = str(mechanism)
    spec.pop("methods", None)
    return spec


def test_a_study_on_joint_configurations_needs_no_task_box_and_equals_the_boxed_one(nobox):
    a = load_problem(_study(nobox))
    b = load_problem(_study("puma560"))
    assert a.names == b.names
    np.testing.assert_allclose(a.model.sensitivity(a.poses), b.model.sensitivity(b.poses), rtol=0, atol=1e-12)
    ra, rb = allocate_optimum(a), allocate_optimum(b)
    assert ra.feasible and rb.feasible
    np.testing.assert_allclose(ra.t, rb.t, rtol=1e-9)
    assert ra.cost == pytest.approx(rb.cost, rel=1e-12)


@pytest.mark.parametrize("poses, key", [({"grid": [2, 2, 2]}, "poses.grid"), ({"latin_hypercube": 8}, "poses.latin_hypercube"),
                                        (None, "poses.grid")])
def test_task_poses_over_a_box_nobody_stated_are_refused(nobox, poses, key):
    spec = _study(nobox)
    if poses is None:
        spec.pop("poses")
    else:
        spec["poses"] = poses
    with pytest.raises(ValidationError, match=rf"^{key} = .*no \[end_effector\] coordinates") as e:
        load_problem(spec)
    assert "\n" not in str(e.value)


def test_a_closed_loop_mechanism_still_needs_its_task_coordinates(tmp_path):
    text = (ROOT / "robots" / "mechanisms" / "fivebar.toml").read_text(encoding="utf-8")
    start = text.index("[end_effector]")
    end = text.index("[assembly]")
    f = tmp_path / "fivebar_nobox.toml"
    f.write_text(text[:start] + text[end:].replace('pose = ["0*mm", "70*mm"]\n', ""), encoding="utf-8")
    with pytest.raises(ValidationError, match=r"^end_effector.coordinates = \[\]: expected the task coordinates of a closed-loop"):
        MechanismModel(f)


@pytest.fixture(scope="module")
def nobox_held(tmp_path_factory):
    """The same, with the tool orientation the shipped description holds ([end_effector] orientation only)."""
    text = PUMA.read_text(encoding="utf-8")
    text = text[:text.index("[end_effector]")] + '[end_effector]\norientation = [["y", "pi/2"]]\n\n' + text[text.index("[assembly]"):]
    text = "\n".join(line for line in text.splitlines() if not line.startswith("pose = "))
    f = tmp_path_factory.mktemp("nobox_held") / "puma_nobox_held.toml"
    f.write_text(text, encoding="utf-8")
    return f


COST = {"model": "exponential", "a0": 1.9, "a1": 0.5, "scale": 1e-5}
PAIRS = {
    "callouts": lambda s: s["robot"].update(callouts=[{"joint": "J3", "kind": "position", "length": "50 mm"}]),
    "norm": lambda s: s["requirement"].update(position="0.5 mm"),
    "rss": lambda s: s["requirement"].update(position="0.5 mm", measure="rss"),
    "calibration": lambda s: (s["requirement"].update(position="0.5 mm"),
                              s.update(calibration={"count": 24, "over": "workspace", "noise": "20 um", "simulate": 0})),
    "task poses": lambda s: s.update(poses={"list": [[0.6, -0.15, 0.0], [0.55, -0.1, 0.05]]}),
}


@pytest.mark.parametrize("pair", list(PAIRS))
def test_without_a_task_box_each_capability_equals_the_boxed_description(nobox_held, pair):
    """Joint configurations with callouts, a norm, RSS, calibration, and task poses given as a list
    (the assembly pose then where the declared assembly joints put the flange): the same optimum as the
    shipped description with its box, to 1e-9."""
    def problem(mechanism):
        s = _study(mechanism)
        s["cost"].update({"position": COST, "axial": COST})
        PAIRS[pair](s)
        return load_problem(s, base_dir=ROOT / "reports" / "studies")
    a, b = problem(nobox_held), problem("puma560")
    assert [m.part for m in a.model.parts()] == [m.part for m in b.model.parts()]
    ra, rb = allocate_optimum(a), allocate_optimum(b)
    assert ra.feasible and rb.feasible
    assert ra.cost == pytest.approx(rb.cost, rel=1e-9)      # (t itself: sources of no effect sit anywhere near their bound)
    np.testing.assert_allclose(a.model.sensitivity(a.poses), b.model.sensitivity(b.poses), rtol=0, atol=1e-9)
