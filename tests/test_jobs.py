"""``evotol reproduce all --jobs N`` (issue 13): several studies at once, each its own process.

Checked: the JSON a study writes when it runs beside another equals, number by number, the JSON of
the same study run alone in this process (wall times excepted); Ctrl-C stops the running studies,
names them and the ones not started, and exits 130; bad ``--jobs`` is a one-line error.
"""
from __future__ import annotations

import importlib.util
import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from evotol import studies
from evotol.cli import main
from evotol.jobs import longest_first, reproduce_concurrently
from evotol.progress import EXPECTED_SECONDS

ROOT = Path(__file__).resolve().parents[1]


def _compare():
    spec = importlib.util.spec_from_file_location("compare_study_json", ROOT / "benchmarks" / "compare_study_json.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def test_longest_first_follows_the_expected_times():
    names = ["mechanisms", "deng2012-irsbot2", "not-measured", "yao2013"]
    order = longest_first(names)
    assert order[-1] == "not-measured"
    assert [EXPECTED_SECONDS[n] for n in order[:-1]] == sorted((EXPECTED_SECONDS[n] for n in order[:-1]), reverse=True)


def test_studies_run_side_by_side_give_the_numbers_of_a_run_alone(tmp_path, capsys):
    names = ["chase1990-clutch", "process-stack"]
    res = reproduce_concurrently(names, tmp_path / "jobs", jobs=2, quick=True, report_every=1e9)
    assert not res.failed and not res.interrupted and set(res.summaries) == set(names)
    assert all((tmp_path / "jobs" / "logs" / f"{n}.log").exists() for n in names)
    cmp = _compare()
    for name in names:
        studies.get(name).run(tmp_path / "alone", quick=True)
        a = json.loads((tmp_path / "alone" / f"{name}.json").read_text())
        b = json.loads((tmp_path / "jobs" / f"{name}.json").read_text())
        out = {"n": 0, "diff": [], "only": []}
        cmp.walk(a, b, [], out, 0.0, cmp.TIMING)
        assert out["n"] > 100 and out["diff"] == [] and out["only"] == [], (name, out["diff"][:5])


def test_ctrl_c_stops_the_running_studies_and_names_what_was_not_run(tmp_path):
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    proc = subprocess.Popen([sys.executable, "-m", "evotol.cli", "reproduce", "all", "--quick", "--jobs", "2",
                             "--out", str(tmp_path)], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=env)
    started, t0 = 0, time.time()
    while started < 2 and time.time() - t0 < 60:
        line = proc.stdout.readline()
        started += line.startswith("[evotol] started")
    assert started == 2
    time.sleep(1.0)
    proc.send_signal(signal.SIGINT)
    out, err = proc.communicate(timeout=120)
    assert proc.returncode == 130, err
    assert "interrupted (Ctrl-C) during " in err and "not run: " in err
    assert "not run: none" not in err            # 11 studies, two were running
    assert "[evotol] run times" in out


@pytest.mark.parametrize("value", ["0", "-1", "two"])
def test_bad_jobs_is_a_one_line_error(value, capsys):
    with pytest.raises(SystemExit) as exc:
        main(["reproduce", "all", "--jobs", value])
    assert exc.value.code == 2
    assert "argument --jobs: expected a positive integer" in capsys.readouterr().err
