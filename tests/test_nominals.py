"""Drawing-ready tables: the nominal column filled wherever evotol knows it (issue 34 item 5).

A mechanism description's design parameters and constant DH entries carry the description's value
(planar 3-RPR, robots/mechanisms/planar3rpr.toml: the expected values are read off the file by
hand); a URDF arm's placement errors have nominal 0, the URDF joint origin they deviate about,
and its origin parameters the URDF's own xyz/rpy (parsed here from the URDF with ElementTree);
entries that hold a joint variable and actuator offsets have none. The CSV, the workbook, the page
and the terminal show the same nominal in display units."""
from __future__ import annotations

import contextlib
import html
import io
import math
import re
import tomllib
import xml.etree.ElementTree as ET
from pathlib import Path

import pandas as pd
import pytest

from evotol.cli import main
from evotol.reporting.drawing import nominal_line
from evotol.studyfile import load_problem
from evotol.summaries.user_study import source_table

RPR = '''name = "rpr_nominal"
seed = 0
[robot]
mechanism = "planar3rpr"
sources = ["Rb", "rp", "P1.d", "A2.gamma", "P3.theta", "A1.theta", "l?"]
[poses]
grid = [2, 2, 2]
[requirement]
position = 1e-4
measure = "worst_case"
[bounds]
lower = 1e-6
upper = 1e-3
[cost.default]
model = "exponential"
a0 = 1.9
a1 = 0.5
scale = 1e-5
[methods]
sensitivity = {}
[verify]
n_samples = 20
[report]
units = "mm, deg"
'''
#: read off robots/mechanisms/planar3rpr.toml: Rb = 200 mm, rp = 50 mm, P1.d = "rp",
#: A2.gamma = "210*deg", P3.theta = "-(330*deg + offset) - pi" with offset = 40 deg (mm, deg)
RPR_NOMINAL = {"Rb": 200.0, "rp": 50.0, "P1.d": 50.0, "A2.gamma": 210.0, "P3.theta": -(330.0 + 40.0) - 180.0}
RPR_BLANK = ["A1.theta", "l1", "l2", "l3"]          # theta = "a1" (a joint variable); actuator offsets


def _run(tmp_path, text: str, name: str) -> str:
    (tmp_path / f"{name}.toml").write_text(text)
    out = io.StringIO()
    with contextlib.redirect_stdout(out):
        assert main(["run", str(tmp_path / f"{name}.toml"), "--out", str(tmp_path)]) == 0
    return out.getvalue()


def test_description_nominals_in_csv_workbook_page_and_terminal(tmp_path):
    terminal = _run(tmp_path, RPR, "rpr_nominal")
    csv = pd.read_csv(tmp_path / "rpr_nominal_tolerances.csv").set_index("source")
    book = pd.read_excel(tmp_path / "rpr_nominal_tolerances.xlsx", sheet_name="sensitivity").set_index("source")
    page = html.unescape((tmp_path / "rpr_nominal.html").read_text())
    table = page[page.index("id='tolerances'") if "id='tolerances'" in page else page.index('id="tolerances"'):]
    table = table[:table.index("</table>")]
    head = re.findall(r"<th>(.*?)</th>", table)
    cells = {r[0]: r for r in (re.findall(r"<td>(.*?)</td>", row) for row in table.split("<tr>")[2:])}
    lines = terminal.splitlines()
    i = next(k for k, line in enumerate(lines) if line.startswith("[evotol] tolerances"))
    trows = {c[0]: c for c in (re.split(r"\s{2,}", line.strip()) for line in lines[i + 2:i + 11])}
    for n, v in RPR_NOMINAL.items():
        for t in (csv, book):
            assert t.loc[n, "nominal"] == pytest.approx(v, rel=1e-12)
        assert float(cells[n][head.index("nominal")]) == pytest.approx(v, rel=1e-9)
        assert float(trows[n][2]) == pytest.approx(v, rel=1e-9)
        assert csv.loc[n, "unit"] == ("deg" if n in ("A2.gamma", "P3.theta") else "mm")
    assert csv.loc["P1.d", "nominal is"] == "d of frame P1 in the description (rp)"
    for n in RPR_BLANK:
        assert math.isnan(csv.loc[n, "nominal"]) and cells[n][head.index("nominal")] == ""
        assert "varies with the pose" in csv.loc[n, "nominal is"]
    assert "P1.d, A2.gamma, P3.theta: the entry's value in the description" in page


def _urdf_origins(path) -> dict:
    """joint -> (xyz, rpy) from the URDF file itself (ElementTree, not Pinocchio)."""
    root = ET.parse(path).getroot()
    return {j.get("name"): tuple([float(x) for x in j.find("origin").get(k).split()] for k in ("xyz", "rpy"))
            for j in root.findall("joint") if j.find("origin") is not None}


def test_urdf_placements_have_nominal_zero_about_the_urdf_origin():
    from evotol.robots.mechanism.urdf.reader import resolve_urdf
    root = Path(__file__).resolve().parents[1] / "reports" / "studies"
    spec = tomllib.loads((root / "ur5_urdf.toml").read_text())
    rows = {r["name"]: r for r in source_table(load_problem(spec, base_dir=root))}
    placements = [n for n in rows if re.search(r"\.(shift|tilt)_[xyz]$", n)]
    assert len(placements) == 30 and len(rows) == 36
    for n in placements:
        joint, field = n.split(".")
        assert rows[n]["nominal"] == 0.0
        assert rows[n]["nominal_note"] == (f"0 = the URDF joint origin of {joint}; the deviation is a "
                                           f"{'shift along' if 'shift' in field else 'tilt about'} its {field[-1]} axis")
    for n in set(rows) - set(placements):                       # encoder offsets
        assert "nominal" not in rows[n] and "varies with the pose" in rows[n]["nominal_note"]
    assert nominal_line({"sources": list(rows.values())}).startswith(
        "Nominal: the 30 placement errors are 0 = the URDF joint origin, the zone is the deviation about it")
    # origin parameters as sources: the URDF's own numbers
    spec["robot"]["sources"] = ["elbow_joint_y", "elbow_joint_z", "wrist_1_joint_pitch", "elbow_joint.shift_x"]
    rows = {r["name"]: r for r in source_table(load_problem(spec, base_dir=root))}
    xyz, rpy = _urdf_origins(resolve_urdf("example-robot-data:ur_description/urdf/ur5_robot.urdf"))["elbow_joint"]
    assert rows["elbow_joint_y"]["nominal"] == pytest.approx(xyz[1], abs=1e-12)
    assert rows["elbow_joint_z"]["nominal"] == pytest.approx(xyz[2], abs=1e-12)
    assert rows["elbow_joint_z"]["nominal_note"] == "the URDF joint origin's xyz z of elbow_joint"
    _, rpy1 = _urdf_origins(resolve_urdf("example-robot-data:ur_description/urdf/ur5_robot.urdf"))["wrist_1_joint"]
    assert rows["wrist_1_joint_pitch"]["nominal"] == pytest.approx(rpy1[1], abs=1e-9)


def test_urdf_study_csv_carries_the_nominal(tmp_path):
    """The shipped UR5 study at one pose: the CSV's nominal is 0 mm / 0 arcsec for every placement
    error and blank for the encoder offsets, and says what it is."""
    root = Path(__file__).resolve().parents[1] / "reports" / "studies"
    text = (root / "ur5_urdf.toml").read_text().replace('name = "ur5_urdf"', 'name = "ur5_nominal"')
    text = text.replace("grid = [3, 3, 3]", "list = [[0.4, 0.0, 0.3]]").replace("optimum = {}\n", "")
    text = re.sub(r"ga = \{.*\}\n", "", text).replace("n_samples = 300", "n_samples = 20")
    _run(tmp_path, text, "ur5_nominal")
    csv = pd.read_csv(tmp_path / "ur5_nominal_tolerances.csv").set_index("source")
    shifts, tilts = csv.index.str.contains(r"\.shift_"), csv.index.str.contains(r"\.tilt_")
    assert shifts.sum() == 18 and tilts.sum() == 12
    assert (csv.loc[shifts, "nominal"] == 0).all() and (csv.loc[shifts, "unit"] == "mm").all()
    assert (csv.loc[tilts, "nominal"] == 0).all() and (csv.loc[tilts, "unit"] == "arcsec").all()
    assert csv.loc[shifts | tilts, "nominal is"].str.contains("URDF joint origin").all()
    assert csv.loc[~(shifts | tilts), "nominal"].isna().all()


ROOT = Path(__file__).resolve().parents[1]


def test_nominals_reach_through_joint_space_and_per_axis_wrappers():
    """The PUMA 560 study (standard DH, poses as joint values, per-axis limits) wraps the description's
    model twice; its nominals are still the description's: a2 = 431.8 mm, d4 = 431.8 mm (Corke's
    table in robots/mechanisms/puma560.toml), alpha1 = 90 deg."""
    import math
    import tomllib

    from evotol.studyfile import load_problem
    from evotol.summaries.nominals import source_nominals

    path = ROOT / "reports" / "studies" / "puma560_axes.toml"
    problem = load_problem(tomllib.loads(path.read_text()), base_dir=path.parent)
    nominal = source_nominals(problem.model, problem.names)
    text = (ROOT / "robots" / "mechanisms" / "puma560.toml").read_text()
    assert text.count('"431.8*mm"') == 2            # a2 and d4 as the description writes them
    assert nominal["a2"] == pytest.approx(0.4318, abs=1e-12)
    assert nominal["d4"] == pytest.approx(0.4318, abs=1e-12)
    assert nominal["alpha1"] == pytest.approx(math.pi / 2, abs=1e-12)
