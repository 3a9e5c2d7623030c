"""``evotol reproduce all --jobs N`` (issue 13): several studies at once, each its own process.

Checked: the JSON a study writes when it runs beside another equals, number by number, the JSON of
the same study run alone in this process (wall times excepted); Ctrl-C stops the running studies,
names them and the ones not started, and exits 130; bad ``--jobs`` is a one-line error.
"""
from __future__ import annotations

import importlib.util
import io
import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path
from types import SimpleNamespace

import pytest

from evotol.cli import parallel_studies as jobs_module
from evotol import studies
from evotol.cli import main
from evotol.cli.parallel_studies import longest_first, reproduce_concurrently
from evotol._runtime.progress import EXPECTED_SECONDS

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


# Slow (~10 s alone) because its check needs both runs: two studies side by side, then each alone, number by number.
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


# Slow (~5-9 s) because its check is real: `evotol reproduce all --jobs 2` started and stopped by SIGINT.
def test_ctrl_c_stops_the_running_studies_and_names_what_was_not_run(tmp_path):
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    proc = subprocess.Popen([sys.executable, "-m", "evotol.cli", "reproduce", "all", "--quick", "--jobs", "2",
                             "--out", str(tmp_path)], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=env)
    started, t0 = 0, time.time()
    while started < 2 and time.time() - t0 < 60:
        line = proc.stderr.readline()            # progress on standard error (issue 40)
        started += line.startswith("[evotol] started")
    assert started == 2
    time.sleep(1.0)
    proc.send_signal(signal.SIGINT)
    out, err = proc.communicate(timeout=120)
    assert proc.returncode == 130, err
    assert "interrupted (Ctrl-C) during " in err and "not run: " in err
    assert "not run: none" not in err            # 11 studies, two were running
    assert "[evotol] run times" in out


@pytest.mark.parametrize("writes", [False, True])
def test_ctrl_c_reads_back_only_a_json_written_by_this_run(tmp_path, monkeypatch, writes):
    """After Ctrl-C, a stopped study counts as ``written`` (and its JSON is read back) only when its
    ``NAME.json`` was written after it started: a stale ``NAME.json`` of an earlier run, one hour
    old, is neither listed in ``written`` nor returned in ``summaries`` (the start time and the
    file's mtime are on the same wall clock)."""
    out = tmp_path / "out"
    out.mkdir()
    stale = out / "x.json"
    stale.write_text(json.dumps({"run": "earlier"}))
    os.utime(stale, (time.time() - 3600,) * 2)
    ready = tmp_path / "ready"
    child = ("import json, pathlib, time\n"
             + (f"pathlib.Path({str(stale)!r}).write_text(json.dumps({{'run': 'this'}}))\n" if writes else "")
             + f"pathlib.Path({str(ready)!r}).touch()\ntime.sleep(60)\n")
    monkeypatch.setattr(jobs_module, "_command", lambda name, out, **kw: [sys.executable, "-c", child])

    def ctrl_c(_seconds):          # Ctrl-C once the study process is under way
        t0 = time.time()
        while not ready.exists() and time.time() - t0 < 30:
            time.sleep(0.05)
        raise KeyboardInterrupt

    monkeypatch.setattr(jobs_module, "time", SimpleNamespace(perf_counter=time.perf_counter, time=time.time, sleep=ctrl_c))
    res = reproduce_concurrently(["x"], out, jobs=1, stream=io.StringIO())
    assert res.stopped == ["x"] and res.not_run == []
    if writes:
        assert res.written == ["x"] and res.summaries == {"x": {"run": "this"}}
    else:
        assert res.written == [] and res.summaries == {}


@pytest.mark.parametrize("value", ["0", "-1", "two"])
def test_bad_jobs_is_a_one_line_error(value, capsys):
    with pytest.raises(SystemExit) as exc:
        main(["reproduce", "all", "--jobs", value])
    assert exc.value.code == 2
    assert "argument --jobs: expected a positive integer" in capsys.readouterr().err
