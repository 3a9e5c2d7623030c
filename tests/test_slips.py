"""Slips that used to pass in silence (issue 41 item 6): each gets one line naming the key, before
any work -- a warning where the value may be meant, an error where it cannot be. The expected
numbers in the lines are the closed forms (0.5 m = 500 mm; 0.05 m = 50 mm; 10 % = 0.1)."""
import tomllib
import warnings
from pathlib import Path

import pytest

from evotol.calibration.plan import CalibrationPlan
from evotol.cli import main
from evotol.core.plausibility import PlausibilityWarning
from evotol.errors import ValidationError
from evotol.studyfile import load_problem
from evotol.robots.mechanism.urdf.reader import resolve_urdf
from tests.fast_study import EXAMPLE, fast_study

ROOT = Path(__file__).resolve().parents[1]
STUDIES = ROOT / "reports" / "studies"


def _warnings_of(spec, folder):
    with warnings.catch_warnings(record=True) as w:
        warnings.simplefilter("always")
        problem = load_problem(spec, folder)
    return problem, [str(x.message) for x in w if issubclass(x.category, PlausibilityWarning)]


def test_a_per_axis_limit_without_unit_is_named_by_its_axis():
    spec = tomllib.loads((STUDIES / "puma560_axes.toml").read_text())
    spec["requirement"]["position"] = {"x": "0.5*mm", "y": 0.5, "z": "0.5*mm"}
    problem, lines = _warnings_of(spec, STUDIES)
    hit = [s for s in lines if s.startswith("requirement.position.y = 0.5 m (500 mm)")]
    assert len(hit) == 1 and "if 0.5 was meant in mm, write 0.0005 or '0.5 mm'" in hit[0], lines
    assert hit[0] in problem.warnings            # kept for the JSON's warnings and the report


def test_a_given_tolerance_without_unit_warns():
    spec = tomllib.loads(EXAMPLE.read_text())
    spec["sources"] = {"R2": {"fixed": 0.05}}
    _, lines = _warnings_of(spec, EXAMPLE.parent)
    assert any(s.startswith("sources.R2.fixed = 0.05 m (50 mm) is above the usual range") and "write 5e-05" in s
               for s in lines), lines
    spec["sources"] = {"R2": {"fixed": "50 um"}}             # with its unit: no warning, the value read
    problem, lines = _warnings_of(spec, EXAMPLE.parent)
    assert not any("sources.R2" in s for s in lines) and problem.tolerances["R2"].locked == pytest.approx(5e-5)


def test_a_drawing_precision_coarser_than_the_zones_warns_before_work(tmp_path, capsys):
    f = fast_study(tmp_path, ("[methods]", "[report]\nprecision = 100\n\n[methods]"))
    assert main(["run", str(f), "--out", str(tmp_path)]) == 0
    err = capsys.readouterr().err
    line = next(s for s in err.splitlines() if "report.precision" in s)
    # the UCR3 example's lower bound 1 µm on an interval ±t: zone ±1 µm, shown as 0 at a 100 µm step
    assert "report.precision = 100 µm is coarser than the zones it rounds" in line and "±1.000 µm" in line


@pytest.mark.parametrize("value, ok", [(10, None), (0.1, 0.1), ("10 %", 0.1), (1.0, None)])
def test_linear_fraction_is_a_fraction(value, ok):
    if ok is None:
        with pytest.raises(ValidationError) as e:
            CalibrationPlan(noise="20 um", count=10, linear_fraction=value)
        msg = str(e.value)
        assert msg.startswith(f"calibration.linear_fraction = {value}") and "(0, 1)" in msg and "\n" not in msg
        if value == 10:
            assert "if 10 was meant in %, write 0.1" in msg
    else:
        assert CalibrationPlan(noise="20 um", count=10, linear_fraction=value).linear_fraction == pytest.approx(ok)


def test_check_mechanism_refuses_tip_on_a_description(capsys):
    assert main(["check-mechanism", str(ROOT / "robots" / "mechanisms" / "puma560.toml"), "--tip", "tool0"]) == 2
    err = capsys.readouterr().err
    assert "--tip = 'tool0'" in err and "description file" in err and len(err.strip().splitlines()) == 1


def test_a_callout_length_in_um_is_named_before_the_infeasible_error(tmp_path, capsys):
    text = (STUDIES / "ur5_callouts.toml").read_text()
    old = 'joint = "elbow_joint"\nkind = "position"\nlength = "50 mm"'
    assert old in text
    f = tmp_path / "short.toml"
    f.write_text(text.replace(old, old.replace("50 mm", "50 um")))
    assert main(["run", str(f), "--out", str(tmp_path)]) != 0
    err = capsys.readouterr().err
    warn = next(s for s in err.splitlines() if "robot.callouts elbow_joint.position: length = 0.05 mm" in s)
    assert "if '50 um' was meant in mm, write '50 mm'" in warn
    assert err.index(warn) < err.index("infeasible")


def test_check_calibration_on_a_stack_says_there_is_no_robot(capsys):
    assert main(["check-calibration", str(STUDIES / "motor_stack.toml")]) == 2
    err = capsys.readouterr().err
    assert "[stack] study has no robot to calibrate" in err and "--noise" not in err


def test_urdf_paths_give_the_right_advice(monkeypatch):
    import importlib.metadata as md

    with pytest.raises(ValidationError) as e:
        resolve_urdf("not-a-package-41:robots/x.urdf")
    assert "pip install not-a-package-41" in str(e.value)
    real = md.distribution

    def missing(name):
        if name == "example-robot-data":
            raise md.PackageNotFoundError(name)
        return real(name)
    with monkeypatch.context() as m:        # example-robot-data not installed, a file evotol does not ship
        m.setattr(md, "distribution", missing)
        with pytest.raises(ValidationError) as e:
            resolve_urdf("example-robot-data:ur_description/urdf/ur10_robot.urdf")
    msg = str(e.value)
    assert 'pip install "evotol[urdf]"' in msg and "evotol ships panda_description" in msg and "\n" not in msg
    try:
        md.distribution("example-robot-data")
    except md.PackageNotFoundError:
        pytest.skip("example-robot-data (a third-party package) is not installed: the checks below need it")
    with pytest.raises(ValidationError) as e:
        resolve_urdf("example-robot-data:ur_description/urdf/ur5_robott.urdf")
    assert "nearest: ur_description/urdf/ur5_robot.urdf" in str(e.value)
    # the package's name spelled with underscores is the same package (its files are found)
    assert resolve_urdf("example_robot_data:ur_description/urdf/ur10_robot.urdf").is_file()
