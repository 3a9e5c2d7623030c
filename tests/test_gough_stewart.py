"""A spatial 6-DOF platform from a description file without hand work (issue 41 item 7):
docs/examples/gough_stewart_6ups.toml, docs/gough_stewart.md.

Every number is checked against a reference written here: the Gough-Stewart closed-form inverse
kinematics l_i = |p + R a_i - b_i| and its first-order map (Merlet 2006, "Parallel Robots",
Sec. 4.1 and eq. 6.1: n_i . (dp + dphi x R a_i) = dl_i), central finite differences of the
nonlinear loop closure, brute-force enumeration of the corners of a source box, and an independent
SLSQP solve of the allocation with one constraint per corner.
"""
from __future__ import annotations

import itertools
import json
import tomllib
from pathlib import Path

import numpy as np
import pytest
from scipy.optimize import minimize
from scipy.spatial.transform import Rotation

from evotol import MechanismModel, Requirement, Tolerance, ToleranceProblem, allocate_optimum
from evotol.cli import main
from evotol.cost_models import ExponentialCost
from evotol.errors import ValidationError
from evotol.robots.mechanism.description.reader import mechanism_from_dict

EXAMPLES = Path(__file__).resolve().parents[1] / "docs" / "examples"
DESCRIPTION = EXAMPLES / "gough_stewart_6ups.toml"
LEGS = [(15, 45), (105, 75), (135, 165), (225, 195), (255, 285), (345, 315)]     # base, platform angle (deg)
RB, RP = 0.5, 0.3
POSES = np.array([[0.0, 0.0, 0.6, 0.0, 0.0, 0.0],
                  [0.03, -0.02, 0.63, np.radians(4), np.radians(-3), np.radians(2)],
                  [-0.04, 0.04, 0.56, np.radians(-5), np.radians(5), np.radians(-5)]])


def _geometry(pose):
    """Base points b_i, platform points R a_i (world, from the centre), legs n_i and lengths."""
    b = np.array([[RB * np.cos(np.radians(x)), RB * np.sin(np.radians(x)), 0.0] for x, _ in LEGS])
    a = np.array([[RP * np.cos(np.radians(y)), RP * np.sin(np.radians(y)), 0.0] for _, y in LEGS])
    R = Rotation.from_euler("ZYX", pose[3:]).as_matrix()             # Rz(yaw) Ry(pitch) Rx(roll)
    Ra = a @ R.T
    v = pose[:3] + Ra - b
    length = np.linalg.norm(v, axis=1)
    return b, Ra, R, v / length[:, None], length


def _closed_form_map(pose, names):
    """[dp; dphi] per unit source from |p + R (a_i - delta a_i) - (b_i + delta b_i)| = l_i + dl_i, linearised:
    n_i . dp + (R a_i x n_i) . dphi = dl_i + n_i . (delta b_i + R delta a_i)."""
    b, Ra, R, n, _ = _geometry(pose)
    J = np.hstack([n, np.cross(Ra, n)])
    rhs = np.zeros((6, len(names)))
    for c, name in enumerate(names):
        if name.startswith("l"):
            rhs[int(name[1]) - 1, c] = 1.0
            continue
        frame, field = name.split(".")
        i, k = int(frame[1]) - 1, "xyz".index(field[-1])
        if frame.startswith("U"):      # base joint centre: placement axes Rz(beta) Rx(-pi/2)
            axes = Rotation.from_euler("ZX", [np.radians(LEGS[i][0]), -np.pi / 2]).as_matrix()
            rhs[i, c] = n[i] @ axes[:, k]
        else:                          # platform frame shifted by +e along its axes: a_i moves by -e
            rhs[i, c] = n[i] @ R[:, k]
    return np.linalg.solve(J, rhs)


@pytest.fixture(scope="module")
def robot():
    return MechanismModel(DESCRIPTION)


def test_the_36_assembly_joints_are_solved_from_a_rough_guess(robot):
    """Six pattern lines in [assembly] joints; the leg lengths evotol solves equal the closed form."""
    pose, q = robot.kin.assembly()
    assert len(q) == 36
    _, _, _, _, length = _geometry(pose)
    assert np.allclose([q[f"l{i}"] for i in range(1, 7)], length, rtol=0, atol=1e-12)
    assert abs(length[0] - 0.66347) < 1e-5          # sqrt(0.27086^2 + 0.08272^2 + 0.6^2) by hand
    qs = robot.joint_values(POSES)
    for p, pose in enumerate(POSES):
        assert np.allclose([qs[f"l{i}"][p] for i in range(1, 7)], _geometry(pose)[4], rtol=0, atol=1e-11)


def test_first_order_map_equals_the_closed_form_and_finite_differences(robot):
    S = robot.sensitivity(POSES)
    names = list(robot.source_names)
    assert len(names) == 42
    for p, pose in enumerate(POSES):
        ref = _closed_form_map(pose, names)
        assert np.abs(S[p] - ref).max() < 1e-12 * max(1.0, np.abs(ref).max())
    h = 1e-6
    E = np.eye(len(names)) * h
    plus = robot.pose_error(POSES, np.broadcast_to(E, (len(POSES),) + E.shape))
    minus = robot.pose_error(POSES, np.broadcast_to(-E, (len(POSES),) + E.shape))
    fd = np.swapaxes((plus - minus) / (2 * h), 1, 2)               # (n, 6, n_sources)
    assert np.abs(fd - S).max() < 1e-6 * np.abs(S).max()


SUBSET = ["l1", "l4", "U2a.shift_x", "U3a.shift_z", "U5a.shift_y", "P1.shift_y", "P4.shift_x", "P6.shift_z"]


def _problem(sources, requirement, lower=1e-6, upper=5e-4):
    robot = MechanismModel(DESCRIPTION, sources=sources)
    cost = ExponentialCost(1.9, 0.5, scale=1e-5)
    tol = {n: Tolerance(cost, lower=lower, upper=upper) for n in robot.source_names}
    return robot, ToleranceProblem(robot, tol, Requirement(position=requirement, measure="worst_case"), POSES)


def test_worst_case_equals_corner_enumeration():
    """The worst case over 8 sources is the largest |dp| over the 256 corners of their box (the
    norm is convex, so a corner attains it): exactly on the first-order model, within the
    second-order terms on the nonlinear one."""
    robot, problem = _problem(SUBSET, 1e-4)
    t = np.array([10, 20, 15, 30, 5, 25, 12, 8]) * 1e-6
    wc = float(problem.max_errors(t)["position"][0])
    corners = np.array(list(itertools.product((-1.0, 1.0), repeat=len(SUBSET)))) * t
    S = robot.sensitivity(POSES)[:, :3, :]
    linear = np.linalg.norm(np.einsum("pij,cj->pci", S, corners), axis=2).max()
    nonlinear = np.linalg.norm(robot.pose_error(POSES, np.broadcast_to(corners, (len(POSES),) + corners.shape))[..., :3],
                               axis=2).max()
    assert abs(wc - linear) <= 1e-9 * linear
    assert abs(wc - nonlinear) <= 1e-3 * linear


def test_optimum_equals_an_independent_scipy_solve():
    """allocate_optimum on six sources vs SLSQP with |S diag(s) t| <= r for every sign vector s
    (half of them: -s gives the same norm) at every pose; the costs agree to 1e-6."""
    sources = ["l1", "l2", "U1a.shift_x", "U3a.shift_y", "P2.shift_z", "P5.shift_x"]
    r = 3e-5
    robot, problem = _problem(sources, r)
    opt = allocate_optimum(problem)
    assert opt.feasible
    S = robot.sensitivity(POSES)[:, :3, :]
    signs = np.array([s for s in itertools.product((-1.0, 1.0), repeat=len(sources)) if s[0] > 0])
    cost = ExponentialCost(1.9, 0.5, scale=1e-5)
    x0 = np.full(len(sources), 2.0)                                  # t / 1e-5

    def margins(x):
        e = np.einsum("pij,cj->pci", S, signs * x * 1e-5)
        return ((r ** 2 - (e ** 2).sum(axis=2)) / r ** 2).ravel()

    ref = minimize(lambda x: float(cost.cost(x * 1e-5).sum()), x0, method="SLSQP",
                   bounds=[(0.1, 50.0)] * len(sources), constraints=[{"type": "ineq", "fun": margins}],
                   options={"ftol": 1e-14, "maxiter": 500})
    assert ref.success, ref.message
    assert abs(opt.cost - ref.fun) <= 1e-6 * ref.fun
    assert np.allclose(opt.t, ref.x * 1e-5, rtol=1e-3)


# Slow (~11 s alone) because it runs the documentation's two examples as a user would, unchanged (docs/gough_stewart.md).
def test_the_docs_examples_run(tmp_path, capsys):
    """The allocation study and the study of given tolerances (patterns) of docs/gough_stewart.md."""
    assert main(["run", str(EXAMPLES / "gough_stewart_study.toml"), "--out", str(tmp_path)]) == 0
    d = json.loads((tmp_path / "gough_stewart.json").read_text())
    assert d["results"]["optimum"]["feasible"] and d["results"]["optimum"]["cost"] < d["results"]["sensitivity"]["cost"]
    ranges = {line.split()[0]: " ".join(line.split()[2:4]) for line in d["problem"].splitlines()[2:]}
    assert [n for n, r in ranges.items() if r == "[2e-06, 0.0001]"] == [f"P{i}.shift_z" for i in range(1, 7)]   # "P?.shift_z"
    assert sum(r == "[2e-06, 0.0005]" for r in ranges.values()) == 36
    assert main(["run", str(EXAMPLES / "gough_stewart_given.toml"), "--out", str(tmp_path)]) == 0
    g = json.loads((tmp_path / "gough_stewart_given.json").read_text())
    given = {s["name"]: s["tolerance"] for s in g["sources"]}
    assert len(given) == 42
    assert all(abs(given[n] - (6e-6 if n[0] in "lP" else 8e-6)) < 1e-15 for n in given)
    # the given design's worst case, recomputed from the closed-form map over all poses of the study
    poses = np.array(g["poses"])
    names = [s["name"] for s in g["sources"]]
    t = np.array([given[n] for n in names])
    axes = np.array([np.abs(_closed_form_map(p, names)[:3] * t).sum(axis=1) for p in poses])   # per-axis worst cases
    value = np.array(g["analysis"]["worst_case"]["position"]["value"])
    assert np.all(axes.max(axis=1) <= value * (1 + 1e-9)) and np.all(value <= np.linalg.norm(axes, axis=1) * (1 + 1e-9))


def _spec():
    return tomllib.loads(DESCRIPTION.read_text())


def test_a_platform_left_without_orientation_is_refused_with_the_key():
    spec = _spec()
    spec["end_effector"]["coordinates"] = spec["end_effector"]["coordinates"][:3]
    spec["end_effector"]["orientation"] = []
    spec["assembly"]["pose"] = spec["assembly"]["pose"][:3]
    with pytest.raises(ValidationError) as info:
        MechanismModel(mechanism_from_dict(spec))
    msg = str(info.value)
    assert "\n" not in msg and "end_effector.orientation" in msg and "[['z', '0']]" in msg
    spec["end_effector"]["orientation"] = [["z", "0"]]             # held level: the platform does not tilt
    robot = MechanismModel(mechanism_from_dict(spec))
    corner = np.array([[0.04, 0.04, 0.64]])
    q = robot.joint_values(corner)
    assert robot.redundancy is None
    assert np.allclose([q[f"l{i}"][0] for i in range(1, 7)], _geometry(np.r_[corner[0], 0, 0, 0])[4], atol=1e-11)


@pytest.mark.parametrize("joints, names", [
    ({"l?": 0.65, "u?": 0.0, "v?": 0.0, "s??": 0.0, "s1?": 0.0}, ["assembly.joints.s1?", "'s??' already matches s1a"]),
    ({"l?": 0.65, "u?": 0.0, "v?": 0.0, "s??": 0.0, "w?": 0.0}, ["assembly.joints.w?", "matching some joint"]),
])
def test_assembly_patterns_that_overlap_or_match_nothing(joints, names):
    spec = _spec()
    spec["assembly"]["joints"] = joints
    with pytest.raises(ValidationError) as info:
        mechanism_from_dict(spec)
    for n in names:
        assert n in str(info.value)


def test_an_exact_joint_overrides_its_pattern():
    spec = _spec()
    spec["assembly"]["joints"] = {**spec["assembly"]["joints"], "l3": "0.7"}
    assert mechanism_from_dict(spec).assembly_joints["l3"] == 0.7
    assert mechanism_from_dict(spec).assembly_joints["l2"] == 0.65


@pytest.mark.parametrize("table, names", [
    ({"l?": {"fixed": 1e-5}, "l[12]": {"fixed": 2e-5}}, ["sources.l[12]", "'l?' already matches l1"]),
    ({"q?": {"fixed": 1e-5}}, ["sources.q?", "a pattern matching some source"]),
])
def test_source_patterns_that_overlap_or_match_nothing(table, names):
    from evotol._runtime.keyword_checks import expand_patterns
    with pytest.raises(ValidationError) as info:
        expand_patterns(table, ["l1", "l2", "l3"], "sources", "source")
    for n in names:
        assert n in str(info.value)
    assert expand_patterns({"l?": {"fixed": 1}, "l2": {"fixed": 2}}, ["l1", "l2"], "sources", "source") == \
        {"l2": {"fixed": 2}, "l1": {"fixed": 1}}
