"""``evotol run`` of a calibrated study (issue 36 items 1, 5, 6, 7): the [calibration] table, the JSON block with a
unit for every number (docs/units.md), the report's comparison; bad plans refused in one line before any work."""
from __future__ import annotations

import json
import tomllib
from pathlib import Path

import numpy as np
import pytest

from evotol.calibration import CalibrationPlan, calibrated_problem
from evotol.calibration import summary as calibration_summary
from evotol.calibration.table import plan_from_table
from evotol.errors import ValidationError
from evotol.studyfile import load_problem, run_study_file
from evotol.studyfile import methods as studyfile_methods
from evotol.studyfile import run as studyfile_run
from evotol.calibration import simulation as calibration_simulation
from evotol.units import numbers_without_unit

ROOT = Path(__file__).resolve().parents[1]
STUDY = ROOT / "reports/studies/ur5_calibrated.toml"
OFFSETS = ["shoulder_pan_joint", "shoulder_lift_joint", "elbow_joint", "wrist_1_joint", "wrist_2_joint"]


@pytest.fixture(scope="module")
def run_json(tmp_path_factory):
    d = tmp_path_factory.mktemp("cal")
    text = STUDY.read_text().replace("grid = [3, 3, 3]", "grid = [2, 2, 2]").replace("simulate = 200", "simulate = 20")
    text = text[:text.index("[methods]")] + "[methods]\nsensitivity = {}\noptimum = {}\n\n[verify]\nn_samples = 30\n"
    (d / "s.toml").write_text(text)
    run_study_file(d / "s.toml", out=d)
    return json.loads((d / "ur5_calibrated.json").read_text()), (d / "ur5_calibrated.html").read_text()


def test_calibrated_study_json_and_report(run_json):
    data, page = run_json
    cal = data["calibration"]
    assert cal["plan"]["identification"]["rank"] == 23 and cal["plan"]["identification"]["condition_number"] < 10
    assert cal["methods"]["optimum"]["cost"] < 0.2 * cal["uncalibrated"]["cost"]
    sim = cal["methods"]["optimum"]["simulation"]
    assert sim["simulated"]["position"]["max"] <= 5e-4 and sim["n_fit_failures"] == 0
    assert numbers_without_unit(data, data["units"]) == []
    assert "What calibration buys" in page and "uncalibrated optimum" in page and "condition number" in page


def test_the_page_has_the_joints_table_its_posture_note_points_to(run_json):
    """Issue 39: a calibrated page said "the joints used are in the table 'Joints used at every pose'" without
    the table. The table is there, one row per pose, and its joints put the UR5's tool0 at the study's poses:
    Pinocchio's forward kinematics of the shipped URDF (independent of evotol's kinematics), to 1e-9 m."""
    import html as html_lib
    import pinocchio as pin
    import re

    data, page = run_json
    text = html_lib.unescape(page)
    assert "in the table 'Joints used at every pose'" in text and "<h2>Joints used at every pose</h2>" in text
    table = text[text.index("Joints used at every pose</h2>"):]
    table = table[:table.index("</table>")]
    joints = data["joints"]
    n = len(joints["values"][joints["variables"][0]])
    assert table.count("<tr>") - 1 == n == len(joints["poses"])
    model = pin.buildModelFromUrdf(str(ROOT / "robots/urdf/ur_description/urdf/ur5_robot.urdf"))
    frame = model.getFrameId("tool0")
    dm = model.createData()
    for i, pose in enumerate(joints["poses"]):
        q = np.array([joints["values"][v][i] for v in joints["variables"]])
        pin.framesForwardKinematics(model, dm, q)
        assert np.allclose(dm.oMf[frame].translation, pose[:3], atol=1e-9)


@pytest.mark.parametrize("table, field, words", [
    ({"count": 1, "noise": "20 um", "identify": OFFSETS}, "calibration.configurations", "fewer measurements"),
    ({"count": 40, "noise": "20 um", "identify": ["elbow_jiont"]}, "calibration.identify", "matching a source"),
    ({"count": 40, "noise": "20 um", "identify": ["*_joint"]}, "calibration.identify", "wrist_3_joint"),
    ({"count": 40, "noise": 20, "identify": OFFSETS}, "calibration.noise", "unit"),
    ({"count": 40, "noise": "-5 um", "identify": OFFSETS}, "calibration.noise", ">= 0"),
    ({"count": 40, "noise": "5 parsecs", "identify": OFFSETS}, "calibration.noise", "um"),
    ({"joints": [[0, -1.2, 1.6, -1.9, -1.57, 0], [0, 0, 4.0, 0, 0, 0]], "noise": "20 um", "identify": ["elbow_joint"]},
     "calibration.joints[1]", "elbow_joint = 4"),
    ({"count": 40, "noise": "20 um", "identfy": OFFSETS}, "calibration.identfy", "identify"),
    ({"noise": "20 um"}, "calibration.count", "configurations"),
    ({"count": 40, "noise": "2 mm", "identify": OFFSETS}, "calibration.noise", "below the requirement"),
])
def test_bad_plans_one_line_before_work(table, field, words, tmp_path, monkeypatch):
    """``evotol run`` of the study with the bad [calibration] table: one line naming the field, and before any
    work -- no method of the study, no simulated calibration and no Monte Carlo ran (spies in their place),
    no output written."""
    text = STUDY.read_text()
    head, tail = text[:text.index("\n[calibration]\n")], text[text.index("\n[methods]\n"):]
    body = "".join(f"{k} = {json.dumps(v)}\n" for k, v in table.items())       # JSON strings/lists are TOML
    (tmp_path / "s.toml").write_text(f"{head}\n[calibration]\n{body}{tail}")
    ran = []

    def spy(name):
        def called(*a, **k):
            ran.append(name)
            raise AssertionError(f"{name} ran before the plan was refused")
        return called
    for m in list(studyfile_methods.METHODS):
        monkeypatch.setitem(studyfile_methods.METHODS, m, spy(m))
    for module in (calibration_summary, calibration_simulation):   # where the simulated calibration is called
        monkeypatch.setattr(module, "simulate_calibration", spy("simulate_calibration"))
    monkeypatch.setattr(studyfile_run, "verify", spy("verify"))
    with pytest.raises(ValidationError) as exc:
        run_study_file(tmp_path / "s.toml", out=tmp_path / "out")
    msg = str(exc.value)
    assert "\n" not in msg and msg.startswith(field) and words in msg, msg
    assert ran == [] and not list(tmp_path.glob("out/*"))


def test_plan_from_table_reads_units_and_defaults():
    plan, n = plan_from_table({"count": 12, "noise": {"position": ["20 um", "0.02 mm", "40um"]}, "identify": "identifiable"})
    assert plan.noise["position"].tolist() == pytest.approx([2e-5, 2e-5, 4e-5]) and n == 200 and plan.k == 3
    with pytest.raises(ValidationError, match="calibration.noise.orientation"):
        plan_from_table({"count": 12, "noise": {"position": "20 um", "orientation": "5 arcsec"}})
    plan, _ = plan_from_table({"count": 12, "measure": ["position", "orientation"],
                               "noise": {"position": "20 um", "orientation": "5 arcsec"}})
    assert plan.rows_per_configuration == 6 and plan.noise["orientation"][0] == pytest.approx(5 * 4.8481368e-6)


def test_compensation_range_caps_an_identified_source():
    spec = tomllib.loads((ROOT / "reports/studies/ur5_urdf.toml").read_text())
    p = load_problem(spec, base_dir=STUDY.parent)
    pc = calibrated_problem(p, CalibrationPlan(noise="20 um", identify=OFFSETS, count=40, seed=0,
                                               compensation_range={"elbow_joint": 2e-4}))
    j = pc.names.index("elbow_joint")
    assert pc.upper[j] == pytest.approx(2e-4)
    assert pc.calibration.bounds["elbow_joint"]["compensation_range"] == 2e-4


def test_the_terminal_prints_the_calibration_the_page_shows(run_json, capsys):
    """Issue 41: a calibrated study printed nothing of its calibration in the terminal. The lines name
    the plan as the page does (the same sentence), the costs, and a saving recomputed here from them."""
    import html as html_lib
    from evotol.cli import _print_results
    data, page = run_json
    _print_results(data)
    out = capsys.readouterr().out
    lines = out[out.index("[evotol] calibration"):].splitlines()
    plan = lines[1].strip()
    assert plan.startswith("Calibration plan: ") and plan in html_lib.unescape(page)
    cal = data["calibration"]
    assert f"condition number {cal['plan']['identification']['condition_number']:.3g}" in plan
    cost = next(x for x in lines if "uncalibrated optimum cost" in x)
    unc, opt = cal["uncalibrated"]["cost"], cal["methods"]["optimum"]["cost"]
    assert f"uncalibrated optimum cost {unc:.6g}" in cost
    assert f"calibrated optimum {opt:.6g} ({100 * (1 - opt / unc):.1f} % saved" in cost
    sim = next(x for x in lines if x.strip().startswith("optimum: simulated calibration"))
    assert "20 robots" in sim and "0 fit failures" in sim
