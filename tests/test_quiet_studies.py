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


def test_clearance_study_marks_no_clearance_as_without_effect_and_redraws(tmp_path):
    """The five-bar with joint clearances (GA only, 5 generations): a clearance class's columns in
    the first-order map are 0 (the certified clearance measure computes its effect), so it must not
    be marked "no effect"; its centred ±t zones, rounded for the drawing, are re-checked by that
    measure (it stopped with "expected centred intervals ±t next to clearance sources")."""
    text = (STUDIES / "fivebar_clearances.toml").read_text()
    text = text[:text.index("[methods]")] + "[methods]\nga = { pop_size = 10, n_gen = 5 }\n[verify]\nn_samples = 20\n"
    (tmp_path / "s.toml").write_text(text)
    with warnings.catch_warnings():
        warnings.simplefilter("error", RuntimeWarning)
        run_study_file(tmp_path / "s.toml", out=tmp_path)
    data = json.loads((tmp_path / "fivebar_clearances.json").read_text())
    clearances = [s["name"] for s in data["sources"] if s["name"].startswith(("bxy_", "bz_"))]
    assert len(clearances) == 10 and not any(s.get("no_effect") for s in data["sources"])
    check = data["drawing"]["ga"]
    assert check["normalised_error"] is not None and check["normalised_error"] <= data["results"]["ga"]["normalised_error"] * (1 + 1e-9)
