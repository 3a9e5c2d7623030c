"""One pipeline for every kind of study file (issue 39 item 2, evotol/studyfile/kinds.py): a Ctrl-C
is handled the same way in a process selection, a stack allocation and an analysis of given
tolerances as in a robot study -- the running step stops, the rest are skipped, what ran is written
with ``interrupted`` and the steps named -- and each kind is found by the one registry."""
from __future__ import annotations

import json
import tomllib
from pathlib import Path

import pytest

from evotol.allocators.process import allocate_process_baselines
from evotol.studyfile import load_process_problem, processes, run_study_file
from evotol.studyfile import run as studyfile_run
from evotol.studyfile.stack_table import STACK_METHODS

STUDIES = Path(__file__).resolve().parents[1] / "reports" / "studies"


def _ctrl_c(*args, **kwargs):
    raise KeyboardInterrupt       # what the run's Ctrl-C handler raises inside the running step


def test_each_file_is_run_by_its_kind():
    kinds = [k.name for k in studyfile_run.KINDS]
    assert kinds == ["processes", "stack", "robot"]
    of = lambda spec: next(k.name for k in studyfile_run.KINDS if k.present(spec))   # noqa: E731
    assert [of({"processes": {}}), of({"stack": {}}), of({"robot": {}})] == kinds


def test_process_study_stopped_by_ctrl_c_writes_what_ran(tmp_path, monkeypatch):
    """[methods] baselines, optimum, ga with the optimum interrupted: the baselines are written and equal
    an independent call, the optimum is named as stopped and the GA as skipped; the page says so."""
    spec = tomllib.loads((STUDIES / "clutch_processes.toml").read_text())
    spec["methods"] = {"baselines": {}, "optimum": {}, "ga": {"pop_size": 10, "n_gen": 2}}
    f = tmp_path / "p.toml"
    f.write_text((STUDIES / "clutch_processes.toml").read_text())
    monkeypatch.setitem(processes.METHODS, "optimum", _ctrl_c)
    monkeypatch.setattr(studyfile_run, "read_study_file", lambda path: spec)
    summary = run_study_file(f, out=tmp_path / "out")
    data = json.loads(Path(summary["json"]).read_text())
    assert data["interrupted"] is True
    assert data["interruption"] == {"stopped": ["optimum"], "skipped": ["ga"], "keep_going": False}
    own = allocate_process_baselines(load_process_problem(spec, base_dir=STUDIES))
    assert sorted(data["results"]) == sorted(f"baseline {k}" for k in own)
    for k, r in own.items():
        assert data["results"][f"baseline {k}"]["cost"] == pytest.approx(r.cost, rel=1e-12)
    assert "Interrupted (Ctrl-C): stopped optimum; not run: ga" in Path(summary["html"]).read_text()


def test_stack_allocation_stopped_by_ctrl_c_keeps_the_analysis(tmp_path, monkeypatch):
    """motor_stack.toml's allocation (optimum, then sensitivity) with the optimum interrupted: the
    sensitivity step is skipped, and the analysis written equals an uninterrupted run's, key by key."""
    f = tmp_path / "s.toml"
    f.write_text((STUDIES / "motor_stack.toml").read_text())
    full = json.loads(Path(run_study_file(f, out=tmp_path / "full")["json"]).read_text())
    monkeypatch.setitem(STACK_METHODS, "optimum", _ctrl_c)
    summary = run_study_file(f, out=tmp_path / "out")
    data = json.loads(Path(summary["json"]).read_text())
    assert "Interrupted (Ctrl-C): stopped optimum; not run: sensitivity" in Path(summary["html"]).read_text()
    assert full["interrupted"] is False and data["interrupted"] is True
    assert data["interruption"] == {"stopped": ["optimum"], "skipped": ["sensitivity"], "keep_going": False}
    assert "allocation" in full and "allocation" not in data        # nothing allocated ran to its end
    kept = set(full) - {"allocation", "interrupted", "interruption", "seconds", "study_file"}
    assert kept and all(data[k] == full[k] for k in kept), [k for k in kept if data[k] != full[k]]


def test_analysis_stopped_by_ctrl_c_writes_nothing(tmp_path, monkeypatch):
    """An analysis of given tolerances is one step: stopped, there is nothing to write, and the Ctrl-C
    reaches the caller (the CLI exits 130)."""
    from evotol.studyfile import given_tolerances, load_problem
    spec = {"name": "given", "robot": {"model": "ucr3"}, "poses": {"grid": [2, 2, 2]},
            "requirement": {"position": 1e-3}, "bounds": {"lower": 1e-6, "upper": 1e-4},
            "cost": {"default": {"model": "exponential", "a0": 1.9, "a1": 0.5, "scale": 1e-5}}}
    spec["sources"] = {n: {"fixed": 1e-5} for n in load_problem(spec).names}
    monkeypatch.setattr(given_tolerances, "analyse", _ctrl_c)
    monkeypatch.setattr(studyfile_run, "read_study_file", lambda path: spec)
    f = tmp_path / "given.toml"
    f.write_text("")
    with pytest.raises(KeyboardInterrupt):
        run_study_file(f, out=tmp_path / "out")
    assert not list((tmp_path / "out").glob("given*"))
