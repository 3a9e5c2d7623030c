"""A study file that names an assembly function ([robot] assembly = "module:function")."""
from pathlib import Path

import numpy as np
import pytest

from evotol.errors import ValidationError
from evotol.studyfile import load_problem, run_study_file

EXAMPLE = Path(__file__).resolve().parents[1] / "reports" / "studies" / "clutch_assembly.toml"


def test_clutch_study_file_builds_the_normalised_problem_and_runs(tmp_path):
    import tomllib

    spec = tomllib.loads(EXAMPLE.read_text())
    p = load_problem(spec)
    assert p.requirement.position == 1.0 and p.n_poses == 1
    assert p.model.derivative_method == "complex step"
    # worst case of the arithmetic stack, by hand: Σ |∂φ/∂x_j| t_j / L
    t = np.array([1e-5, 2e-5, 3e-5])
    expected = float(np.abs(p.model.gradient[0]) @ t / np.radians(2.0))
    assert p.evaluate(t[None]).position[0, 0] == pytest.approx(expected, rel=1e-5)
    summary = run_study_file(EXAMPLE, out=tmp_path)
    assert summary["results"]["optimum"]["feasible"]
    assert summary["results"]["ga"]["cost"] >= summary["results"]["optimum"]["cost"] * (1 - 1e-9)


@pytest.mark.parametrize("robot, field", [
    ({"assembly": "evotol.studies._process_benchmarks:clutch_angle", "limits": {"phi": 0.03}}, "robot.nominal"),
    ({"assembly": "evotol.studies._process_benchmarks:no_such", "nominal": {"a": 1.0}, "limits": {"phi": 0.03}}, "robot.assembly"),
    ({"assembly": "evotol.studies._process_benchmarks:clutch_angle", "nominal": {"a": 0.027, "c": 0.011, "e": 0.05},
      "limits": {"phi": 0.03}, "variant": "x"}, "robot.variant"),
])
def test_bad_assembly_study_file_names_the_field(robot, field):
    with pytest.raises(ValidationError) as err:
        load_problem({"robot": robot, "cost": {"default": {"model": "reciprocal", "a0": 1.0, "a1": 1.0, "scale": 1e-3}}})
    assert err.value.field == field
