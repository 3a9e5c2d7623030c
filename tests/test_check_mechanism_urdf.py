"""``evotol check-mechanism arm.urdf --tip tool0`` and the rank section of every check (issue 23 item 6).

Independent numbers: Pinocchio's placement regressor (its rank over the same configurations), the
UR5's two tilts the old roll/pitch/yaw sources cannot produce (the pitch = pi/2 origins,
``docs/mechanisms.md``), forward kinematics against Pinocchio.
"""
import json
from pathlib import Path

from evotol.cli import main

ROOT = Path(__file__).resolve().parents[1]
UR5 = ROOT / "robots" / "urdf" / "ur_description" / "urdf" / "ur5_robot.urdf"
OLD = "*_joint_x,*_joint_y,*_joint_z,*_joint_roll,*_joint_pitch,*_joint_yaw,*_joint"


def run(argv, capsys):
    try:
        code = main(argv)
    except SystemExit as exc:
        code = exc.code
    cap = capsys.readouterr()
    return code, cap.out, cap.err


def test_urdf_file_json_gives_sources_limits_rank_and_fd(capsys):
    code, out, _ = run(["check-mechanism", str(UR5), "--tip", "tool0", "--json"], capsys)
    assert code == 0
    d = json.loads(out)
    assert d["n_sources"] == 36 and d["sources"][0]["name"] == "shoulder_pan_joint.shift_x"
    assert {"nominal", "unit", "group"} <= set(d["sources"][0])
    r = d["identifiability"]
    assert r["rank"] == r["pinocchio_rank"] == r["combined_rank"] == 26 and not r["missing"]
    assert ["wrist_1_joint", "wrist_2_joint.tilt_y", 1] in r["duplicated"]   # offset of wrist 1 = tilt of wrist 2's seat
    assert d["fk_vs_pinocchio"] < 1e-12 and d["fd_rel_error"] < 1e-6
    assert abs(d["limits"][2]["lower"] + 3.14159265) < 1e-8 and len(d["workspace"]) == 3
    assert [j["solved"] for j in d["assembly"]["joints"]] == [0.0] * 6


def test_urdf_text_names_the_blind_tilts_of_the_old_sources(capsys):
    code, out, _ = run(["check-mechanism", str(UR5), "--tip", "tool0", "--sources", OLD], capsys)
    assert code == 0
    assert "rank of the 42 sources over 20 random configurations inside the joint limits: 24; Pinocchio's placement regressor 26" in out
    assert "missing (no source moves the tip this way): shoulder_lift_joint.tilt_z, wrist_1_joint.tilt_z" in out
    assert "duplicated: shoulder_lift_joint_roll = -shoulder_lift_joint_yaw" in out


def test_urdf_without_tip_is_one_line(capsys):
    code, out, err = run(["check-mechanism", str(UR5)], capsys)
    assert code == 2 and "--tip" in err and len(err.strip().splitlines()) == 1


def test_description_check_has_box_limits_and_rank(capsys):
    code, out, _ = run(["check-mechanism", "panda", "--poses", "20", "--json"], capsys)
    assert code == 0
    d = json.loads(out)
    r = d["identifiability"]
    assert r["n_sources"] == 42 and r["rank"] == r["pinocchio_rank"] == r["combined_rank"]
    assert d["limits"][3]["upper"] == -0.0698 and d["workspace"][0]["low"] == 0.3


def _no_fd_check(**extra):
    """A check result whose finite-difference agreement was not computed (``fd_rel_error`` None)."""
    return {"name": "toy", "file": "toy.toml", "planar": True, "n_sources": 0, "sources": [], "actuated": ["q1"],
            "passive": [], "n_poses": 3, "closure_residual": 0.0, "fd_rel_error": None, "seconds": 0.1,
            "assembly": {"pose": [{"name": "x", "value": 0.1, "unit": "m"}],
                         "joints": [{"name": "q1", "declared": 0.0, "solved": 0.0, "unit": "rad"}]},
            "end_effector": {"frame": "P", "position": [0.1, 0.0, 0.0], "yaw_pitch_roll": [0.0, 0.0, 0.0]}, **extra}


def test_fd_not_computed_is_said_not_a_traceback(capsys, monkeypatch):
    """``fd_rel_error`` None (no nonlinear model to difference): the text output of a description and
    of a URDF file says "not computed" on the finite-difference line and exits 0 (was a TypeError
    formatting None, and for a URDF a TypeError comparing None with --rtol)."""
    import evotol.robots.mechanism.checks.description as checks
    import evotol.robots.mechanism.urdf.check as urdf_check

    monkeypatch.setattr(checks, "check_mechanism", lambda *a, **k: _no_fd_check())
    monkeypatch.setattr(urdf_check, "check_urdf_file", lambda *a, **k: _no_fd_check(tip="tool0", fk_vs_pinocchio=0.0))
    for argv, line in ((["check-mechanism", "toy"], "  sensitivity vs central finite differences of the closure: not computed"),
                       (["check-mechanism", "arm.urdf", "--tip", "tool0"], "  sensitivity vs central finite differences: not computed")):
        code, out, err = run(argv, capsys)
        assert code == 0 and "Traceback" not in err, err
        assert any(s.startswith(line) for s in out.splitlines()), out
    code, out, _ = run(["check-mechanism", "arm.urdf", "--tip", "tool0", "--json"], capsys)
    assert code == 0 and json.loads(out)["fd_rel_error"] is None
