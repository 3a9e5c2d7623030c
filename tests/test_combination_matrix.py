"""The pair matrix of docs/combinations.md beyond the UR5 pairs of tests/test_combinations.py (issue 39
item 3): every pair of poses (task, joint configurations, grid + refinement), requirement forms (norm,
per axis; worst case, RSS, yield), analysis of given tolerances, clearances and callouts, on a URDF
arm, a standard-DH and a modified-DH PUMA 560 and a closed-loop 5-bar, either composes -- its
first-order map equal to central differences of its own nonlinear model, with exactly the parts
asked for -- or is refused before any work in one line that names both.

The measures (worst case, RSS, yield) change the requirement, not the error model: a pair of a
measure and a part composes when the model does; a measure an allocator cannot take is the
allocator's refusal (``methods.optimum: requirement.measure = 'yield' ...``), tested in
tests/test_bad_inputs.py.
"""
from __future__ import annotations

import copy
import time
from pathlib import Path

import pytest

from evotol.errors import ValidationError
from evotol.studyfile.problem import load_problem
from evotol.studyfile.run import _run_claimed
from tests.test_combinations import COST, JOINTS, fd_check

PUMA_JOINTS = [["10*deg", "10*deg", "-100*deg", "-20*deg", "30*deg", "-60*deg"], [0, "45*deg", "180*deg", 0, "45*deg", 0]]
HOSTS = {
    "urdf": ({"mechanism": "ur5"}, [[0.35, -0.05, 0.25], [0.45, 0.05, 0.35]], JOINTS, "elbow_joint", 5e-4),
    "std-dh": ({"mechanism": "puma560"}, [[0.6, -0.15, 0.0], [0.55, -0.1, 0.05]], PUMA_JOINTS, "J3", 5e-4),
    "mod-dh": ({"mechanism": "puma560_modified"}, [[0.6, -0.15, 0.0], [0.55, -0.1, 0.05]], PUMA_JOINTS, "3", 5e-4),
    "closed-loop": ({"mechanism": "fivebar"}, [[0.0, 0.07], [-0.02, 0.055]], [[1.5, -1.1, 1.65, 1.1, -2.3]], "B", 1e-4),
}
PART = {"joints": "joint_space", "per-axis": "axis_limits", "callouts": "callouts"}


def study(host: str, caps) -> dict:
    """A small study on ``host`` with the capabilities ``caps`` (as a parsed study file)."""
    robot, poses, joints, seat, req = HOSTS[host]
    s = {"name": "pair", "seed": 0, "robot": copy.deepcopy(robot), "poses": {"list": copy.deepcopy(poses)},
         "requirement": {"position": req, "measure": "worst_case"}, "bounds": {"lower": 1e-7, "upper": 1e-3 if req > 1e-4 else 1e-4},
         "cost": {"default": COST}, "methods": {"optimum": {}}, "verify": {"n_samples": 100}}
    if "joints" in caps:
        s["poses"] = {"joints": copy.deepcopy(joints)}
    if "grid+refine" in caps:       # beside joint configurations: their refinement
        s["poses"] = {**s["poses"], "refine": True} if "joints" in caps else {"grid": [2] * len(poses[0]), "refine": True}
    if "per-axis" in caps:
        s["requirement"]["position"] = {"x": req, "y": req}
    if "rss" in caps:
        s["requirement"]["measure"] = "rss"
    if "yield" in caps:
        s["requirement"].update(measure="yield", probability=0.99)
    if "clearances" in caps:
        s["clearances"] = {"h": 0.01}
    if "callouts" in caps:
        s["robot"]["callouts"] = [{"joint": seat, "kind": "position", "length": "50 mm"}]
    if "analysis" in caps:      # every source given: read the composed sources first
        p = load_problem({k: v for k, v in s.items() if k != "calibration"})
        s["sources"] = {n: {"fixed": req / 250} for n in p.names}
        s.pop("methods")
    return s


COMPOSE = [
    ("urdf", ("grid+refine", "per-axis")), ("urdf", ("grid+refine", "callouts")), ("urdf", ("grid+refine", "rss")),
    ("urdf", ("rss", "callouts")), ("urdf", ("rss", "joints")), ("urdf", ("rss", "per-axis")),
    ("urdf", ("yield", "joints")), ("urdf", ("yield", "callouts")),
    ("urdf", ("analysis", "callouts")), ("urdf", ("analysis", "joints")), ("urdf", ("analysis", "per-axis")),
    ("urdf", ("analysis", "rss")), ("urdf", ("analysis", "yield")),
    ("std-dh", ("joints",)), ("std-dh", ("callouts",)), ("std-dh", ("per-axis",)), ("std-dh", ("joints", "callouts")),
    ("std-dh", ("joints", "per-axis")), ("std-dh", ("callouts", "per-axis")), ("std-dh", ("analysis", "joints")),
    ("mod-dh", ("joints",)), ("mod-dh", ("per-axis",)), ("mod-dh", ("callouts",)), ("mod-dh", ("joints", "per-axis")),
    ("mod-dh", ("joints", "callouts")), ("mod-dh", ("analysis", "per-axis")),
    ("closed-loop", ("per-axis",)), ("closed-loop", ("analysis",)), ("closed-loop", ("clearances",)),
    ("closed-loop", ("per-axis", "analysis")), ("closed-loop", ("rss", "per-axis")),
]


@pytest.mark.parametrize("host, caps", COMPOSE, ids=lambda v: v if isinstance(v, str) else "+".join(v))
def test_pairs_that_compose_keep_their_parts_and_match_finite_differences(host, caps):
    problem = load_problem(study(host, caps))
    parts = {m.part for m in problem.model.parts()} - {None}
    assert parts == {PART[c] for c in caps if c in PART}, parts
    assert problem.robot is problem.model.described
    assert ("clearances" in caps) == (problem.clearances is not None)
    if "analysis" in caps:
        assert not problem.free.any()
    assert fd_check(problem) < 1e-5


REFUSED = [
    ("urdf", ("joints", "grid+refine"), r"^poses\.refine = True: expected nothing next to poses\.joints"),
    ("urdf", ("analysis", "grid+refine"), r"^poses\.refine = True: expected no refine when every tolerance is given"),
    ("urdf", ("clearances", "joints"), r"^clearances = 'UR5': expected a robot with joint clearances posed by task poses.*\[poses\] joints"),
    ("closed-loop", ("joints",), r"^poses\.joints = '5-bar': expected a serial arm: with closed loops"),
    ("closed-loop", ("joints", "clearances"), r"^poses\.joints = '5-bar': expected a serial arm"),
    ("closed-loop", ("callouts",), r"^callout B = '5-bar': expected a joint of a spatial mechanism"),
    ("closed-loop", ("per-axis", "clearances"), r"^requirement\.position = .*: expected a norm bound \(a number\) with \[clearances\]"),
    ("closed-loop", ("analysis", "clearances"), r"^clearances = \[.*\]: expected no joint-clearance classes in an analysis of given tolerances"),
]


@pytest.mark.parametrize("host, caps, line", REFUSED, ids=lambda v: v if isinstance(v, str) and not v.startswith("^") else
                         ("+".join(v) if isinstance(v, tuple) else ""))
def test_pairs_that_do_not_compose_are_refused_in_one_line_before_any_work(host, caps, line, tmp_path, monkeypatch):
    import evotol.verification.tolerance_analysis as ta
    import evotol.allocators as allocators
    if "analysis" in caps and "clearances" in caps:     # the analysis' sources: every one, the clearance classes too
        s = study(host, tuple(c for c in caps if c != "analysis"))
        s["sources"] = {n: {"fixed": 4e-7} for n in load_problem(s).names}
        s.pop("methods")
    else:
        s = study(host, caps)
    work = []
    monkeypatch.setattr(ta, "given_tolerances", lambda *a, **k: work.append("analysis"))    # the first work of an analysis
    monkeypatch.setattr(allocators, "allocate_optimum", lambda *a, **k: work.append("optimum"))
    t0 = time.perf_counter()
    with pytest.raises(ValidationError, match=line) as e:
        _run_claimed(s, tmp_path / "pair.toml", tmp_path, "pair", 0, t0, False)
    assert "\n" not in str(e.value) and not work
    assert not list(tmp_path.iterdir())         # nothing written
