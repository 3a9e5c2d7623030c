"""Issue 33 item 7: no numerical warnings leak to the terminal. Fast example studies of
reports/studies run with every RuntimeWarning (divide by zero, invalid value, overflow) raised as an
error; the PUMA 560 study (sources without effect) runs the same way in tests/test_export.py."""
from __future__ import annotations

import json
import warnings
from pathlib import Path

import pytest

from evotol.studyfile import run_study_file

STUDIES = Path(__file__).resolve().parents[1] / "reports" / "studies"


@pytest.mark.parametrize("name", ["clutch_assembly", "motor_stack", "planar3rrr"])
def test_example_study_runs_without_runtime_warnings(name, tmp_path):
    """Each study completes (its summary written, every method with a cost) with RuntimeWarnings
    as errors: a division by zero or an invalid value anywhere on its path would fail here."""
    with warnings.catch_warnings():
        warnings.simplefilter("error", RuntimeWarning)
        run_study_file(STUDIES / f"{name}.toml", out=tmp_path)
    data = json.loads((tmp_path / f"{name}.json").read_text())
    methods = data["results"] if "results" in data else data["allocation"]["methods"]
    assert methods and all("cost" in r for r in methods.values())
