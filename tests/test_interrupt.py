"""Issue 15: Ctrl-C during ``evotol run`` is said on the terminal and in the report, exits 130
(unless ``--keep-going``), and keeps everything already computed.

Each test starts a real ``python -m evotol.cli run`` subprocess on a small 3-UCR study whose GA
would run for 100 000 generations, waits until the GA has started, sends SIGINT, and checks the
exit code, the message, the JSON and the HTML. "Nothing computed is lost" is checked against an
independent recomputation of the method that finished before the interruption.
"""
from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time
import tomllib
from pathlib import Path

import pytest

from evotol.allocators import allocate_sensitivity
from evotol.studyfile import load_problem

ROOT = Path(__file__).resolve().parents[1]
EXAMPLE = ROOT / "reports" / "studies" / "ucr3_example.toml"


def _study(tmp_path: Path) -> Path:
    text = EXAMPLE.read_text().replace("grid = [5, 5, 3]", "grid = [3, 3, 2]")
    text = text[:text.index("[methods]")] + (
        "[methods]\nsensitivity = {}\nga = { pop_size = 20, n_gen = 100000 }\noptimum = {}\n\n"
        "[verify]\nn_samples = 50\n")
    f = tmp_path / "long.toml"
    f.write_text(text)
    return f


def _interrupt_run(tmp_path: Path, *extra: str) -> tuple[int, str, dict, str]:
    f = _study(tmp_path)
    env = dict(os.environ, OMP_NUM_THREADS="1", OPENBLAS_NUM_THREADS="1", PYTHONUNBUFFERED="1")
    proc = subprocess.Popen([sys.executable, "-m", "evotol.cli", "run", str(f), "--out", str(tmp_path), *extra],
                            cwd=ROOT, env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        seen = []
        for line in proc.stderr:                  # wait until the GA has started (progress: standard error)
            seen.append(line)
            if line.startswith("[evotol] ga"):
                break
        else:
            pytest.fail(f"the GA never started: {''.join(seen)} {proc.stdout.read()}")
        time.sleep(1.0)                           # let it run some generations
        proc.send_signal(signal.SIGINT)
        out, err = proc.communicate(timeout=120)
    finally:
        if proc.poll() is None:
            proc.kill()
    summary = json.loads((tmp_path / "ucr3_example.json").read_text())
    html = (tmp_path / "ucr3_example.html").read_text()
    return proc.returncode, err, summary, html


def _sensitivity_recomputed(tmp_path: Path) -> dict:
    spec = tomllib.loads(_study(tmp_path).read_text())
    return allocate_sensitivity(load_problem(spec)).tolerances


def test_ctrl_c_exits_130_says_so_and_keeps_what_was_computed(tmp_path):
    code, err, summary, html = _interrupt_run(tmp_path)
    assert code == 130, err
    assert "Traceback" not in err
    assert "interrupted (Ctrl-C): stopped ga" in err and "skipped optimum" in err
    assert summary["interrupted"] is True
    assert summary["interruption"]["stopped"] == ["ga"]
    assert "optimum" in summary["interruption"]["skipped"]
    assert "optimum" not in summary["results"]
    # the GA stopped early with its best design so far, and says so
    ga = summary["results"]["ga"]
    assert ga["interrupted"] is True and ga["cost"] > 0
    # the method finished before Ctrl-C is in the JSON, equal to an independent recomputation
    assert summary["results"]["sensitivity"]["tolerances"] == pytest.approx(_sensitivity_recomputed(tmp_path), rel=1e-12)
    assert "Interrupted (Ctrl-C): stopped ga" in html


def test_keep_going_runs_the_remaining_methods_and_exits_0(tmp_path):
    code, err, summary, html = _interrupt_run(tmp_path, "--keep-going")
    assert code == 0, err
    assert "interrupted (Ctrl-C): stopped ga" in err
    assert summary["interruption"] == {"stopped": ["ga"], "skipped": [], "keep_going": True}
    assert summary["results"]["optimum"]["feasible"] is True
    assert set(summary["monte_carlo"]) == {"sensitivity", "ga", "optimum"}
    assert summary["results"]["ga"]["interrupted"] is True


def test_a_stack_study_keeps_what_ran_before_a_ctrl_c(tmp_path, monkeypatch):
    """The stack path runs its allocation methods in the one step loop of every study (issue 39): a
    Ctrl-C in the first method stops it, skips the second, and the study is still written, marked
    interrupted, with the stack analysis (computed before the methods) intact."""
    import evotol.studyfile.stack_table as st
    from evotol.studyfile import run_study_file

    calls = []

    def interrupted(problem, **kw):
        calls.append("optimum")
        raise KeyboardInterrupt

    monkeypatch.setitem(st.STACK_METHODS, "optimum", interrupted)
    monkeypatch.setitem(st.STACK_METHODS, "sensitivity", lambda problem, **kw: calls.append("sensitivity"))
    study = tmp_path / "motor.toml"
    study.write_text((ROOT / "reports" / "studies" / "motor_stack.toml").read_text(encoding="utf-8"), encoding="utf-8")
    summary = run_study_file(study, out=tmp_path)
    assert calls == ["optimum"]                               # the second method never started
    assert summary["interrupted"] is True
    assert summary["interruption"] == {"stopped": ["optimum"], "skipped": ["sensitivity"], "keep_going": False}
    written = json.loads(Path(summary["json"]).read_text(encoding="utf-8"))
    assert written["interrupted"] is True and "allocation" not in written
    assert set(written) == set(summary) - {"html", "json"}      # the analysis computed before the methods is kept
