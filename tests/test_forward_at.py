"""``evotol check-mechanism --at`` and the URDF end links (issue 33 items 3 and 7): the forward
kinematics printed at given joints equals the textbook product of A_i; a missing ``--tip`` names
the URDF's end links (read independently here with ElementTree)."""
from __future__ import annotations

import json
import subprocess
import sys
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np
import pytest

from evotol.errors import ValidationError
from evotol.robots.mechanism.kinematics.forward_at import forward_at, urdf_end_links
from evotol.robots.mechanism.model.error_model import MechanismModel
from tests.test_standard_dh import PUMA, textbook_fk

ROOT = Path(__file__).resolve().parents[1]
UR5 = ROOT / "robots" / "urdf" / "ur_description" / "urdf" / "ur5_robot.urdf"


def test_forward_at_equals_the_textbook():
    out = forward_at(MechanismModel(PUMA), "10*deg, 10*deg, -100*deg, -20*deg, 30*deg, -60*deg")
    T = textbook_fk(np.radians([10, 10, -100, -20, 30, -60]))
    assert np.allclose(out["position"], T[:3, 3], atol=1e-12) and np.allclose(out["rotation"], T[:3, :3], atol=1e-12)
    yaw, pitch, roll = out["zyx"]
    Rz = np.array([[np.cos(yaw), -np.sin(yaw), 0], [np.sin(yaw), np.cos(yaw), 0], [0, 0, 1]])
    Ry = np.array([[np.cos(pitch), 0, np.sin(pitch)], [0, 1, 0], [-np.sin(pitch), 0, np.cos(pitch)]])
    Rx = np.array([[1, 0, 0], [0, np.cos(roll), -np.sin(roll)], [0, np.sin(roll), np.cos(roll)]])
    assert np.allclose(Rz @ Ry @ Rx, T[:3, :3], atol=1e-12)


def test_forward_at_refuses_bad_values():
    with pytest.raises(ValidationError) as e:
        forward_at(MechanismModel(PUMA), "0.1, 0.2")
    assert e.value.field == "--at[0]" and "6 joint values" in str(e.value)


def test_cli_at_and_missing_tip():
    run = lambda *a: subprocess.run([sys.executable, "-m", "evotol.cli", "check-mechanism", *a], capture_output=True,
                                    text=True, cwd=ROOT)
    r = run("puma560", "--at", "0, 45*deg, 180*deg, 0, 45*deg, 0", "--json")
    assert r.returncode == 0
    assert np.allclose(json.loads(r.stdout)["position"], textbook_fk(np.radians([0, 45, 180, 0, 45, 0]))[:3, 3], atol=1e-12)
    r = run(str(UR5))
    assert r.returncode != 0 and "tool0" in r.stderr and "Traceback" not in r.stderr
    root = ET.parse(UR5).getroot()
    parents = {j.find("parent").get("link") for j in root.findall("joint")}
    leaves = [j.find("child").get("link") for j in root.findall("joint") if j.find("child").get("link") not in parents]
    assert urdf_end_links(UR5) == leaves and "tool0" in leaves
