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

import builtins
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

#: seconds per file (set-up, call, tear-down of every test), summed from a local run with ``--durations=0``
#: on 2026-12-02 (2 workers, the machine otherwise idle, numba's cache warm: 900 s in all, 480 s of wall),
#: the 50 files of 5 s or more; the docs site build is left out (it is skipped without the docs extra). Files
#: not listed run after these, more tests first (pytest-xdist's own order). A guide for the order only: a stale
#: or missing entry changes how long the run takes, never what it checks (the table of 2026-11-27 missed
#: test_iso9283_closed_loop_allocators.py, 64 s, which then ran after every listed file).
FILE_SECONDS = {
    "test_iso9283_closed_loop_allocators.py": 64, "test_iso9283_closed_loop.py": 34, "test_iso9283_front.py": 29,
    "test_combinations.py": 28, "test_jobs.py": 26, "test_feasibility.py": 26, "test_tolerances.py": 25,
    "test_docstrings.py": 25, "test_parcoords.py": 24, "test_explorer.py": 23,
    "test_iso9283_calibrated_methods.py": 19, "test_iso9283_calibrated_budget.py": 18,
    "test_callout_allocation.py": 18, "test_iso9283_monotone.py": 17, "test_urdf_walk.py": 16,
    "test_no_task_box.py": 16, "test_calibration.py": 16, "test_pose_blocks.py": 15,
    "test_calibration_simulation.py": 15, "test_process.py": 14, "test_iso9283_orientation.py": 14,
    "test_cli_conventions.py": 13, "test_calibration_random.py": 13, "test_faults.py": 13, "test_interrupt.py": 13,
    "test_calibration_linear_range.py": 11, "test_choi2000_study.py": 11, "test_allocators.py": 11,
    "test_calibration_study.py": 11, "test_gough_stewart.py": 10, "test_iso9283_ga.py": 10,
    "test_iso9283_sensitivity.py": 10, "test_deng2012_synth_engine.py": 10, "test_mechanism.py": 10,
    "test_callout_page_chromium.py": 9, "test_drawn_callouts.py": 9, "test_faults_full_disk.py": 9,
    "test_planar5r.py": 8, "test_iso9283_baselines.py": 7, "test_irsbot2.py": 7, "test_user_report.py": 7,
    "test_delta_study.py": 7, "test_faults_dask.py": 7, "test_checks_optimised.py": 7, "test_quiet_studies.py": 6,
    "test_typing.py": 6, "test_irsbot2_study.py": 6, "test_posture.py": 6, "test_layers.py": 6,
    "test_process_studies.py": 5,
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


@pytest.fixture(scope="session")
def _chromium_session():
    from evotol.reporting.headless import HeadlessChromium
    from tests.browser import require_chromium

    require_chromium()
    with HeadlessChromium() as browser:
        yield browser


@pytest.fixture
def chromium(_chromium_session):
    """The test process's headless Chromium (:class:`evotol.reporting.headless.HeadlessChromium`), started
    once for the session (issue 43: a start and a close cost 1-2 s per test); the tabs the test opened are
    closed after it, so each test sees a browser with no page of another. Skipped (or failed, with
    ``EVOTOL_REQUIRE_BROWSER=1``) as :func:`tests.browser.require_chromium` says when there is none."""
    browser = _chromium_session
    before = {t["targetId"] for t in browser.send("Target.getTargets")["targetInfos"]}
    yield browser
    for t in browser.send("Target.getTargets")["targetInfos"]:
        if t["type"] == "page" and t["targetId"] not in before:
            browser.send("Target.closeTarget", {"targetId": t["targetId"]})


@pytest.fixture
def hide_numba(monkeypatch):
    """``hide_numba(*cached)``: ``import numba`` fails until the test ends (the fallbacks without numba);
    the ``functools.lru_cache`` functions ``cached`` (compiled kernels) are cleared now and again once
    numba is back."""
    caches = []
    real = builtins.__import__

    def no_numba(name, *args, **kwargs):
        if name == "numba" or name.startswith("numba."):
            raise ImportError("numba hidden by the test")
        return real(name, *args, **kwargs)

    def hide(*cached):
        caches.extend(cached)
        for c in cached:
            c.cache_clear()
        monkeypatch.setattr(builtins, "__import__", no_numba)

    yield hide
    monkeypatch.undo()
    for c in caches:
        c.cache_clear()
