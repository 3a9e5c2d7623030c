"""One unit grammar (issue 41 item 5, docs/units.md): every length and angle a study file or a
description takes reads ``"0.5 mm"``, ``"0.5*mm"``, ``"20 um"``, ``"20*um"``, ``"0.1 mrad"``,
``"30 deg"`` and inches through the one table ``evotol.units.quantity.UNITS``. Each reader is
checked against the value written out by hand in SI (1 mm = 1e-3 m, 1 in = 25.4 mm exactly,
1 deg = pi/180 rad)."""
import math
import tomllib

import pytest

from evotol.calibration.plan import parse_noise
from evotol.core.axis_limits import parse_axis_limits
from evotol.core.requirement import Requirement
from evotol.errors import ValidationError
from evotol.studyfile import load_problem
from evotol.units.quantity import parse_quantity
from evotol.robots.mechanism.callouts.table import parse_length
from evotol.robots.mechanism.description.expressions import Expression
from tests.fast_study import EXAMPLE

LENGTHS = {"0.5 mm": 5e-4, "0.5*mm": 5e-4, "0.5mm": 5e-4, "20 um": 2e-5, "20*um": 2e-5, "20 µm": 2e-5,
           "20*µm": 2e-5, "0.002 in": 0.002 * 0.0254, "0.002*inch": 0.002 * 0.0254, "1e-3 m": 1e-3}
ANGLES = {"0.1 mrad": 1e-4, "0.1*mrad": 1e-4, "30 deg": math.pi / 6, "30*deg": math.pi / 6,
          "36 arcsec": 36 / 3600 * math.pi / 180, "5 urad": 5e-6}


@pytest.mark.parametrize("text", list(LENGTHS))
def test_every_length_reader_takes_every_spelling(text, tmp_path):
    want = LENGTHS[text]
    assert parse_quantity(text, "x", "length") == pytest.approx(want, rel=1e-12)
    assert Requirement(position=text).position == pytest.approx(want, rel=1e-12)
    assert parse_axis_limits({"position": {"z": text}}).position["z"] == pytest.approx(want, rel=1e-12)
    assert parse_length(text, "length") == pytest.approx(want, rel=1e-12)
    assert parse_noise(text)["position"][0] == pytest.approx(want, rel=1e-12)
    if " " not in text.strip():          # an expression entry of a description (names, * and numbers)
        assert Expression.parse(text, "d")({}) == pytest.approx(want, rel=1e-12)


@pytest.mark.parametrize("text", list(ANGLES))
def test_every_angle_reader_takes_every_spelling(text):
    want = ANGLES[text]
    assert Requirement(position=1e-3, orientation=text).orientation == pytest.approx(want, rel=1e-12)
    assert parse_axis_limits({"orientation": {"x": text}}).orientation["x"] == pytest.approx(want, rel=1e-12)
    assert parse_noise({"orientation": text}, measure=("orientation",))["orientation"][0] == pytest.approx(want, rel=1e-12)
    assert Expression.parse(text, "alpha")({}) == pytest.approx(want, rel=1e-12)


def test_a_study_file_takes_units_in_requirement_bounds_and_given_tolerances():
    spec = tomllib.loads(EXAMPLE.read_text())
    spec["requirement"]["position"] = "0.05*mm"
    spec["bounds"] = {"lower": "1 um", "upper": "0.2 mm"}
    spec["sources"] = {"R1": {"locked": "20*um"}, "R2": {"fixed": "15 um"}}
    p = load_problem(spec, EXAMPLE.parent)
    assert p.requirement.position == pytest.approx(5e-5, rel=1e-12)
    j1, j2 = p.names.index("R1"), p.names.index("R2")
    assert p.tolerances["R1"].locked == pytest.approx(2e-5, rel=1e-12)
    assert p.upper[j2] == pytest.approx(1.5e-5, rel=1e-12)
    free = [j for j in range(p.n_sources) if j not in (j1, j2) and p.model.sources[j].unit == "m"]
    assert p.upper[free[0]] == pytest.approx(2e-4, rel=1e-12) and p.lower[free[0]] == pytest.approx(1e-6, rel=1e-12)


@pytest.mark.parametrize("text, kind, field", [("20 deg", "length", "requirement.position"),
                                                ("0.5 mm", "angle", "requirement.orientation"),
                                                ("0.5 furlong", "length", "requirement.position"),
                                                ("mm 0.5", "length", "requirement.position")])
def test_a_wrong_unit_is_one_line_naming_the_key(text, kind, field):
    with pytest.raises(ValidationError) as e:
        Requirement(**{kind == "length" and "position" or "orientation": text})
    msg = str(e.value)
    assert field in msg and text in msg and "\n" not in msg
