"""The command line as users of other tools expect it (issue 40): ``--version``; results on stdout,
progress and messages on stderr; ``-q``/``-v``; help in plain words; every exit code documented; a
library that logs through :mod:`logging` and never prints."""
from __future__ import annotations

import ast
import os
import re
import subprocess
import sys
from pathlib import Path

import pytest

import evotol
from evotol.cli import build_parser, main
from tests.fast_study import fast_study

ROOT = Path(__file__).resolve().parents[1]


def _cli(*args, cwd=ROOT):
    env = {**os.environ, "PYTHONPATH": str(ROOT), "OMP_NUM_THREADS": "1", "OPENBLAS_NUM_THREADS": "1"}
    return subprocess.run([sys.executable, "-m", "evotol.cli", *map(str, args)], cwd=cwd, env=env,
                          capture_output=True, text=True, timeout=300)


def test_version_is_the_package_version():
    done = _cli("--version")
    assert done.returncode == 0 and done.stdout == f"evotol {evotol.__version__}\n" and done.stderr == ""


def test_results_on_stdout_progress_on_stderr(tmp_path):
    """``2>/dev/null`` leaves the results alone: the per-method table on stdout, every progress and
    file message on stderr; ``-q`` removes the progress and keeps the results."""
    study = fast_study(tmp_path)
    done = _cli("run", study, "--out", tmp_path)
    assert done.returncode == 0, done.stderr
    out, err = done.stdout.splitlines(), done.stderr.splitlines()
    assert any(line.startswith("[evotol] results") for line in out)
    assert any(line.lstrip().startswith("sensitivity") for line in out)          # the method's row
    assert "[evotol] sensitivity ..." in err and any(line.startswith("[evotol] wrote ") for line in err)
    assert not any(line.startswith("[evotol] wrote ") or line == "[evotol] sensitivity ..." for line in out)
    quiet = _cli("run", study, "--out", tmp_path, "--force", "-q")
    assert quiet.returncode == 0 and quiet.stdout == done.stdout       # same results (same seed)
    assert not [line for line in quiet.stderr.splitlines() if line.startswith("[evotol]")], quiet.stderr


def test_quiet_and_verbose_set_the_log_level(capsys):
    import logging

    for argv, level in ((["list"], logging.INFO), (["-q", "list"], logging.WARNING), (["list", "-q"], logging.WARNING),
                        (["-v", "list"], logging.DEBUG), (["list", "-v"], logging.DEBUG)):
        assert main(argv) == 0
        assert logging.getLogger("evotol").level == level, argv
    capsys.readouterr()
    main(["list"])                                    # leave the default for the other tests


def _helps(parser):
    yield parser.description or ""
    for action in parser._actions:
        yield action.help or ""
        for sub in getattr(action, "choices", None) or {}:
            if hasattr(action.choices[sub], "_actions"):
                yield from _helps(action.choices[sub])


def test_help_texts_are_plain_words():
    """No reStructuredText markup, issue numbers or source paths in any help text (they come from
    module docstrings written for developers)."""
    texts = list(_helps(build_parser()))
    assert len(texts) > 40
    bad = [t for t in texts if re.search(r"``|:[a-z]+:`|\bissues? \d+|\w+/\w+\.py\b", t)]
    assert not bad, bad


def test_every_exit_code_is_documented():
    """The exit codes in docs/errors.md's table are the ones the command returns: the literal
    ``return N`` / ``N if ... else M`` values of evotol/cli, argparse's 2, and Ctrl-C's 130."""
    table = (ROOT / "docs" / "errors.md").read_text(encoding="utf-8").split("## Exit codes", 1)[1].split("\n## ", 1)[0]
    documented = {int(m) for m in re.findall(r"^\| (\d+) \|", table, re.M)}
    returned = set()
    for path in (ROOT / "evotol" / "cli").rglob("*.py"):
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            if isinstance(node, ast.Return) and node.value is not None:
                for sub in ast.walk(node.value):
                    if isinstance(sub, ast.Constant) and type(sub.value) is int:
                        returned.add(sub.value)
    assert returned <= documented, returned - documented
    assert documented == {0, 1, 2, 3, 130}      # 3: a write the system refused (docs/reliability.md)
    row1 = next(line for line in table.splitlines() if line.startswith("| 1 |"))
    assert "check-mechanism" in row1 and "check-calibration" in row1 and "reproduce all" in row1


def _prints(path: Path) -> list[int]:
    tree = ast.parse(path.read_text(encoding="utf-8"))
    return [n.lineno for n in ast.walk(tree)
            if isinstance(n, ast.Call) and isinstance(n.func, ast.Name) and n.func.id == "print"]


def test_the_library_never_prints():
    """Outside the command line (evotol/cli) no module calls print(); what a library module has to
    say goes through logging (issue 40). Docstring examples are not calls, so they do not count.
    The Heartbeat and the plausibility display print only to a stream their caller passes."""
    allowed = {ROOT / "evotol" / "_runtime" / "progress.py", ROOT / "evotol" / "core" / "plausibility.py"}
    found = {}
    for package in ("evotol", "robots", "cost_models"):
        for path in (ROOT / package).rglob("*.py"):
            if (ROOT / "evotol" / "cli") in path.parents or path in allowed:
                continue
            if lines := _prints(path):
                found[str(path.relative_to(ROOT))] = lines
    assert not found, found
    for path in allowed:                      # each print there writes to an explicit stream argument
        tree = ast.parse(path.read_text(encoding="utf-8"))
        calls = [n for n in ast.walk(tree) if isinstance(n, ast.Call) and getattr(n.func, "id", "") == "print"]
        assert calls and all(any(k.arg == "file" for k in c.keywords) for c in calls), path


def test_library_messages_go_through_logging(tmp_path, caplog, capsys):
    """A study run from Python says what it runs through ``logging`` (logger evotol.studyfile.steps, the one step loop of every study),
    and prints nothing."""
    import logging

    from evotol.studyfile import run_study_file

    with caplog.at_level(logging.INFO, logger="evotol"):
        run_study_file(fast_study(tmp_path), out=tmp_path)
    assert ("evotol.studyfile.steps", logging.INFO, "sensitivity ...") in caplog.record_tuples   # the one step loop
    assert capsys.readouterr().out == ""
