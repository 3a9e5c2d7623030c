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
