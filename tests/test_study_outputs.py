"""Issue 27 item 4: nothing is overwritten. ``evotol run`` refuses to write over another study's
files (two study files with the same ``name`` and the same ``--out``), before any computation,
and says so; the same study file may run again; ``--force`` overwrites on purpose."""
from __future__ import annotations

import json

from evotol.cli import main
from tests.fast_study import fast_study


def _run(argv, capsys):
    try:
        code = main(argv)
    except SystemExit as exc:
        code = exc.code
    return code, capsys.readouterr().err


def test_second_study_with_the_same_name_refuses_and_loses_nothing(tmp_path, capsys):
    out = tmp_path / "out"
    first, second = fast_study(tmp_path / "a"), fast_study(tmp_path / "b", ("position = 5e-5 ", "position = 4e-5 "))
    assert _run(["run", str(first), "--out", str(out)], capsys)[0] == 0
    before = {p.name: p.read_bytes() for p in out.iterdir()}
    code, err = _run(["run", str(second), "--out", str(out)], capsys)
    assert code == 2 and "Traceback" not in err
    line = err.strip().splitlines()[-1]
    for name in (f"--out = '{out}'", "ucr3_example.json and ucr3_example.html", f"by the study file {first.resolve()}",
                 "--force", "name = 'ucr3_example'"):
        assert name in line, (name, line)
    assert {p.name: p.read_bytes() for p in out.iterdir()} == before          # the first study's files are intact


def test_the_same_study_file_runs_again_into_its_folder(tmp_path, capsys):
    f = fast_study(tmp_path)
    assert _run(["run", str(f), "--out", str(tmp_path)], capsys)[0] == 0
    f.write_text(f.read_text().replace("position = 5e-5 ", "position = 4e-5 "))     # edited, still the same study
    assert _run(["run", str(f), "--out", str(tmp_path)], capsys)[0] == 0
    summary = json.loads((tmp_path / "ucr3_example.json").read_text())
    assert summary["study_file"] == str(f.resolve()) and "4e-05" in summary["problem"]


def test_force_overwrites_on_purpose(tmp_path, capsys):
    out = tmp_path / "out"
    first, second = fast_study(tmp_path / "a"), fast_study(tmp_path / "b")
    assert _run(["run", str(first), "--out", str(out)], capsys)[0] == 0
    assert _run(["run", str(second), "--out", str(out), "--force"], capsys)[0] == 0
    assert json.loads((out / "ucr3_example.json").read_text())["study_file"] == str(second.resolve())


def test_files_without_a_recorded_study_file_are_not_overwritten(tmp_path, capsys):
    """A seed study's JSON (or an earlier evotol's) records no study file: refused, said so."""
    (tmp_path / "ucr3_example.json").write_text(json.dumps({"name": "ucr3_example"}))
    code, err = _run(["run", str(fast_study(tmp_path / "s")), "--out", str(tmp_path)], capsys)
    assert code == 2 and "ucr3_example.json there were written by another study (no study file recorded)" in err
    (tmp_path / "ucr3_example.json").unlink()
    (tmp_path / "ucr3_example.html").write_text("<html></html>")                       # only a report
    code, err = _run(["run", str(fast_study(tmp_path / "s")), "--out", str(tmp_path)], capsys)
    assert code == 2 and "ucr3_example.html there were written" in err


def test_a_process_study_records_its_file_too(tmp_path, capsys):
    """Process-selection study files (evotol/studyfile/processes.py) run again into their folder;
    a copy under another path with the same name is refused."""
    from pathlib import Path

    text = (Path(__file__).resolve().parents[1] / "reports" / "studies" / "clutch_processes.toml").read_text()
    start = text.index("[methods]")
    end = text.index("\n[", start + 1) if "\n[" in text[start + 1:] else len(text)
    text = text[:start] + "[methods]\noptimum = {}\n" + text[end:]
    (tmp_path / "a").mkdir()
    (tmp_path / "b").mkdir()
    a, b = tmp_path / "a" / "p.toml", tmp_path / "b" / "p.toml"
    a.write_text(text)
    b.write_text(text)
    for f, code in ((a, 0), (a, 0), (b, 2)):
        got, err = _run(["run", str(f), "--out", str(tmp_path)], capsys)
        assert got == code, err
    assert "clutch_processes.json and clutch_processes.html there were written by the study file" in err
    assert json.loads((tmp_path / "clutch_processes.json").read_text())["study_file"] == str(a.resolve())


def test_source_table_keeps_the_nominals_of_a_robot_with_clearances():
    """With a ``[clearances]`` table the problem keeps the description as ``problem.model`` and
    the classes beside it (``problem.clearances``); its ``error_model`` is the one
    ``WithClearances`` around the description (issue 32: built once, by the problem). The source
    table gives the description's nominal lengths (m) of L0..L5, and none for the clearance classes."""
    import tomllib
    from pathlib import Path

    from evotol.measures.clearances import ClearanceSources, WithClearances
    from evotol.summaries.user_study import source_nominals, source_table
    from evotol.studyfile import load_problem
    from evotol.robots.mechanism.model.error_model import MechanismModel

    path = Path(__file__).resolve().parents[1] / "reports" / "studies" / "fivebar_clearances.toml"
    pr = load_problem(tomllib.loads(path.read_text()), base_dir=path.parent)
    assert isinstance(pr.model, MechanismModel) and isinstance(pr.clearances, ClearanceSources)
    assert isinstance(pr.error_model, WithClearances) and pr.error_model.base is pr.model
    assert pr.error_model.clearances is pr.clearances
    assert pr.names == (*pr.model.source_names, *pr.clearances.names)
    assert source_nominals(pr.model) == {"L0": 0.1, "L1": 0.05, "L2": 0.05, "L3": 0.05, "L4": 0.05, "L5": 0.0}
    rows = {r["name"]: r for r in source_table(pr)}
    assert [rows[f"L{i}"]["nominal"] for i in range(6)] == [0.1, 0.05, 0.05, 0.05, 0.05, 0.0]
    classes = [c.name for c in pr.clearances.sources]
    assert classes and all("nominal" not in rows[c] for c in classes)
