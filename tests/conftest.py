"""Session-wide fixtures: study runs that several test files read (issue 43 item 3).

Each runs once per test process (once per xdist worker), in its own temporary folder; a test gets a
deep copy of the returned summary, so no test sees another's changes. The files written are read-only
by convention: a test that edits a study's output makes its own run.
"""
from __future__ import annotations

import copy
from pathlib import Path

import pytest

STUDIES = Path(__file__).resolve().parents[1] / "reports" / "studies"


@pytest.fixture(scope="session")
def _motor_stack_session(tmp_path_factory):
    from evotol.studyfile import run_study_file

    out = tmp_path_factory.mktemp("motor_stack")
    return out, run_study_file(STUDIES / "motor_stack.toml", out=out)


@pytest.fixture
def motor_stack_run(_motor_stack_session):
    """``(out, summary)``: the shipped ``reports/studies/motor_stack.toml`` run once for the session
    (``evotol run``: ``out/motor_stack.json`` and ``.html``); the summary is the test's own copy."""
    out, summary = _motor_stack_session
    return out, copy.deepcopy(summary)
