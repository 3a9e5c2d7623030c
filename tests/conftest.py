"""Session-wide fixtures: study runs that several test files read (issue 43 item 3).

Each runs once per test process (once per xdist worker), in its own temporary folder; a test gets a
deep copy of the returned summary, so no test sees another's changes. The files written are read-only
by convention: a test that edits a study's output makes its own run.

The order of the test files (issue 43 item 3): ``--dist loadfile`` hands a worker one whole file at a
time, in the order of the collection (``--no-loadscope-reorder`` in ``pyproject.toml``: pytest-xdist
would otherwise order the files by their number of tests). :func:`pytest_collection_modifyitems` puts
the longest files first (:data:`FILE_SECONDS`), so the run does not end with one worker busy on a long
file while the other idles (longest processing time first: the makespan is at most 4/3 of the best).
"""
from __future__ import annotations

import copy
import os
from collections import Counter
from pathlib import Path

# One BLAS thread per test process, as ``evotol``'s command sets for itself (evotol.cli.main,
# evotol/_runtime/blas_threads.py): with two xdist workers on two cores, OpenBLAS's own threads spin
# against the other worker -- the five-bar's 80 SLSQP solves (tests/test_fivebar.py) took 28.8 s with
# two BLAS threads and 6.6 s with one, alone on a machine at load 4 (issue 43). Set before numpy is
# loaded here; the limit below covers a numpy that a plugin loaded first. Subprocesses inherit it.
for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

import pytest
from threadpoolctl import threadpool_limits

STUDIES = Path(__file__).resolve().parents[1] / "reports" / "studies"

#: seconds of the slowest tests of a file (set-up, call, tear-down), summed per file: the 40 slowest of
#: the whole run as ``.ci/run`` prints them (``--durations=40``), the larger of CI's two runs of
#: 2026-11-27 (pytest 363 s and 359 s, 2 workers). Files not listed run after these, more tests first
#: (pytest-xdist's own order). A guide for the order only: a stale or missing entry changes how long
#: the run takes, never what it checks.
FILE_SECONDS = {
    "test_callout_allocation.py": 40, "test_feasibility.py": 28, "test_conformance.py": 21, "test_explorer.py": 21,
    "test_calibration.py": 20, "test_tolerances.py": 20, "test_delta_study.py": 16, "test_parcoords.py": 16,
    "test_combinations.py": 16, "test_clearance_engine.py": 14, "test_choi2000_study.py": 14, "test_jobs.py": 13,
    "test_irsbot2_study.py": 13, "test_urdf_walk.py": 12, "test_serial_fast_path.py": 11, "test_interrupt.py": 10,
    "test_typing.py": 10, "test_cli_conventions.py": 10, "test_iso9283_studyfile.py": 9, "test_fivebar.py": 9,
    "test_mechanism.py": 9, "test_calibration_simulation.py": 8, "test_deng2012_synth_engine.py": 7,
    "test_yao2013_study.py": 7, "test_urdf_limits_redundancy.py": 6, "test_irsbot2.py": 6,
    "test_calibration_study.py": 6, "test_quiet_studies.py": 6, "test_layers.py": 6,
    "test_clearance_allocation.py": 6, "test_knots.py": 5, "test_allocators.py": 5, "test_drawn_callouts.py": 5,
    "test_studyfile_specs.py": 5, "test_export.py": 5,
}


def pytest_configure(config):
    """BLAS limited to one thread for the whole test process (see the variables set above), unless the
    user set ``OPENBLAS_NUM_THREADS`` (or ``OMP_``/``MKL_``) to something else."""
    if os.environ["OPENBLAS_NUM_THREADS"] == "1":
        config._evotol_blas_limit = threadpool_limits(limits=1, user_api="blas")


def pytest_collection_modifyitems(config, items):
    """Longest files first (:data:`FILE_SECONDS`), then the others by their number of tests (descending);
    the tests of a file keep their order."""
    def file_of(item):
        return item.nodeid.split("::", 1)[0].rsplit("/", 1)[-1]
    first, count = {}, Counter(file_of(item) for item in items)
    for i, item in enumerate(items):
        first.setdefault(file_of(item), i)
    items.sort(key=lambda item: (-FILE_SECONDS.get(file_of(item), 0), -count[file_of(item)], first[file_of(item)]))


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
