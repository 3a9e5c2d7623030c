"""Issue 15: Ctrl-C during ``evotol reproduce`` names the study it stopped, what was written and
what was not run, and exits 130 -- also when a GA inside a study swallowed the Ctrl-C (it returns
its best design so far, so the study itself would finish as if nothing happened)."""
from __future__ import annotations

import os
import signal
from pathlib import Path

import pytest

from evotol import studies
from evotol.cli import main
from evotol.studies import Study, StudyResult


class _Page:
    def write(self, path):
        Path(path).write_text("<html></html>", encoding="utf-8")
        return Path(path)


def _study(name: str, compute) -> Study:
    return Study(name=name, title=name, compute=compute, render=lambda result: _Page(), config={"seed": 0})


def _quiet(cfg):
    return StudyResult({"value_m": 1.0})


def _raises(cfg):
    raise KeyboardInterrupt


def _swallows(cfg):
    """What allocate_ga does with Ctrl-C: catch it and return the best design so far."""
    try:
        os.kill(os.getpid(), signal.SIGINT)
    except KeyboardInterrupt:
        pass
    return StudyResult({"value_m": 2.0})


@pytest.mark.parametrize("second, written", [(_raises, False), (_swallows, True)])
def test_reproduce_all_stops_at_ctrl_c_and_says_where(monkeypatch, tmp_path, capsys, second, written):
    fake = {"a-first": _study("a-first", _quiet), "b-second": _study("b-second", second),
            "c-third": _study("c-third", _quiet)}
    monkeypatch.setattr(studies, "available", lambda: fake)
    assert main(["reproduce", "all", "--out", str(tmp_path), "--jobs", "1"]) == 130
    err = capsys.readouterr().err
    assert "interrupted (Ctrl-C) during b-second" in err
    assert "completed and written: a-first" in err and "not run: c-third" in err
    assert (tmp_path / "a-first.json").exists() and not (tmp_path / "c-third.json").exists()
    assert (tmp_path / "b-second.json").exists() == written
    assert ("stopped early" in err) == written
