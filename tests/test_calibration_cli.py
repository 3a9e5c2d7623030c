"""``evotol check-calibration`` (issue 36 item 5): the base set and condition number of a plan, before any allocation."""
from __future__ import annotations

import argparse
from pathlib import Path

import pytest

from evotol.cli.commands.check_calibration import check_calibration, cmd_check_calibration
from evotol.errors import ValidationError

ROOT = Path(__file__).resolve().parents[1]


def _args(file, **kw):
    base = dict(count=None, over=None, noise=None, identify=None, instrument=None, max_condition=1e3, json=False)
    return argparse.Namespace(file=str(file), **{**base, **kw})


def test_study_file_plan(capsys):
    assert cmd_check_calibration(_args(ROOT / "reports/studies/ur5_calibrated.toml")) == 0
    out = capsys.readouterr().out
    assert "identifiable directions (rank of the seen columns): 23" in out and "condition number (unit-norm columns): 8.05" in out
    assert "wrist_3_joint: moves no measured coordinate" in out and "tolerances hold 0.454 mm" in out


def test_mechanism_with_options_and_a_poor_plan(capsys):
    """The task box alone: 17 identifiable directions, condition number above 1e3 -> exit 1 with the advice."""
    assert cmd_check_calibration(_args("ur5", noise="20 um", count=40)) == 1
    assert "spread the configurations" in capsys.readouterr().out
    out = check_calibration("ur5", {"noise": "20 um", "count": 40, "identify": ["shoulder_*_joint", "elbow_joint"]})
    assert out["identification"]["n_identified"] == 3 and out["identification"]["condition_number"] < 10
    with pytest.raises(ValidationError, match="--noise"):
        check_calibration("ur5", {"count": 40})
