"""Poses as joint configurations (issue 33 item 1): robots/mechanism/model/joint_space.py and ``[poses] joints``.

The requirement must hold at exactly the configurations given: the sensitivities are compared with
finite differences of the textbook forward kinematics at those joints, and the study file's
certified optimum is re-checked at them by enumerating the corners of the tolerance box.
"""
from __future__ import annotations

import itertools
from pathlib import Path

import numpy as np
import pytest

from evotol.errors import ValidationError
from evotol.studyfile import load_problem
from evotol.robots.mechanism.model.joint_space import JointSpaceModel, joint_configurations
from evotol.robots.mechanism.model.error_model import MechanismModel
from tests.test_standard_dh import PUMA, TABLE, textbook_fk

ROOT = Path(__file__).resolve().parents[1]
CONFIGS_DEG = [[10, 10, -100, -20, 30, -60], [0, -90, 90, 0, 0, 0], [90, -60, -30, 30, -45, 90],
               [0, 45, 180, 0, 45, 0], [-30, 20, 150, 45, 60, 10]]


def study(**poses):
    return {"name": "puma_joints", "robot": {"mechanism": str(PUMA), "sources": ["a2", "a3", "d3", "d4", "theta2", "theta3"]},
            "poses": poses, "requirement": {"position": 5e-4}, "bounds": {"lower": 1e-6, "upper": 1e-3},
            "cost": {"default": {"model": "exponential", "a0": 1.9, "a1": 0.5, "scale": 1e-5}}}


def test_joint_poses_are_held_exactly():
    model = MechanismModel(PUMA)
    jm, Q = joint_configurations(model, [[f"{v}*deg" for v in c] for c in CONFIGS_DEG])
    assert np.allclose(Q, np.radians(CONFIGS_DEG), atol=0)
    S = jm.sensitivity(Q)
    h = 1e-7
    j = model.source_names.index("d4")
    for q, s in zip(Q, S):            # d4 moves the tool as the textbook product says, at these joints
        up = [list(r) for r in TABLE]
        up[3][0] += h
        assert np.allclose(s[:3, j], (textbook_fk(q, up)[:3, 3] - textbook_fk(q)[:3, 3]) / h, atol=1e-6)
    assert np.allclose(jm.tool_pose(Q), [textbook_fk(q) for q in Q], atol=1e-12)


def test_by_name_and_in_order_are_the_same():
    model = MechanismModel(PUMA)
    _, Q1 = joint_configurations(model, [["10*deg", 0.2, "-100*deg", 0, 0, "1*deg"]])
    _, Q2 = joint_configurations(model, [{"q6": "1*deg", "q5": 0, "q4": 0, "q3": "-100*deg", "q2": 0.2, "q1": "10*deg"}])
    assert np.array_equal(Q1, Q2)


def test_study_file_optimum_holds_at_the_configurations():
    from evotol.allocators import allocate_optimum
    spec = study(joints=[[f"{v}*deg" for v in c] for c in CONFIGS_DEG])
    problem = load_problem(spec)
    assert isinstance(problem.model, JointSpaceModel) and problem.n_poses == 5
    r = allocate_optimum(problem)
    assert r.verdict.startswith("certified optimal")
    # corners of the tolerance box at each configuration: the largest |dp| is the requirement
    J = MechanismModel(PUMA, sources=spec["robot"]["sources"]).sensitivity_at_joints(np.radians(CONFIGS_DEG))[:, :3]
    worst = max(np.linalg.norm(J @ (np.array(s) * r.t), axis=1).max() for s in itertools.product((-1, 1), repeat=len(r.t)))
    assert worst == pytest.approx(5e-4, rel=1e-6)


@pytest.mark.parametrize("joints, field, words", [
    ([["10*deg", 0, 0, 0, 0]], "poses.joints[0]", "6 joint values"),
    ([{"q1": 0, "q2": 0}], "poses.joints[0]", "missing"),
    ([{"q1": 0, "q2": 0, "q3": 0, "q4": 0, "q5": 0, "q6": 0, "q7": 0}], "poses.joints[0].q7", "joint variable"),
    ([[30, 0, 0, 0, 0, 0]], "poses.joints[0].q1", "30*deg"),
    ([["a", 0, 0, 0, 0, 0]], "poses.joints[0].q1", "constant"),
    ([], "poses.joints", "list"),
])
def test_bad_joint_poses(joints, field, words):
    with pytest.raises(ValidationError) as e:
        load_problem(study(joints=joints))
    assert e.value.field == field and words in str(e.value)


def test_joint_limits_and_closed_loops_are_refused_before_work(tmp_path):
    text = PUMA.read_text() + '\n[limits]\nq2 = ["-45*deg", "225*deg"]\n'
    f = tmp_path / "puma_limits.toml"
    f.write_text(text)
    spec = study(joints=[[0, "-90*deg", 0, 0, 0, 0]])
    spec["robot"]["mechanism"] = str(f)
    with pytest.raises(ValidationError) as e:
        load_problem(spec)
    assert e.value.field == "poses.joints[0].q2" and "-90 deg" in str(e.value) and "[-45, 225] deg" in str(e.value)
    spec = study(joints=[[0, 0]])
    spec["robot"] = {"mechanism": "fivebar"}
    with pytest.raises(ValidationError) as e:
        load_problem(spec)
    assert e.value.field == "poses.joints" and "serial arm" in str(e.value)
    spec = study(joints=[[0] * 6], grid=3)
    with pytest.raises(ValidationError) as e:
        load_problem(spec)
    assert e.value.field == "poses.grid"


def test_sources_without_effect_are_marked():
    # PUMA 560 with d6 = 0: frame 6's origin is the wrist centre, so the wrist rows' alpha and theta cannot move it
    from evotol.reporting.user_study import tolerance_rows
    from evotol.summaries.user_study import source_table, sources_without_effect
    spec = study(joints=[[0, 0.5, 1.0, 0, 0.5, 0], [0.3, 0.2, 1.5, 0.4, 0.5, 0.2]])
    spec["robot"] = {"mechanism": str(PUMA)}
    problem = load_problem(spec)
    flagged = [n for n, f in zip(problem.names, sources_without_effect(problem)) if f]
    # independently: perturb each entry of the textbook table by 1e-3 and see whether frame 6's origin moves
    moves = {}
    for q in problem.poses:
        for row in range(6):
            for field, name in ((0, "d"), (1, "a"), (2, "alpha")):
                up = [list(r) for r in TABLE]
                up[row][field] += 1e-3
                d = np.linalg.norm(textbook_fk(q, up)[:3, 3] - textbook_fk(q)[:3, 3])
                moves[f"{name}{row + 1}"] = max(moves.get(f"{name}{row + 1}", 0.0), d)
            d = np.linalg.norm(textbook_fk(q + 1e-3 * (np.arange(6) == row))[:3, 3] - textbook_fk(q)[:3, 3])
            moves[f"theta{row + 1}"] = max(moves.get(f"theta{row + 1}", 0.0), d)
    assert flagged == [n for n in problem.names if moves[n] < 1e-12]
    assert set(flagged) == {"alpha4", "theta4", "alpha5", "theta5", "alpha6", "theta6"}
    summary = {"sources": source_table(problem), "results": {"x": {"tolerances": dict(zip(problem.names, problem.upper))}},
               "display_units": {"length": "mm", "angle": "mrad"}}
    rows, _ = tolerance_rows(summary)
    assert [r[0] for r in rows if "no effect" in r[1]] == flagged
